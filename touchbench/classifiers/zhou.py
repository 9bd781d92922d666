"""Zhou et al. 2017, section 4.2: the seven classifiers of MATLAB's
Classification Learner app (R2017a) they compared.

The paper names only the presets ("Medium Tree (maximum 20 splits)",
"LDA", "SVM with linear kernel", "SVM with quadratic kernel", "KNN with
K = 10", "distance weighted KNN with K = 10", "Bagged Trees (random forest
bag, with decision tree learners)"); the settings below are those presets'
documented options, mapped to scikit-learn:

- **Medium Tree**: ``fitctree`` with Gini's diversity index, at most 20
  splits (= at most 21 leaves, ``max_leaf_nodes=21``), ``MinParentSize`` 10
  (``min_samples_split=10``), ``MinLeafSize`` 1, no surrogate splits. Not
  matched: MATLAB grows the tree layer by layer until 20 splits are made;
  scikit-learn grows best-first (largest impurity decrease first) under
  ``max_leaf_nodes``, so a different 20-split tree can result.
- **Linear Discriminant**: ``fitcdiscr`` ``'linear'`` (pooled full
  covariance, empirical priors) = ``LinearDiscriminantAnalysis``. Where
  the pooled covariance is singular MATLAB regularises it (its ``Gamma``
  raised to the least value that inverts it) and scikit-learn's SVD solver
  drops the null directions instead; on the tpm-like scene's features the
  covariance is not singular (condition number of the within-class
  correlation about 1e6 for the basic + wavelet J = 10 set), so the two
  fit the same model.
- **Linear SVM / Quadratic SVM**: ``fitcecoc`` with one-vs-one coding over
  binary ``fitcsvm`` learners (box constraint 1, ``Standardize`` on,
  ``KernelScale 'auto'``), kernel ``x'z`` or ``(1 + x'z)^2`` on inputs
  divided by the kernel scale, prediction by loss-weighted decoding with the
  hinge loss. Written out in :class:`MatlabSVMClassifier`: one libsvm
  ``SVC`` per pair of classes, each standardised on its own two classes and
  given its own automatic kernel scale. That scale follows MATLAB's
  heuristic (:func:`matlab_auto_kernel_scale`), which is not in MathWorks'
  documentation; we took it from the ``optimalKernelScale`` function of a
  MATLAB release that may not be R2017a, and it subsamples at random
  (seeded here, MATLAB's stream cannot be reproduced), so kernel scales
  match in distribution, not value.
- **Medium KNN / Weighted KNN**: ``fitcknn`` with 10 neighbours, Euclidean
  distance, ``Standardize`` on, equal weights or ``'squaredinverse'``
  weights (``1/d^2``: MATLAB's "Weighted KNN" preset; scikit-learn's
  ``weights="distance"`` would be ``1/d``). Ties go to the first class in
  sorted order, like MATLAB's ``'smallest'`` rule.
- **Bagged Trees**: ``fitcensemble`` ``'Bag'`` with 30 deep trees
  (``MaxNumSplits`` n - 1, ``MinLeafSize`` 1, Gini), each split choosing
  among a random sqrt(M) of the predictors (the random-forest variant the
  paper names), i.e. ``RandomForestClassifier(30, max_features="sqrt")``.

Standardisation, as Classification Learner does: only the SVM and KNN
presets standardise, each column by its mean and *sample* standard
deviation (:class:`SampleStandardScaler`), learned on the training fold.
Trees, LDA and bagged trees see the raw features (they are invariant to it,
LDA up to rounding).
"""

from __future__ import annotations

from numbers import Integral
import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.ensemble import RandomForestClassifier
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import Pipeline
from sklearn.svm import SVC
from sklearn.tree import DecisionTreeClassifier
from sklearn.utils import check_random_state
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval

from ._util import MAX_SEED, DelegatingClassifier, SampleStandardScaler, build
from .base import CLASSIFIERS, ParamError

SOURCE = "Zhou et al. 2017, section 4.2; MATLAB Classification Learner R2017a presets"


def squared_inverse_weights(dist: np.ndarray) -> np.ndarray:
    """MATLAB's ``'squaredinverse'`` neighbour weights ``1/d^2``. A query at
    distance zero from some neighbours gives those neighbours all the weight
    (scikit-learn's rule for ``weights="distance"``)."""
    dist = np.asarray(dist, dtype=np.float64)
    zero = dist == 0
    with np.errstate(divide="ignore"):
        w = 1.0 / dist**2
    rows = zero.any(axis=1)
    w[rows] = zero[rows].astype(np.float64)
    return w


def inverse_weights(dist: np.ndarray) -> np.ndarray:
    """MATLAB's ``'inverse'`` weights ``1/d`` (zero distances as above)."""
    dist = np.asarray(dist, dtype=np.float64)
    zero = dist == 0
    with np.errstate(divide="ignore"):
        w = 1.0 / dist
    rows = zero.any(axis=1)
    w[rows] = zero[rows].astype(np.float64)
    return w


_KNN_WEIGHTS = {"equal": "uniform", "inverse": inverse_weights, "squaredinverse": squared_inverse_weights}


def _scaler(standardize: bool):
    return SampleStandardScaler() if standardize else "passthrough"


def matlab_auto_kernel_scale(Xpos: np.ndarray, Xneg: np.ndarray, rng: np.random.Generator,
                             n_sub: int = 100) -> float:
    """The kernel scale MATLAB's ``fitcsvm`` picks for ``'KernelScale','auto'``
    on a two-class problem (``classreg.learning.svmutils.optimalKernelScale``):
    draw at most ``n_sub`` observations of each class without replacement;
    for each sampled positive, the distance to its nearest sampled negative
    (zero distances ignored); the median of those, times
    ``sqrt(n_pos_sampled / N_pos * n_neg_sampled / N_neg) ** (1 / P)``.
    Falls back to 1 when no finite distance exists (MATLAB warns and uses 1).
    MATLAB draws the subsample from its global stream; here ``rng`` does.
    """
    n_pos, n_neg, p = len(Xpos), len(Xneg), Xpos.shape[1]
    ip = rng.choice(n_pos, size=min(n_sub, n_pos), replace=False)
    ineg = rng.choice(n_neg, size=min(n_sub, n_neg), replace=False)
    a, b = Xpos[ip], Xneg[ineg]
    d2 = (a**2).sum(1)[:, None] + (b**2).sum(1)[None, :] - 2.0 * a @ b.T
    d = np.sqrt(np.maximum(d2, 0.0))
    d[d == 0] = np.inf
    scale = float(np.median(d.min(axis=1)))
    if not np.isfinite(scale):
        return 1.0
    return scale * np.sqrt(len(ip) / n_pos * len(ineg) / n_neg) ** (1.0 / p)


class MatlabSVMClassifier(ClassifierMixin, BaseEstimator):
    """Classification Learner's SVM presets: ``fitcecoc`` with one-vs-one
    coding over binary SVMs, each fitted (by libsvm) on its two classes with
    its own standardisation and kernel scale, predictions by loss-weighted
    decoding with the hinge loss (MATLAB's defaults for SVM learners).

    Parameters
    ----------
    kernel : ``"linear"`` (``x'z``) or ``"polynomial"`` (``(1 + x'z)^q``), on
        inputs divided by the kernel scale.
    polynomial_order : ``q`` (2 = "Quadratic SVM").
    box_constraint : ``C`` (1).
    kernel_scale : ``"auto"`` (the preset; :func:`matlab_auto_kernel_scale`,
        seeded by ``random_state``) or a positive number.
    standardize : each binary learner centres and scales its training
        columns (sample standard deviation), as ``'Standardize', true``.
    tol : libsvm's stopping tolerance (MATLAB's SMO uses 1e-3 too).

    ``decision_function`` returns minus the average hinge loss of each class
    (higher is better); there is no ``predict_proba`` (the preset fits no
    posterior).
    """

    #: checked when a protocol is read: box_constraint and tol are the binary SVCs' C and tol (their
    #: own constraints); polynomial_order a positive whole number, as MATLAB's PolynomialOrder
    _parameter_constraints = {"box_constraint": SVC._parameter_constraints["C"],
                              "tol": SVC._parameter_constraints["tol"],
                              "polynomial_order": [Interval(Integral, 1, None, closed="left")]}

    def __init__(self, kernel="linear", polynomial_order=2, box_constraint=1.0, kernel_scale="auto",
                 standardize=True, tol=1e-3, random_state=None):
        self.kernel = kernel
        self.polynomial_order = polynomial_order
        self.box_constraint = box_constraint
        self.kernel_scale = kernel_scale
        self.standardize = standardize
        self.tol = tol
        self.random_state = random_state

    def fit(self, X, y):
        if self.kernel not in ("linear", "polynomial"):
            raise ValueError(f"kernel must be 'linear' or 'polynomial', got {self.kernel!r}")
        if not (self.kernel_scale == "auto" or (not isinstance(self.kernel_scale, str) and self.kernel_scale > 0)):
            raise ValueError(f"kernel_scale must be 'auto' or positive, got {self.kernel_scale!r}")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        k = len(self.classes_)
        if k < 2:
            raise ValueError("MatlabSVMClassifier needs at least two classes; got 1 class")
        rng = np.random.default_rng(check_random_state(self.random_state).randint(MAX_SEED))
        linear = self.kernel == "linear"
        self.pairs_, self.learners_, self.kernel_scales_ = [], [], []
        for i in range(k):
            for j in range(i + 1, k):
                rows = (yi == i) | (yi == j)
                Xp = X[rows]
                yb = np.where(yi[rows] == i, 1, -1)  # MATLAB onevsone: first class +1, second -1
                scaler = SampleStandardScaler().fit(Xp) if self.standardize else None
                Xs = scaler.transform(Xp) if scaler is not None else Xp
                if self.kernel_scale == "auto":
                    s = matlab_auto_kernel_scale(Xs[yb == 1], Xs[yb == -1], rng)
                else:
                    s = float(self.kernel_scale)
                svm = SVC(kernel="poly", degree=1 if linear else int(self.polynomial_order),
                          gamma=1.0 / s**2, coef0=0.0 if linear else 1.0, C=self.box_constraint,
                          tol=self.tol).fit(Xs, yb)
                self.pairs_.append((i, j))
                self.learners_.append((scaler, svm))
                self.kernel_scales_.append(s)
        return self

    def _class_scores(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        k = len(self.classes_)
        loss = np.zeros((X.shape[0], k))
        count = np.zeros(k)
        for (i, j), (scaler, svm) in zip(self.pairs_, self.learners_):
            s = svm.decision_function(scaler.transform(X) if scaler is not None else X)
            loss[:, i] += np.maximum(0.0, 1.0 - s) / 2.0  # hinge loss for code +1
            loss[:, j] += np.maximum(0.0, 1.0 + s) / 2.0  # and for code -1
            count[i] += 1
            count[j] += 1
        return -loss / count

    def decision_function(self, X):
        """Minus each class's average hinge loss, shape (n, K); for two
        classes the scikit-learn convention, (n,) positive for ``classes_[1]``."""
        score = self._class_scores(X)
        return score[:, 1] - score[:, 0] if score.shape[1] == 2 else score

    def predict(self, X):
        score = self._class_scores(X)
        return self.classes_[np.argmax(score, axis=1)]


class MatlabKNNClassifier(DelegatingClassifier):
    """Classification Learner's KNN presets: Euclidean distance on
    standardised inputs; ``distance_weight`` ``"equal"`` (Medium KNN),
    ``"squaredinverse"`` (Weighted KNN) or ``"inverse"``."""

    #: checked when a protocol is read: the KNeighborsClassifier's own n_jobs, and its n_neighbors
    #: bound (at least 1) without its None (a KNN classifier needs a K)
    _parameter_constraints = {"n_neighbors": [Interval(Integral, 1, None, closed="left")],
                              "n_jobs": KNeighborsClassifier._parameter_constraints["n_jobs"]}

    def __init__(self, n_neighbors=10, distance_weight="equal", standardize=True, n_jobs=1):
        self.n_neighbors = n_neighbors
        self.distance_weight = distance_weight
        self.standardize = standardize
        self.n_jobs = n_jobs

    def _make_estimator(self, n_features, n_classes):
        if self.distance_weight not in _KNN_WEIGHTS:
            raise ValueError(f"distance_weight must be one of {sorted(_KNN_WEIGHTS)}, got {self.distance_weight!r}")
        knn = KNeighborsClassifier(n_neighbors=self.n_neighbors, weights=_KNN_WEIGHTS[self.distance_weight],
                                   metric="euclidean", n_jobs=self.n_jobs)
        return Pipeline([("standardize", _scaler(self.standardize)), ("knn", knn)])

    def fit(self, X, y):  # KNN takes no sample weights
        return super().fit(X, y)


TREE_DEFAULTS = {"criterion": "gini", "max_leaf_nodes": 21, "min_samples_split": 10, "min_samples_leaf": 1}
LDA_DEFAULTS = {"solver": "svd"}
LINEAR_SVM_DEFAULTS = {"kernel": "linear", "box_constraint": 1.0, "kernel_scale": "auto", "standardize": True}
QUADRATIC_SVM_DEFAULTS = {"kernel": "polynomial", "polynomial_order": 2, "box_constraint": 1.0,
                          "kernel_scale": "auto", "standardize": True}
KNN_DEFAULTS = {"n_neighbors": 10, "distance_weight": "equal", "standardize": True, "n_jobs": 1}
WKNN_DEFAULTS = {"n_neighbors": 10, "distance_weight": "squaredinverse", "standardize": True, "n_jobs": 1}
BAGGED_DEFAULTS = {"n_estimators": 30, "max_features": "sqrt", "criterion": "gini", "bootstrap": True,
                   "min_samples_leaf": 1, "n_jobs": 1}


@CLASSIFIERS.register("zhou-tree", description="MATLAB Medium Tree: Gini, at most 20 splits",
                      source=SOURCE, defaults=TREE_DEFAULTS, extra=None)
def zhou_tree(random_state=None, **params):
    return build(DecisionTreeClassifier, TREE_DEFAULTS, random_state, params, name="zhou-tree")


def check_lda(params: dict) -> None:
    """scikit-learn's rule across fields, which its declared domains cannot say: ``shrinkage`` only
    with the ``lsqr`` or ``eigen`` solver (the ``svd`` solver refuses it when fitted)."""
    if params.get("shrinkage") is not None and params.get("solver", "svd") == "svd":
        raise ParamError(("shrinkage",), "shrinkage needs solver: lsqr or eigen (the svd solver, zhou-lda's, "
                                         "takes none)")


@CLASSIFIERS.register("zhou-lda", description="MATLAB Linear Discriminant: pooled full covariance",
                      source=SOURCE, defaults=LDA_DEFAULTS, extra=None, check_params=check_lda)
def zhou_lda(random_state=None, **params):
    return build(LinearDiscriminantAnalysis, LDA_DEFAULTS, random_state, params, name="zhou-lda")


@CLASSIFIERS.register("zhou-linear-svm",
                      description="MATLAB Linear SVM: auto kernel scale, one-vs-one, C=1, standardised",
                      source=SOURCE, defaults=LINEAR_SVM_DEFAULTS, extra=None)
def zhou_linear_svm(random_state=None, **params):
    return build(MatlabSVMClassifier, LINEAR_SVM_DEFAULTS, random_state, params, name="zhou-linear-svm")


@CLASSIFIERS.register("zhou-quadratic-svm",
                      description="MATLAB Quadratic SVM: (1 + x'z)^2 kernel, auto scale, one-vs-one, C=1",
                      source=SOURCE, defaults=QUADRATIC_SVM_DEFAULTS, extra=None)
def zhou_quadratic_svm(random_state=None, **params):
    return build(MatlabSVMClassifier, QUADRATIC_SVM_DEFAULTS, random_state, params, name="zhou-quadratic-svm")


@CLASSIFIERS.register("zhou-knn", description="MATLAB Medium KNN: K=10, Euclidean, equal weights, standardised",
                      source=SOURCE, defaults=KNN_DEFAULTS, extra=None)
def zhou_knn(random_state=None, **params):
    return build(MatlabKNNClassifier, KNN_DEFAULTS, random_state, params, name="zhou-knn")


@CLASSIFIERS.register("zhou-weighted-knn",
                      description="MATLAB Weighted KNN: K=10, Euclidean, 1/d^2 weights, standardised",
                      source=SOURCE, defaults=WKNN_DEFAULTS, extra=None)
def zhou_weighted_knn(random_state=None, **params):
    return build(MatlabKNNClassifier, WKNN_DEFAULTS, random_state, params, name="zhou-weighted-knn")


@CLASSIFIERS.register("zhou-bagged-trees", description="MATLAB Bagged Trees: 30 deep trees, sqrt(M) per split",
                      source=SOURCE, defaults=BAGGED_DEFAULTS, extra=None, cheap_params=dict(n_estimators=5))
def zhou_bagged_trees(random_state=None, **params):
    return build(RandomForestClassifier, BAGGED_DEFAULTS, random_state, params, name="zhou-bagged-trees")
