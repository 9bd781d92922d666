"""Gradient-boosted trees with XGBoost: not one of the four papers'
classifiers, a modern baseline for the same feature sets.

XGBoost is an optional install (:data:`INSTALL_HINT`): the ``xgboost``
extra (the full build, GPU-capable; an XGBoost already installed satisfies
it as it is) or ``xgboost-cpu`` (the CPU-only build, a few MB; the tests
use it). Both install the same ``xgboost`` package: have one of them.

Defaults for these data sizes (hundreds to a few thousand captures, tens to
a few thousand features, 7 to 14 classes): 300 rounds of depth-4 trees at
learning rate 0.1 with row and column subsampling 0.8 (regularises when
features outnumber captures), the ``hist`` tree method, one thread.
XGBoost needs integer labels: the wrapper encodes the gesture names with a
``LabelEncoder`` and decodes its predictions. With a fixed ``random_state``
and ``n_jobs`` the model is bit-identical across runs on one machine.
"""

from __future__ import annotations

from numbers import Integral, Real
import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.preprocessing import LabelEncoder
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval

from ..core.errors import TouchbenchError
from ._util import build, check_sample_weight, importable, seed_int
from .base import CLASSIFIERS

INSTALL_HINT = "pip install 'touchbench[xgboost]'  (or 'touchbench[xgboost-cpu]': the CPU-only build)"


def xgboost_available() -> bool:
    """Whether XGBoost (either build) can be imported, without importing it."""
    return importable("xgboost")


class XGBoostClassifier(ClassifierMixin, BaseEstimator):
    """``xgboost.XGBClassifier`` that accepts and returns string labels."""

    #: XGBoost's documented ranges (checked when a protocol is read): eta in [0, 1], max_depth,
    #: min_child_weight, lambda at least 0, subsample and colsample_bytree in (0, 1]
    _parameter_constraints = {
        "learning_rate": [Interval(Real, 0, 1, closed="both")],
        "max_depth": [Interval(Integral, 0, None, closed="left")],
        "min_child_weight": [Interval(Real, 0, None, closed="left")],
        "reg_lambda": [Interval(Real, 0, None, closed="left")],
        "subsample": [Interval(Real, 0, 1, closed="right")],
        "colsample_bytree": [Interval(Real, 0, 1, closed="right")],
    }

    def __init__(self, n_estimators=300, max_depth=4, learning_rate=0.1, subsample=0.8, colsample_bytree=0.8,
                 min_child_weight=1.0, reg_lambda=1.0, tree_method="hist", n_jobs=1, random_state=None):
        self.n_estimators = n_estimators
        self.max_depth = max_depth
        self.learning_rate = learning_rate
        self.subsample = subsample
        self.colsample_bytree = colsample_bytree
        self.min_child_weight = min_child_weight
        self.reg_lambda = reg_lambda
        self.tree_method = tree_method
        self.n_jobs = n_jobs
        self.random_state = random_state

    def fit(self, X, y, sample_weight=None):
        if not xgboost_available():
            raise TouchbenchError(f"the 'xgboost' classifier needs XGBoost, which is not installed: {INSTALL_HINT}")
        import xgboost  # an optional install, imported when fitted

        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.encoder_ = LabelEncoder().fit(y)
        self.classes_ = self.encoder_.classes_
        yi = self.encoder_.transform(y)
        seed = seed_int(self.random_state)
        k = len(self.classes_)
        self.booster_model_ = xgboost.XGBClassifier(
            n_estimators=self.n_estimators, max_depth=self.max_depth, learning_rate=self.learning_rate,
            subsample=self.subsample, colsample_bytree=self.colsample_bytree,
            min_child_weight=self.min_child_weight, reg_lambda=self.reg_lambda, tree_method=self.tree_method,
            n_jobs=self.n_jobs, random_state=int(seed),
            objective="binary:logistic" if k <= 2 else "multi:softprob",
        )
        if k == 1:  # XGBoost cannot fit one class; every prediction is that class
            self.booster_model_ = None
            return self
        if sample_weight is not None:
            sample_weight = check_sample_weight(sample_weight, X.shape[0])
        self.booster_model_.fit(X, yi, sample_weight=sample_weight)
        return self

    def __getstate__(self):
        """Saved with the booster as XGBoost's own JSON (``booster_json_``), not as Python objects."""
        state = dict(super().__getstate__())
        model = state.get("booster_model_")
        if model is not None:
            state["booster_model_"] = None
            state["booster_json_"] = bytes(model.get_booster().save_raw(raw_format="json"))
        return state

    def __setstate__(self, state):
        state = dict(state)
        raw = state.pop("booster_json_", None)
        super().__setstate__(state)
        if raw is not None:
            import xgboost

            model = xgboost.XGBClassifier(n_jobs=self.n_jobs)
            model.load_model(bytearray(raw))
            self.booster_model_ = model

    def predict_proba(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        if self.booster_model_ is None:
            return np.ones((X.shape[0], 1))
        return np.asarray(self.booster_model_.predict_proba(X), dtype=np.float64)

    def predict(self, X):
        p = self.predict_proba(X)
        return self.classes_[np.argmax(p, axis=1)]


DEFAULTS = {"n_estimators": 300, "max_depth": 4, "learning_rate": 0.1, "subsample": 0.8,
            "colsample_bytree": 0.8, "min_child_weight": 1.0, "reg_lambda": 1.0, "tree_method": "hist",
            "n_jobs": 1}


@CLASSIFIERS.register("xgboost", description="XGBoost gradient-boosted trees (300 x depth 4, lr 0.1, hist)",
                      source="XGBoost (Chen & Guestrin 2016); not from the papers, a modern baseline",
                      defaults=DEFAULTS, extra="xgboost", cheap_params=dict(n_estimators=10))
def xgboost_classifier(random_state=None, **params):
    return build(XGBoostClassifier, DEFAULTS, random_state, params, name="xgboost")
