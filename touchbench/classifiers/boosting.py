"""SAMME boosting with Weka's AdaBoostM1 control flow.

Gaus et al. 2015 (sections 3.3.2 and 4) boost random forests with
"Stage-wise Additive Modelling" (SAMME: Zhu, Zou, Rosset and Hastie, 2009,
"Multi-class AdaBoost"), 500 iterations, in Weka. SAMME differs from
AdaBoost.M1 in the weight of a weak learner,
``alpha = log((1 - err) / err) + log(K - 1)``, which stays positive while the
weighted error ``err`` is below ``1 - 1/K`` rather than below 1/2.

The loop follows Weka's ``AdaBoostM1.buildClassifierWithWeights``
(reweighting, the weak learner receives the instance weights):

1. fit the weak learner on the weighted training set;
2. measure its weighted error ``err`` (on the training set itself, as Weka
   does, or out of bag, see ``weak_error``);
3. if ``err == 0`` or ``err >= 1 - 1/K`` stop; the learner is discarded
   unless it is the first, in which case it is the whole model (Weka: "If
   we're the first we have to use it");
4. otherwise keep it with weight ``alpha``, multiply the weights of the
   misclassified instances by ``exp(alpha)`` and renormalise.

Prediction with a single kept learner returns that learner's own
``predict_proba`` (Weka's ``distributionForInstance`` does the same); with
several, the class scores ``sum_m alpha_m [h_m(x) = k]`` are turned into
probabilities with a softmax (Weka's ``Utils.logs2probs``).

What happens with random-forest weak learners (the finding the registry
entry ``gaus-boost`` documents): a forest of fully grown trees classifies
its own training set perfectly, so ``err == 0`` at the first iteration and
the loop stops there. Measured on real HAART (challenge training split, 578
captures): with Gaus et al.'s five feature sets combined (SD, BMH, MSD,
SMMHH, LBPTOP; 3196 columns) and with 192 simple per-cell statistics, a
1000-tree forest has training accuracy 1.0 and ``gaus-boost`` keeps one
forest (test accuracy 62.8% against 64.4% for ``gaus-rf``: the same model
up to the seed). "Boosting" with 500
iterations is then exactly one random forest: Weka's AdaBoostM1 and
scikit-learn's ``AdaBoostClassifier`` both behave this way. That is
consistent with Gaus et al.'s near-identical RF and boosting accuracies
(Tables 5 and 8). ``weak_error="oob"`` is an opt-in alternative that
measures each forest's error out of bag, so the weights are finite and the
ensemble really boosts (on the same HAART data, 20 iterations of 200-tree
forests: weighted out-of-bag errors 0.27, then about 0.5 to 0.7, below
SAMME's limit 1 - 1/7; test accuracy 67.2%); it is not what the paper ran.
"""

from __future__ import annotations

from numbers import Integral, Real
import math
import warnings

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.utils import check_random_state
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval

from ._util import MAX_SEED, WekaRandomForestClassifier, check_sample_weight


class SAMMEClassifier(ClassifierMixin, BaseEstimator):
    """SAMME boosting of ``estimator`` with Weka AdaBoostM1's stopping rules.

    Parameters
    ----------
    estimator : classifier supporting ``sample_weight``; default a 100-tree
        :class:`WekaRandomForestClassifier`.
    n_estimators : maximum number of boosting iterations.
    weak_error : ``"train"`` (Weka, the paper) measures each learner's
        weighted error on the training set it was fitted on; ``"oob"`` uses
        the out-of-bag predictions of a bagged learner (needs ``oob_score``;
        it is switched on) so that a perfectly fitting forest still gets a
        finite weight.
    learning_rate : multiplies ``alpha`` (1.0 in SAMME and Weka).
    random_state : seeds each weak learner in turn.
    n_jobs : passed to the weak learner when it has ``n_jobs``.

    Attributes
    ----------
    estimators_, estimator_weights_, estimator_errors_ : the kept learners,
        their ``alpha`` and weighted error.
    n_iterations_ : number of kept learners.
    stop_reason_ : ``"n_estimators"``, ``"perfect_fit"`` (``err == 0``) or
        ``"too_weak"`` (``err >= 1 - 1/K``).
    """

    #: checked when a protocol is read: the rounds' weight is scaled by a positive learning rate
    _parameter_constraints = {"learning_rate": [Interval(Real, 0, None, closed="neither")]}

    def __init__(self, estimator=None, n_estimators=50, weak_error="train", learning_rate=1.0,
                 random_state=None, n_jobs=1):
        self.estimator = estimator
        self.n_estimators = n_estimators
        self.weak_error = weak_error
        self.learning_rate = learning_rate
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _weak_learner(self):
        if self.estimator is None:
            return WekaRandomForestClassifier(n_estimators=100, criterion="entropy", max_features="weka")
        return clone(self.estimator)

    def _validate(self):
        if self.weak_error not in ("train", "oob"):
            raise ValueError(f"weak_error must be 'train' or 'oob', got {self.weak_error!r}")
        self._validate_counts()

    def _validate_counts(self):
        if not (isinstance(self.n_estimators, (int, np.integer)) and self.n_estimators >= 1):
            raise ValueError(f"n_estimators must be a positive integer, got {self.n_estimators!r}")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be positive, got {self.learning_rate!r}")

    def fit(self, X, y, sample_weight=None):
        self._validate()
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        k = len(self.classes_)
        n = X.shape[0]
        rng = check_random_state(self.random_state)
        w = check_sample_weight(sample_weight, n).copy()
        w /= w.sum()

        self.estimators_, weights, errors = [], [], []
        self.stop_reason_ = "n_estimators"
        for it in range(self.n_estimators):
            est, miss, err = self._fit_weak(X, yi, w, rng)
            stop = self._stop_reason(err, k)
            if stop is not None:
                self.stop_reason_ = stop
                if it == 0:  # Weka: "If we're the first we have to use it"
                    self.estimators_.append(est)
                    weights.append(1.0)
                    errors.append(err)
                break
            alpha = self.learning_rate * (math.log((1.0 - err) / err) + math.log(k - 1.0))
            self.estimators_.append(est)
            weights.append(alpha)
            errors.append(err)
            w = w * np.exp(alpha * miss)
            w /= w.sum()
        self.estimator_weights_ = np.asarray(weights)
        self.estimator_errors_ = np.asarray(errors)
        self.n_iterations_ = len(self.estimators_)
        return self

    @staticmethod
    def _stop_reason(err: float, k: int) -> str | None:
        """Weka's stopping rule in SAMME's form: a perfect fit, or an error at or above ``1 - 1/K``."""
        if err <= 0.0:
            return "perfect_fit"
        if err >= 1.0 - 1.0 / k:
            return "too_weak"
        return None

    def _seeded(self, est, rng):
        """``est`` with the next seed of ``rng`` and ``n_jobs``, where it takes them."""
        params = est.get_params(deep=False)
        upd = {}
        if "random_state" in params:
            upd["random_state"] = int(rng.randint(MAX_SEED))
        if "n_jobs" in params:
            upd["n_jobs"] = self.n_jobs
        return est.set_params(**upd)

    def _fit_weak(self, X, yi, w, rng):
        """One weak learner fitted on the weighted training set: the learner, which rows it
        misclassifies, and its weighted error (on the training set, or out of bag)."""
        est = self._seeded(self._weak_learner(), rng)
        if self.weak_error == "oob":
            if "oob_score" not in est.get_params(deep=False):
                raise ValueError("weak_error='oob' needs a bagged weak learner with oob_score")
            est.set_params(oob_score=True)
        with warnings.catch_warnings():  # "Some inputs do not have OOB scores": handled below
            warnings.filterwarnings("ignore", message="Some inputs do not have OOB scores")
            est.fit(X, yi, sample_weight=w * X.shape[0])
        miss = self._weak_predictions(est, X) != yi
        return est, miss, float(np.sum(w[miss]))

    def _weak_predictions(self, est, X):
        """Each row's prediction by the learner: on the training set, or out of
        bag (rows in every bag, likely once their weight is large, fall back
        to the in-bag prediction)."""
        if self.weak_error == "train":
            return est.predict(X)
        oob = est.oob_decision_function_
        pred = est.predict(X)
        seen = np.isfinite(oob).all(axis=1) & (oob.sum(axis=1) > 0)
        pred[seen] = est.classes_[np.argmax(oob[seen], axis=1)]
        return pred

    def _proba_int(self, X):
        """Probabilities over ``0..K-1`` (the labels the learners saw)."""
        k = len(self.classes_)
        if self.n_iterations_ == 1:
            p = np.zeros((X.shape[0], k))
            p[:, self.estimators_[0].classes_.astype(int)] = self.estimators_[0].predict_proba(X)
            return p
        scores = np.zeros((X.shape[0], k))
        for est, a in zip(self.estimators_, self.estimator_weights_):
            scores[np.arange(X.shape[0]), est.predict(X).astype(int)] += a
        scores -= scores.max(axis=1, keepdims=True)
        e = np.exp(scores)
        return e / e.sum(axis=1, keepdims=True)

    def predict_proba(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self._proba_int(X)

    def predict(self, X):
        p = self.predict_proba(X)
        return self.classes_[np.argmax(p, axis=1)]


class GausBoostingClassifier(SAMMEClassifier):
    """Gaus et al.'s boosting: SAMME over Weka-style random forests.

    Flat parameters for the weak learner (``n_trees``, ``max_features``,
    ``criterion``) so a protocol can set them without nested names. See the
    module docstring for what happens when a forest fits its training set
    perfectly (the default case: boosting stops after one forest).
    """

    #: n_trees: the trees of each round's forest, each one built and kept, so bounded as n_estimators
    _parameter_constraints = {**SAMMEClassifier._parameter_constraints,
                              "n_trees": [Interval(Integral, 1, 100_000, closed="both")]}

    def __init__(self, n_estimators=500, n_trees=1000, max_features="weka", criterion="entropy",
                 weak_error="train", learning_rate=1.0, random_state=None, n_jobs=1):
        self.n_estimators = n_estimators
        self.n_trees = n_trees
        self.max_features = max_features
        self.criterion = criterion
        self.weak_error = weak_error
        self.learning_rate = learning_rate
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _weak_learner(self):
        return WekaRandomForestClassifier(
            n_estimators=self.n_trees, max_features=self.max_features, criterion=self.criterion
        )


#: Weka AdaBoostM1's ``MAX_NUM_RESAMPLING_ITERATIONS``: draws of a resample before a zero error is accepted
MAX_REDRAWS = 10


class ResampledBoostingClassifier(GausBoostingClassifier):
    """SAMME boosting of forests, each fitted on a weighted resample and weighed by its out-of-bag error.

    Gaus et al. 2015 (Sec. 3.3.2: SAMME, "similar to Adaboost, but the
    difference is in how the error rate is computed"; Sec. 4: random forests
    as weak learners, 500 iterations, Weka) boost forests that fit their
    training set perfectly, so Weka's AdaBoostM1 loop stops after the first
    forest (module docstring). This variant keeps boosting; it is not what
    the paper ran. Its interpretations, one by one:

    1. the weak learner is fitted, unweighted, on a resample of the
       training set: ``n`` rows drawn with replacement, with probabilities
       the current boosting weights (Weka AdaBoostM1's resampling option
       ``-Q``, ``Instances.resampleWithWeights``);
    2. its weighted error is measured on the rows the resample left out
       (out of bag): ``err = sum(w[oob & miss]) / sum(w[oob])``. Weka's
       ``-Q`` measures it on the whole training set, which a forest fits
       perfectly; this is the one departure from Weka;
    3. a zero error, or a resample leaving out no row of positive weight, is
       drawn again, at most ``MAX_REDRAWS`` (10) times in all, as Weka's
       ``-Q`` does for a zero error; then Weka's stopping rule applies (stop
       at ``err == 0``, ``stop_reason_`` ``"perfect_fit"``, or with no row out
       of bag, ``"no_out_of_bag"``; the first learner is kept, with weight 1);
    4. SAMME's weight ``alpha = log((1 - err) / err) + log(K - 1)`` and its
       limit ``err >= 1 - 1/K`` (stop, ``"too_weak"``), as ``gaus-boost``;
    5. the reweighting multiplies by ``exp(alpha)`` the weight of every
       training row the learner misclassifies, in bag or out (Weka's
       ``setWeights`` classifies every training row); a forest misclassifies
       few of its in-bag rows, so mostly the out-of-bag misses gain weight.

    Parameters are ``gaus-boost``'s but ``weak_error`` (always out of bag,
    as above).
    """

    def __init__(self, n_estimators=500, n_trees=1000, max_features="weka", criterion="entropy",
                 learning_rate=1.0, random_state=None, n_jobs=1):
        self.n_estimators = n_estimators
        self.n_trees = n_trees
        self.max_features = max_features
        self.criterion = criterion
        self.learning_rate = learning_rate
        self.random_state = random_state
        self.n_jobs = n_jobs

    def _validate(self):
        self._validate_counts()

    @staticmethod
    def _stop_reason(err: float, k: int) -> str | None:
        if math.isnan(err):
            return "no_out_of_bag"
        return SAMMEClassifier._stop_reason(err, k)

    def _fit_weak(self, X, yi, w, rng):
        """The learner fitted on a resample drawn by ``w`` (redrawn while its out-of-bag error is zero
        or unmeasurable, at most ``MAX_REDRAWS`` draws), its misses on every row, its out-of-bag error
        (NaN when no row of positive weight was out of bag)."""
        n = X.shape[0]
        for _ in range(MAX_REDRAWS):
            bag = rng.choice(n, size=n, replace=True, p=w)
            out = np.ones(n, dtype=bool)
            out[bag] = False
            est = self._seeded(self._weak_learner(), rng)
            est.fit(X[bag], yi[bag])
            miss = est.predict(X) != yi
            w_out = float(np.sum(w[out]))
            err = float(np.sum(w[out & miss]) / w_out) if w_out > 0.0 else math.nan
            if err > 0.0:
                break
        return est, miss, err
