"""Flagg 2012 (MSc thesis), Appendix A "Model Parameters": the four
Weka models of chapters 3 and 4.

- ``flagg-logistic``: Weka ``Logistic``, "ridge regularization parameter:
  1.0E-8; maximum iterations: not fixed, optimize weights fully (-1)".
  Weka standardises every attribute (sample standard deviation) and
  minimises ``-loglik + ridge * ||beta||^2`` (intercepts unpenalised) with
  a quasi-Newton method until convergence. Here: :class:`SampleStandardScaler`
  then scikit-learn's multinomial ``LogisticRegression`` with L-BFGS and
  ``C = 1 / (2 * ridge)`` (scikit-learn minimises ``0.5 ||w||^2 + C * loss``,
  so the two objectives coincide), ``max_iter=10000`` and a tight ``tol``
  standing in for "until convergence". Not matched: Weka fits K - 1 weight
  vectors against a reference class where scikit-learn fits K symmetric
  ones; with a ridge of 1e-8 both are essentially unpenalised and agree
  except on separable data, where neither converges (both stop at their
  limits and may then predict differently).
- ``flagg-bayesnet``: Weka ``BayesNet`` with K2 search and SimpleEstimator,
  see :mod:`touchbench.classifiers.bayesnet`. It is a real K2 network; with
  Weka's default ``maxNrOfParents = 1`` it is a naive Bayes over
  MDL-discretised attributes, as Weka's is.
- ``flagg-mlp``: Weka ``MultilayerPerceptron``, hidden layer ``"a"`` =
  (attributes + classes) / 2 (19 in the thesis), learning rate 0.3, momentum
  0.2, 500 epochs, normalised attributes, see
  :mod:`touchbench.classifiers.mlp`. The thesis' seed (0) is Weka's; the
  engine's ``random_state`` replaces it.
- ``flagg-rf``: Weka ``RandomForest``, 10 trees, unlimited depth, 5
  features per split (the thesis writes "5 (option '0' in Weka)"; Weka's
  ``-K 0`` gives ``int(log2 M) + 1``, which is 5 for 16 <= M < 32, so both
  readings agree for Flagg's feature count; we use 5, capped at M), seed 1
  in the thesis, replaced by the engine's ``random_state``. Split criterion
  information gain (Weka's ``RandomTree``).
"""

from __future__ import annotations

from numbers import Real
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import Pipeline
from sklearn.utils._param_validation import Interval

from ._util import (
    DelegatingClassifier,
    SampleStandardScaler,
    WekaRandomForestClassifier,
    build,
)
from .base import CLASSIFIERS
from .bayesnet import K2BayesNetClassifier
from .mlp import WekaMLPClassifier

SOURCE = "Flagg 2012, Appendix A (Weka)"


class WekaLogisticRegression(DelegatingClassifier):
    """Weka ``Logistic`` (ridge-penalised multinomial logistic regression on
    standardised attributes); see the module docstring for the mapping.

    Parameters
    ----------
    ridge : Weka ``-R`` (1e-8 in Flagg).
    max_iter, tol : L-BFGS limits standing in for Weka's ``-M -1``.
    n_jobs : kept for the registry's uniform interface (L-BFGS multinomial
        fits are single-threaded in scikit-learn).
    """

    #: checked when a protocol is read: a positive ridge (C = 1 / (2 ridge)), and the max_iter and
    #: tol of the LogisticRegression it builds (its own constraints)
    _parameter_constraints = {"ridge": [Interval(Real, 0, None, closed="neither")],
                              "max_iter": LogisticRegression._parameter_constraints["max_iter"],
                              "tol": LogisticRegression._parameter_constraints["tol"]}

    def __init__(self, ridge=1e-8, max_iter=10000, tol=1e-10, n_jobs=1):
        self.ridge = ridge
        self.max_iter = max_iter
        self.tol = tol
        self.n_jobs = n_jobs

    def _make_estimator(self, n_features, n_classes):
        if not self.ridge > 0:
            raise ValueError(f"ridge must be positive, got {self.ridge!r}")
        return Pipeline([
            ("standardize", SampleStandardScaler()),
            ("logistic", LogisticRegression(C=1.0 / (2.0 * self.ridge), solver="lbfgs",
                                            max_iter=self.max_iter, tol=self.tol)),
        ])

    _has_decision_function = True

    def fit(self, X, y, sample_weight=None):
        super().fit(X, y, sample_weight=sample_weight)
        self.n_iter_ = self.estimator_[-1].n_iter_
        return self


LOGISTIC_DEFAULTS = {"ridge": 1e-8, "max_iter": 10000, "tol": 1e-10, "n_jobs": 1}
BAYESNET_DEFAULTS = {"max_parents": 1, "alpha": 0.5, "init_as_naive_bayes": True, "random_order": False}
MLP_DEFAULTS = {"hidden_layers": "a", "learning_rate": 0.3, "momentum": 0.2, "max_epochs": 500,
                "normalize_attributes": True}
RF_DEFAULTS = {"n_estimators": 10, "max_features": 5, "max_depth": None, "criterion": "entropy", "n_jobs": 1}


@CLASSIFIERS.register(
    "flagg-logistic",
    description="Weka Logistic: multinomial logistic regression, ridge 1e-8, fitted to convergence",
    source=SOURCE, defaults=LOGISTIC_DEFAULTS, extra=None, cheap_params=dict(max_iter=100, tol=1e-4))
def flagg_logistic(random_state=None, **params):
    return build(WekaLogisticRegression, LOGISTIC_DEFAULTS, random_state, params, name="flagg-logistic")


@CLASSIFIERS.register(
    "flagg-bayesnet",
    description="Weka BayesNet: K2 search (max 1 parent = naive Bayes), SimpleEstimator 0.5, MDL bins",
    source=SOURCE, defaults=BAYESNET_DEFAULTS, extra=None,
)
def flagg_bayesnet(random_state=None, **params):
    return build(K2BayesNetClassifier, BAYESNET_DEFAULTS, random_state, params, name="flagg-bayesnet")


@CLASSIFIERS.register(
    "flagg-mlp",
    description="Weka MultilayerPerceptron: 1 hidden layer (attribs+classes)/2, lr 0.3, momentum 0.2, 500 epochs",
    source=SOURCE, defaults=MLP_DEFAULTS, extra=None, cheap_params=dict(max_epochs=10))
def flagg_mlp(random_state=None, **params):
    return build(WekaMLPClassifier, MLP_DEFAULTS, random_state, params, name="flagg-mlp")


@CLASSIFIERS.register(
    "flagg-rf",
    description="Weka RandomForest: 10 trees, 5 features per split, unlimited depth",
    source=SOURCE, defaults=RF_DEFAULTS, extra=None, cheap_params=dict(n_estimators=5))
def flagg_rf(random_state=None, **params):
    return build(WekaRandomForestClassifier, RF_DEFAULTS, random_state, params, name="flagg-rf")

