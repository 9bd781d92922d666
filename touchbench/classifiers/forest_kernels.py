"""The compiled walk of :class:`touchbench.classifiers.fastforest.CompiledForest`, used when numba is
installed.

The nodes are packed once (:func:`pack_tree`), each tree breadth first: a node is one 16-byte record
(threshold, feature, first child; a node's two children side by side, so a step of the walk reads
one record), a leaf's record points to its row of a table of the leaves' distinct values. The walk
(:func:`forest_proba`): each tree for every row, from the root to the child at ``child + (x[feature]
> threshold)`` until a leaf; each row's leaf values added in tree order, then divided by the number
of trees. The same comparisons and the same additions in the same order as scikit-learn's walk and
accumulation, so the same numbers bit for bit; the vectorised numpy walk of :mod:`.fastforest`
stays the path without numba (tests/test_deploy_units.py holds both to scikit-learn exactly).

Imported on first use (:func:`touchbench.classifiers.fastforest.kernels`: never without numba),
compiled once per machine (numba's on-disk cache).
"""

from __future__ import annotations

import numba
import numpy as np

jit = numba.njit(cache=True, nogil=True)

#: one node of the packed walk: a leaf has child ``-1 - (its row of the value table)``
NODE = np.dtype([("threshold", np.float64), ("feature", np.int32), ("child", np.int32)])


@jit
def pack_tree(left, right, feature, threshold, leaf_row, at, thr_out, feat_out, child_out):
    """One tree's nodes (scikit-learn's arrays; a leaf's ``left`` is -1) into the packed records from
    index ``at``, breadth first; the index after its last node."""
    n = left.size
    queue = np.empty(n, dtype=np.int64)
    where = np.empty(n, dtype=np.int64)
    queue[0] = 0
    where[0] = at
    head, tail, free = 0, 1, at + 1
    while head < tail:
        u = queue[head]
        head += 1
        k = where[u]
        if left[u] < 0:
            thr_out[k] = np.inf
            feat_out[k] = 0
            child_out[k] = -1 - leaf_row[u]
            continue
        thr_out[k] = threshold[u]
        feat_out[k] = feature[u]
        child_out[k] = free
        where[left[u]] = free
        where[right[u]] = free + 1
        queue[tail] = left[u]
        queue[tail + 1] = right[u]
        tail += 2
        free += 2
    return free


@jit
def forest_proba(xs, n_features, roots, threshold, feature, child, table, out):
    """``out`` ``(n, C)``: the mean leaf value over the trees for each row of the flat rows ``xs``
    (``n * n_features`` values, float32 readings as float64), walking the packed nodes."""
    n, n_classes = out.shape
    n_trees = roots.shape[0]
    out[:] = 0.0
    for t in range(n_trees):
        for i in range(n):
            row = i * n_features
            node = roots[t]
            c = child[node]
            while c >= 0:
                node = c + (1 if xs[row + feature[node]] > threshold[node] else 0)
                c = child[node]
            leaf = -1 - c
            for k in range(n_classes):
                out[i, k] += table[leaf, k]
    for i in range(n):
        for k in range(n_classes):
            out[i, k] /= n_trees
