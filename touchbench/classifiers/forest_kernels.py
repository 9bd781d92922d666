"""The compiled walk of :class:`touchbench.classifiers.fastforest.CompiledForest`, used when numba is
installed.

The nodes are packed once (:func:`pack_forest`), each tree depth first: a node is one 16-byte record
(threshold, feature, first child; a node's two children side by side, so a step of the walk reads
one record), a leaf's record points to its row of a table of leaf values (one row per class for the leaves
of one class, as a grown tree's mostly are; a row of its own for another). The walk
(:func:`forest_proba`): each tree for every row, from the root to the child at ``child + (x[feature]
> threshold)`` until a leaf, several trees side by side (their reads overlap); each row's leaf values
added in tree order, then divided by the number of trees. The same comparisons and the same additions in the same order as scikit-learn's walk and
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
def pack_forest(children, feature, threshold, value, roots, thr_out, feat_out, child_out, table):
    """The flat walk's nodes (:class:`touchbench.classifiers.fastforest.CompiledForest`'s: a leaf is
    its own child) packed into the records, each tree depth first from its root (a node's children side
    by side, the left one's subtree next: a walk going left reads nearby records); a leaf points to
    its row of ``table``: the one-hot row of its class when its values are one class's (``table``'s
    first rows, the identity), else a row of its own. The rows of ``table`` used."""
    n_classes = value.shape[1]
    stack = np.empty(threshold.size, dtype=np.int64)
    where = np.empty(threshold.size, dtype=np.int64)
    rows = n_classes
    free = 0
    for root in roots:
        stack[0] = root
        where[root] = free
        top, free = 1, free + 1
        while top:
            top -= 1
            u = stack[top]
            k = where[u]
            if children[2 * u] == u:
                thr_out[k] = np.inf
                feat_out[k] = 0
                child_out[k] = -1 - _leaf_row(value[u], table, rows)
                if child_out[k] == -1 - rows:
                    rows += 1
                continue
            thr_out[k] = threshold[u]
            feat_out[k] = feature[u]
            child_out[k] = free
            for side in range(2):  # the left child on top: its subtree is packed next
                where[children[2 * u + side]] = free + side
                stack[top + 1 - side] = children[2 * u + side]
            top += 2
            free += 2
    return rows


@jit
def _leaf_row(v, table, rows):
    """The row of ``table`` for the leaf values ``v``: its class's when one-hot, else ``rows`` (filled)."""
    hot = -1
    for k in range(v.size):
        if v[k] == 1.0 and hot < 0:
            hot = k
        elif v[k] != 0.0:
            hot = -2
    if hot >= 0:
        return hot
    table[rows] = v
    return rows


#: the trees walked side by side for one row: their steps do not wait on each other's reads, so the
#: memory reads of several walks are in flight at once (a walk alone waits on every node it reads)
WALKS = 8


@jit
def forest_proba(xs, n_features, roots, threshold, feature, child, table, out):
    """``out`` ``(n, C)``: the mean leaf value over the trees for each row of the flat rows ``xs``
    (``n * n_features`` values, float32 readings as float64), walking the packed nodes, :data:`WALKS`
    trees side by side; each row's leaf values are added in tree order once their walks end."""
    n, n_classes = out.shape
    n_trees = roots.shape[0]
    out[:] = 0.0
    node = np.empty(WALKS, dtype=np.int64)
    c = np.empty(WALKS, dtype=np.int64)
    for t0 in range(0, n_trees, WALKS):
        m = min(WALKS, n_trees - t0)
        for i in range(n):
            row = i * n_features
            for g in range(m):
                node[g] = roots[t0 + g]
                c[g] = child[node[g]]
            walking = True
            while walking:
                walking = False
                for g in range(m):
                    if c[g] >= 0:
                        u = c[g] + (1 if xs[row + feature[node[g]]] > threshold[node[g]] else 0)
                        node[g] = u
                        c[g] = child[u]
                        walking = True
            for g in range(m):
                leaf = -1 - c[g]
                for k in range(n_classes):
                    out[i, k] += table[leaf, k]
    for i in range(n):
        for k in range(n_classes):
            out[i, k] /= n_trees
