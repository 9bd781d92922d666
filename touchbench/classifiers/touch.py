"""touchbench's own classifiers: extremely randomised trees, plain and tuned by nested CV.

Not from a paper. Designed for the ``touch-rhythm``, ``cell-rhythm`` and
``contact-motion`` feature sets (:mod:`touchbench.features.touch`), usable
on any feature matrix. Every choice below was made by cross-validation
inside the challenge's training subjects (leave one training subject out);
docs/research/touch-methods.md has the numbers, including what did not help.

- ``touch-extra-trees``: scikit-learn's ``ExtraTreesClassifier``, 500 trees, 30 % of
  the features tried per split (``max_features=0.3``; better than
  ``sqrt`` in the inner CV), unlimited depth, one thread. Extra-trees
  rather than Gaus et al.'s random forest (2015, Sec. 4): equal in the
  inner CV, several times faster to fit.
- ``touch-extra-trees-fast``: the same with 100 trees, for the latency-bound entry
  (one capture's prediction costs about a fifth).
- ``touch-extra-trees-tuned``: nested cross-validation. Inside ``fit``, the training
  rows only are split by subject (``groups``, which the run engine passes:
  the training fold's subjects; without groups, stratified folds) and a
  small grid (``max_features`` x number of features kept by an importance
  ranking) is scored by inner-fold accuracy; the best is refitted on all
  training rows. The ranking is itself computed inside each inner training
  part, so no row scores a choice it helped make. The test fold is never
  seen: ``fit`` receives only the training matrix, and ``predict`` only
  applies the refitted model. ``inner_splitter_`` records the splitter and
  ``cv_results_`` the inner scores.
"""

from __future__ import annotations

from numbers import Integral
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.model_selection import GroupKFold, LeaveOneGroupOut, StratifiedKFold
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval

from ..core.constraints import ListOf
from ._util import MAX_SEED, build, seed_int
from .base import CLASSIFIERS, count_constraint
from .fastforest import compile_forest

#: at most this many rows are predicted with the compiled forest (live use, latency)
FEW_ROWS = 16
SOURCE = "touchbench (docs/research/touch-methods.md); Geurts et al. 2006 extra-trees via scikit-learn"


def _extra_trees(n_estimators: int, max_features: Any, n_jobs: int, seed: int) -> ExtraTreesClassifier:
    return ExtraTreesClassifier(n_estimators=int(n_estimators), max_features=max_features, n_jobs=int(n_jobs), random_state=seed)


class SelectedExtraTrees(ClassifierMixin, BaseEstimator):
    """Extra-trees on the ``keep`` most important features (all when ``keep`` is None).

    The importance ranking is the impurity importance of a 200-tree
    extra-trees model fitted on the same training rows (the fold's, never
    the test rows), so selection happens inside the training fold.
    """

    #: ``predict`` is ``classes_`` at the argmax of ``predict_proba`` (the run engine asks once for both)
    labels_are_argmax_proba = True

    #: checked when a protocol is read: max_features and n_jobs are the ExtraTreesClassifier's (its
    #: own constraints), keep None or at least 1 column, n_estimators the shared bound on trees
    _parameter_constraints = {"n_estimators": count_constraint("n_estimators"),
                              "max_features": ExtraTreesClassifier._parameter_constraints["max_features"],
                              "keep": [None, Interval(Integral, 1, None, closed="left")],
                              "n_jobs": ExtraTreesClassifier._parameter_constraints["n_jobs"],
                              "random_state": ["random_state"]}

    def __init__(self, n_estimators=500, max_features=0.3, keep=None, n_jobs=1, random_state=None):
        self.n_estimators = n_estimators
        self.max_features = max_features
        self.keep = keep
        self.n_jobs = n_jobs
        self.random_state = random_state

    def fit(self, X, y):
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        seed = seed_int(self.random_state)
        if self.keep is not None and int(self.keep) < X.shape[1]:
            ranker = _extra_trees(200, self.max_features, self.n_jobs, seed + 1).fit(X, y)
            self.columns_ = np.sort(np.argsort(-ranker.feature_importances_, kind="stable")[: int(self.keep)])
        else:
            self.columns_ = np.arange(X.shape[1])
        self.model_ = _extra_trees(self.n_estimators, self.max_features, self.n_jobs, seed).fit(X[:, self.columns_], y)
        self.classes_ = self.model_.classes_
        return self

    def forest_and_columns(self):
        """The fitted forest behind ``predict_proba`` and the input columns it reads
        (:func:`touchbench.classifiers.fastforest.compile_forest` walks it without this wrapper)."""
        check_is_fitted(self)
        return self.model_, self.columns_

    def predict_proba(self, X):
        """Class probabilities; a few rows (<= ``FEW_ROWS``) go through the compiled forest
        (:mod:`touchbench.classifiers.fastforest`, bit-identical to scikit-learn's, one
        vectorised walk over all trees instead of one Python call per tree)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)[:, self.columns_]
        if X.shape[0] <= FEW_ROWS:
            if getattr(self, "_compiled", None) is None:

                self._compiled = compile_forest(self.model_) or False
            if self._compiled:
                return self._compiled.predict_proba(X)
        return self.model_.predict_proba(X)

    def predict(self, X):
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]


class NestedTunedExtraTrees(ClassifierMixin, BaseEstimator):
    """``SelectedExtraTrees`` whose ``max_features`` and ``keep`` are chosen by inner CV on the training rows.

    Inner splits: with ``groups`` (the training subjects), one training
    subject is left out when there are at most ``max_groups_loo`` of them,
    else ``GroupKFold(inner_folds)``; without groups,
    ``StratifiedKFold(inner_folds)``.
    Ties go to the earlier grid entry (the cheaper, default-like one).
    """

    #: ``predict`` is ``classes_`` at the argmax of ``predict_proba`` (the run engine asks once for both)
    labels_are_argmax_proba = True

    #: checked when a protocol is read: each grid's values as SelectedExtraTrees declares them (at
    #: least one value each; every pair is fitted once per inner fold), n_estimators and
    #: inner_folds the shared bounds (trees; 2..1000 inner folds, never more than the training
    #: subjects), max_groups_loo at least 0 (only compared with the number of groups)
    _parameter_constraints = {
        "n_estimators": count_constraint("n_estimators"),
        "grid_max_features": [ListOf(SelectedExtraTrees._parameter_constraints["max_features"], min_length=1)],
        "grid_keep": [ListOf(SelectedExtraTrees._parameter_constraints["keep"], min_length=1)],
        "inner_folds": count_constraint("inner_folds"),
        "max_groups_loo": [Interval(Integral, 0, None, closed="left")],
        "n_jobs": ExtraTreesClassifier._parameter_constraints["n_jobs"],
        "random_state": ["random_state"]}

    def __init__(self, n_estimators=500, grid_max_features=(0.3, "sqrt"), grid_keep=(None, 150),
                 inner_folds=3, max_groups_loo=0, n_jobs=1, random_state=None):
        self.n_estimators = n_estimators
        self.grid_max_features = grid_max_features
        self.grid_keep = grid_keep
        self.inner_folds = inner_folds
        self.max_groups_loo = max_groups_loo
        self.n_jobs = n_jobs
        self.random_state = random_state

    def _inner_splitter(self, y, groups):
        if groups is not None and len(np.unique(groups)) >= 2:
            n_groups = len(np.unique(groups))
            if n_groups <= int(self.max_groups_loo):
                return LeaveOneGroupOut()
            return GroupKFold(n_splits=min(int(self.inner_folds), n_groups))
        _, counts = np.unique(y, return_counts=True)
        k = max(2, min(int(self.inner_folds), int(counts.min())))
        return StratifiedKFold(n_splits=k, shuffle=True, random_state=seed_int(self.random_state) % MAX_SEED)

    def candidates(self) -> list[dict[str, Any]]:
        return [{"max_features": mf, "keep": k} for k in self.grid_keep for mf in self.grid_max_features]

    def fit(self, X, y, groups=None):
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        if groups is not None:
            groups = np.asarray(groups)
            if len(groups) != len(y):
                raise ValueError(f"groups has {len(groups)} entries for {len(y)} training rows")
        seed = seed_int(self.random_state)
        base = SelectedExtraTrees(n_estimators=self.n_estimators, n_jobs=self.n_jobs, random_state=seed)
        splitter = self._inner_splitter(y, groups)
        self.inner_splitter_ = splitter
        folds = list(splitter.split(X, y, groups))
        scores = []
        for cand in self.candidates():
            accs = []
            for a, b in folds:
                if len(np.unique(y[a])) < 2:
                    continue
                m = clone(base).set_params(**cand).fit(X[a], y[a])
                accs.append(float(np.mean(m.predict(X[b]) == y[b])))
            scores.append(float(np.mean(accs)) if accs else -1.0)
        best = int(np.argmax(scores))
        self.cv_results_ = {"params": self.candidates(), "mean_accuracy": scores}
        self.best_params_ = self.candidates()[best]
        self.model_ = clone(base).set_params(**self.best_params_).fit(X, y)
        self.classes_ = self.model_.classes_
        return self

    def forest_and_columns(self):
        """The refitted model's forest and the columns it reads (:meth:`SelectedExtraTrees.forest_and_columns`)."""
        check_is_fitted(self)
        return self.model_.forest_and_columns()

    def predict_proba(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.model_.predict_proba(X)

    def predict(self, X):
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]


DEFAULTS_ET = {"n_estimators": 500, "max_features": 0.3, "keep": None, "n_jobs": 1}
DEFAULTS_FAST = {"n_estimators": 100, "max_features": 0.3, "keep": None, "n_jobs": 1}
DEFAULTS_TUNED = {"n_estimators": 500, "grid_max_features": (0.3, "sqrt"), "grid_keep": (None, 150),
                  "inner_folds": 3, "max_groups_loo": 0, "n_jobs": 1}


@CLASSIFIERS.register("touch-extra-trees", description="touchbench: extra-trees, 500 trees, 30 % of features per split, on any feature matrix",
                      source=SOURCE, defaults=DEFAULTS_ET, extra=None, cheap_params=dict(n_estimators=5))
def touch_extra_trees(random_state=None, **params):
    return build(SelectedExtraTrees, DEFAULTS_ET, random_state, params, name="touch-extra-trees")


@CLASSIFIERS.register("touch-extra-trees-fast", description="touchbench: extra-trees, 100 trees (latency-bound entry), on any feature matrix",
                      source=SOURCE, defaults=DEFAULTS_FAST, extra=None, cheap_params=dict(n_estimators=5))
def touch_extra_trees_fast(random_state=None, **params):
    return build(SelectedExtraTrees, DEFAULTS_FAST, random_state, params, name="touch-extra-trees-fast")


@CLASSIFIERS.register("touch-extra-trees-tuned", description="touchbench: extra-trees with max_features and feature selection chosen by nested CV over training subjects",
                      source=SOURCE, defaults=DEFAULTS_TUNED, extra=None, cheap_params=dict(n_estimators=5, inner_folds=2))
def touch_extra_trees_tuned(random_state=None, **params):
    return build(NestedTunedExtraTrees, DEFAULTS_TUNED, random_state, params, name="touch-extra-trees-tuned")
