"""The compiled walk of :class:`touchbench.classifiers.fastforest.CompiledForest`, used when numba is
installed.

One loop per (sample, tree): from the tree's root, the child at ``2 node + (x[feature] >
threshold)`` until a leaf (a node that is its own child); the trees' leaf values added in tree
order, then divided by the number of trees. The same operations in the same order as
scikit-learn's walk and accumulation, so the same numbers bit for bit; the vectorised numpy walk of
:mod:`.fastforest` stays the path without numba (tests/test_deploy_units.py holds both to
scikit-learn exactly).

Imported on first use (:func:`touchbench.classifiers.fastforest.kernels`: never without numba),
compiled once per machine (numba's on-disk cache).
"""

from __future__ import annotations

import numba

jit = numba.njit(cache=True, nogil=True)


@jit
def forest_proba(xs, n_features, roots, children, feature, threshold, value, out):
    """``out`` ``(n, C)``: the mean leaf value over the trees for each row of the flat rows ``xs``
    (``n * n_features`` values, float32 readings as float64)."""
    n, n_classes = out.shape
    n_trees = roots.shape[0]
    for i in range(n):
        row = i * n_features
        for k in range(n_classes):
            out[i, k] = 0.0
        for t in range(n_trees):
            node = roots[t]
            while True:
                nxt = children[2 * node + (1 if xs[row + feature[node]] > threshold[node] else 0)]
                if nxt == node:
                    break
                node = nxt
            for k in range(n_classes):
                out[i, k] += value[node, k]
        for k in range(n_classes):
            out[i, k] /= n_trees
