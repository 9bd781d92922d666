"""Class probabilities of a fitted scikit-learn forest for a few samples, fast.

Why: ``RandomForestClassifier.predict_proba`` walks its trees one at a time
in Python (one call and one input validation per tree), which for the
1000 trees of Gaus et al. (2015, section 4) costs tens to
hundreds of milliseconds per window, however small the input. A live
recogniser classifies one to a few windows per decision, so here every
tree is walked at once: the trees' nodes are concatenated into flat arrays
and each step of the walk is one vectorised numpy operation over all
(sample, tree) pairs, as many steps as the deepest tree; with numba installed
one compiled loop walks them instead, over nodes packed as 16-byte
records (:mod:`.forest_kernels`: a tenth or two of a millisecond for a
500-tree forest on two windows, where the numpy walk pays about a
millisecond of per-step calls).

The result is the same, bit for bit, as scikit-learn's: the input is
rounded to float32 as scikit-learn's trees do, a sample goes left when
``x[feature] <= threshold``, a tree's probability is its leaf's ``value``
(class fractions since scikit-learn 1.4), and the trees' probabilities are
added in estimator order (a sequential cumulative sum, as scikit-learn's
single-threaded accumulation) and divided by the number of trees. The test
compares both walks with ``predict_proba`` exactly. Inputs with NaN (which scikit-learn
routes by the learned missing-value direction) fall back to scikit-learn.

Supported: a ``ForestClassifier`` (random forest, extra trees and their
subclasses that do not override ``predict_proba``) with one output, and an
estimator that wraps one: it declares ``forest_and_columns()``, the fitted
forest whose probabilities are its own and the input columns that forest
reads (None: all), as touchbench's extra-trees do
(:mod:`touchbench.classifiers.touch`, which keep an importance-ranked
subset of the columns). :func:`compile_forest` returns None for anything
else and callers use the estimator's own ``predict_proba``.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from ..core.compiled import kernels

__all__ = ["CompiledForest", "compile_forest"]



class CompiledForest:
    """Flat node arrays of every tree of a fitted forest (see module docstring)."""

    def __init__(self, forest: Any, columns: Any = None, n_features: int | None = None):
        """``columns``: the input columns the forest reads (None: all); ``n_features``: the width of
        the input (the wrapping estimator's; default the forest's)."""
        from sklearn.tree._tree import TREE_LEAF

        self.forest = forest
        self.columns = None if columns is None else np.asarray(columns, dtype=np.int64)
        trees = [e.tree_ for e in forest.estimators_]
        self.n_trees = len(trees)
        self.n_features = int(forest.n_features_in_ if n_features is None else n_features)
        sizes = np.array([t.node_count for t in trees], dtype=np.int64)
        offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        left, right, feature, threshold, value = [], [], [], [], []
        for off, t in zip(offsets, trees):
            lc = t.children_left.astype(np.int64)
            rc = t.children_right.astype(np.int64)
            leaf = lc == TREE_LEAF
            own = np.arange(t.node_count, dtype=np.int64) + off
            # A leaf points to itself on both sides, so extra steps keep it in place.
            left.append(np.where(leaf, own, lc + off))
            right.append(np.where(leaf, own, rc + off))
            feature.append(np.where(leaf, 0, t.feature).astype(np.int64))
            threshold.append(np.where(leaf, np.inf, t.threshold).astype(np.float64))
            value.append(np.asarray(t.value[:, 0, :], dtype=np.float64))
        # children side by side: node k's left child at 2k, its right child at 2k + 1
        self.children = np.stack([np.concatenate(left), np.concatenate(right)], axis=1).ravel()
        self.feature = np.concatenate(feature)
        if self.columns is not None:  # read the wrapping estimator's columns directly
            self.feature = self.columns[self.feature]
        self.threshold = np.concatenate(threshold)
        self.value = np.concatenate(value)
        self.roots = offsets.astype(np.int64)
        self.depth = int(max(t.max_depth for t in trees))
        self.classes_ = forest.classes_

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Same as ``forest.predict_proba(X[:, columns])``, for a 2-D ``X`` of a few rows.

        With numba, :func:`.forest_kernels.forest_proba` on the packed nodes (:meth:`_packed`). Else
        each step of the walk, for all (sample, tree) pairs at once: the node's feature read from
        the flat rows, compared with its threshold, and the child taken at ``2 node + (x > threshold)``
        (``x > threshold`` is ``not x <= threshold`` for the finite values walked), into buffers
        allocated once per call."""
        X = np.asarray(X)
        if X.ndim != 2 or X.shape[1] != self.n_features:
            raise ValueError(f"expected {self.n_features} features per row, got shape {X.shape}")
        x32 = X.astype(np.float32)
        if not np.isfinite(x32 if self.columns is None else x32[:, self.columns]).all():
            return self.forest.predict_proba(X if self.columns is None else X[:, self.columns])
        n = x32.shape[0]
        xs = x32.astype(np.float64).ravel()
        kern = kernels("classifiers.forest_kernels")
        if kern is not None:
            out = np.empty((n, self.value.shape[1]), dtype=np.float64)
            kern.forest_proba(xs, self.n_features, *self._packed(kern), out)
            return out
        node = np.broadcast_to(self.roots, (n, self.n_trees)).copy()
        offset = np.arange(0, n * self.n_features, self.n_features, dtype=np.int64)[:, None]
        feature, threshold, children = self.feature, self.threshold, self.children
        for _ in range(self.depth):
            right = xs[feature[node] + offset] > threshold[node]
            node = children[(node << 1) + right]
        leaf_values = self.value[node]  # (n, trees, classes)
        total = np.cumsum(leaf_values, axis=1)[:, -1, :]
        return total / self.n_trees


    def _packed(self, kern: ModuleType) -> tuple:
        """The compiled walk's nodes (:mod:`.forest_kernels`), packed once: each tree's root, the records'
        thresholds, features and first children (views of one record array) and the table of leaf values."""
        if getattr(self, "_pack", None) is None:
            n, n_classes = self.value.shape
            nodes = np.empty(n, dtype=kern.NODE)
            table = np.zeros((n_classes + int(np.count_nonzero(self.children[::2] == np.arange(n))), n_classes))
            table[:n_classes] = np.eye(n_classes)
            used = kern.pack_forest(self.children, self.feature, self.threshold, self.value, self.roots,
                                    nodes["threshold"], nodes["feature"], nodes["child"], table)
            self._pack = (self.roots, nodes["threshold"], nodes["feature"], nodes["child"], table[:used].copy())
        return self._pack


def compile_forest(estimator: Any) -> CompiledForest | None:
    """A :class:`CompiledForest` for a supported fitted forest, or an estimator wrapping one
    (``forest_and_columns()``), else None."""
    parts = getattr(estimator, "forest_and_columns", None)
    if callable(parts):
        forest, columns = parts()
        if not _supported(forest):
            return None
        return CompiledForest(forest, columns, n_features=getattr(estimator, "n_features_in_", None))
    return CompiledForest(estimator) if _supported(estimator) else None


def _supported(estimator: Any) -> bool:
    """Whether ``estimator`` is a fitted one-output scikit-learn forest whose probabilities are its trees' mean."""
    try:
        from sklearn.ensemble._forest import ForestClassifier
        from sklearn.tree import DecisionTreeClassifier
    except ImportError:  # pragma: no cover
        return False
    if not isinstance(estimator, ForestClassifier):
        return False
    if type(estimator).predict_proba is not ForestClassifier.predict_proba:
        return False
    ests = getattr(estimator, "estimators_", None)
    if not ests or getattr(estimator, "n_outputs_", 1) != 1:
        return False
    return all(type(e).predict_proba is DecisionTreeClassifier.predict_proba for e in ests)
