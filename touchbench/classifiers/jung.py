"""Jung et al. (CoST: ICMI 2014 "Touching the void"; JMUI 2016), cited in
Gaus et al. 2015 (section 4): "Jung et al [22] (Bayes: 54%;
SVM: 53%)" on CoST, under leave-one-subject-out.

Gaus et al. give only the two classifier families and their accuracies, not
their settings. Interpretation:

- ``jung-naive-bayes``: a Bayesian classifier with normally distributed,
  independent features per class, i.e. Gaussian naive Bayes
  (``GaussianNB``, empirical priors, scikit-learn's ``var_smoothing``).
- ``jung-svm``: libsvm's C-SVC with an RBF kernel (one-vs-one) on features
  standardised on the training fold (:class:`SampleStandardScaler`),
  ``C = 1`` and ``gamma = "scale"`` (``1 / (M * Var(X))``, which is 1/M on
  standardised features). Jung et al. tuned their SVM; touchbench leaves
  tuning to a protocol (a grid over ``C`` and ``gamma``) rather than hiding
  a search inside the classifier. ``probability=True`` adds Platt-scaled
  probabilities (``CalibratedClassifierCV``, 5 unshuffled folds).
"""

from __future__ import annotations

from sklearn.calibration import CalibratedClassifierCV
from sklearn.naive_bayes import GaussianNB
from sklearn.pipeline import Pipeline
from sklearn.svm import SVC

from ._util import DelegatingClassifier, SampleStandardScaler, build
from .base import CLASSIFIERS

SOURCE = "Jung et al. 2014/2016, as cited in Gaus et al. 2015, section 4"


class StandardizedSVC(DelegatingClassifier):
    """RBF-kernel C-SVC on standardised inputs (see the module docstring)."""

    #: scikit-learn's own constraints of the SVC it builds (checked when a protocol is read)
    _parameter_constraints = {k: SVC._parameter_constraints[k] for k in ("C", "kernel", "gamma", "tol")}

    def __init__(self, C=1.0, kernel="rbf", gamma="scale", standardize=True, probability=False, tol=1e-3,
                 random_state=None):
        self.C = C
        self.kernel = kernel
        self.gamma = gamma
        self.standardize = standardize
        self.probability = probability
        self.tol = tol
        self.random_state = random_state

    _has_decision_function = True

    def _proba_available(self):
        return bool(self.probability)

    def _make_estimator(self, n_features, n_classes):
        svm = SVC(C=self.C, kernel=self.kernel, gamma=self.gamma, tol=self.tol, random_state=self.random_state)
        if self.probability:  # Platt scaling fitted by 5-fold cross-validation (deterministic folds)
            svm = CalibratedClassifierCV(svm, method="sigmoid", cv=5, ensemble=False)
        return Pipeline([("standardize", SampleStandardScaler() if self.standardize else "passthrough"),
                         ("svm", svm)])


NB_DEFAULTS = {"var_smoothing": 1e-9}
SVM_DEFAULTS = {"C": 1.0, "kernel": "rbf", "gamma": "scale", "standardize": True, "probability": False}


@CLASSIFIERS.register("jung-naive-bayes", description="Gaussian naive Bayes (Jung et al.'s Bayesian classifier)",
                      source=SOURCE, defaults=NB_DEFAULTS, extra=None)
def jung_naive_bayes(random_state=None, **params):
    return build(GaussianNB, NB_DEFAULTS, random_state, params, name="jung-naive-bayes")


@CLASSIFIERS.register("jung-svm", description="RBF-kernel SVM, C=1, gamma='scale', standardised features",
                      source=SOURCE, defaults=SVM_DEFAULTS, extra=None)
def jung_svm(random_state=None, **params):
    return build(StandardizedSVC, SVM_DEFAULTS, random_state, params, name="jung-svm")
