"""Compiled loops for ``contact-evidence`` (:mod:`touchbench.features.contact`), used when numba is
installed: a sibling of :mod:`touchbench.features.touch_kernels` (the same rules: one capture at a
time, numpy's values within 1e-9, numpy's thresholds exactly)."""

from __future__ import annotations

import math

import numpy as np

from .order_kernels import counted, select
from .touch_kernels import jit


@jit
def evidence(u, flat, floor, units, quiet, ranks, full, integral, out):
    """``contact-evidence``'s features into ``out`` ``(N, 6 + 3 * units + 4)`` from the heights ``u``
    ``(N, T, C)``, them sorted per capture ``flat`` ``(N, T * C)``, the noise floor's lower bound
    ``floor``, the ``quiet`` cells' count, the ranks of the level's order statistics and the full scale.
    ``integral``: every height is a whole number of a span below 65536, so medians and the level's
    order statistics are read off counts and ``flat`` is not read (it may be empty). Medians, the
    quiet cells and the thresholds are numpy's values exactly (a reading is counted above a
    threshold by comparison); the level's mean is the exact sum of whole numbers there."""
    n, t, nc = u.shape
    col = np.empty(t)
    med = np.empty(nc)
    mads = np.empty(quiet)
    cm = np.empty(nc)
    sq = np.empty(nc)
    fm = np.empty(t)
    counts = np.zeros(4 * t + 2, dtype=np.int64)
    for i in range(n):
        ui = u[i]
        o = out[i]
        cm[:] = 0.0
        for k in range(t):
            top = ui[k, 0]
            for c in range(nc):
                v = ui[k, c]
                cm[c] += v
                top = max(top, v)
            fm[k] = top
        cm /= t
        sq[:] = 0.0
        for k in range(t):
            for c in range(nc):
                d = ui[k, c] - cm[c]
                sq[c] += d * d
        for c in range(nc):
            col[:] = ui[:, c]
            med[c] = _median_counted(col, counts) if integral else _median(col)
        qcells = np.argsort(med, kind="mergesort")[:quiet]
        for m in range(quiet):
            c = qcells[m]
            if integral:  # twice the deviations: whole numbers (a median is whole or half)
                for k in range(t):
                    col[k] = 2.0 * abs(ui[k, c] - med[c])
                mads[m] = _median_counted(col, counts) / 2.0
            else:
                for k in range(t):
                    col[k] = abs(ui[k, c] - med[c])
                mads[m] = _median(col)
        rest = _median(med[qcells])
        noise = max(1.4826 * _median(mads), floor)
        if integral:
            _counted_level(ui, ranks, rest + noise * units, o)
        else:
            _sorted_level(flat[i], ranks, rest + noise * units, o)
        for m in range(4):
            o[m] /= full
        top = o[3] * full
        o[4] = cm.min() / full
        o[5] = cm.max() / full
        for m in range(units.size):
            thr = rest + noise * units[m]
            o[7 + 3 * m] = (fm > thr).sum() / t
            o[8 + 3 * m] = (cm > thr).sum() / nc
        b = 6 + 3 * units.size
        sd_sum = 0.0
        sd_max = 0.0
        for c in range(nc):
            sd = math.sqrt(sq[c] / t)
            sd_sum += sd
            sd_max = max(sd_max, sd)
        o[b] = (top - rest) / noise
        o[b + 1] = (cm.max() - rest) / noise
        o[b + 2] = sd_sum / nc / noise
        o[b + 3] = sd_max / noise


@jit
def _sorted_level(fi, ranks, thr, o):
    """The level's mean, order statistics at ``ranks`` and maximum into ``o[0:4]`` (in heights) and the
    fractions of readings above the thresholds ``thr`` into ``o[6::3]``, from the sorted heights ``fi``."""
    total = fi.size
    o[0] = fi.sum() / total
    o[1] = fi[ranks[0]]
    o[2] = fi[ranks[1]]
    o[3] = fi[total - 1]
    for m in range(thr.size):
        o[6 + 3 * m] = (total - np.searchsorted(fi, thr[m], side="right")) / total


@jit
def _counted_level(ui, ranks, thr, o):
    """:func:`_sorted_level` from the counts of the whole-number heights ``ui`` ``(T, C)``."""
    t, nc = ui.shape
    total = t * nc
    lo = ui.min()
    hist = np.zeros(int(ui.max() - lo) + 1, dtype=np.int64)
    acc = 0.0
    for k in range(t):
        for c in range(nc):
            hist[int(ui[k, c] - lo)] += 1
            acc += ui[k, c]
    o[0] = acc / total
    counted(hist, 0, hist.size, lo, ranks, o[1:3])
    o[3] = lo + hist.size - 1
    for m in range(thr.size):
        above = 0
        for b in range(hist.size - 1, -1, -1):
            if lo + b <= thr[m]:
                break
            above += hist[b]
        o[6 + 3 * m] = above / total


@jit
def _median(x):
    """``numpy.median`` of ``x`` (reordered in place): the middle value, or the mean of the two middle
    ones (the largest below the middle, as :func:`touchbench.features.contact._median_last`)."""
    m = x.size // 2
    mid = select(x, m)  # x[m] the m-th smallest, nothing larger before it
    return mid if x.size % 2 else (x[:m].max() + mid) / 2.0


@jit
def _median_counted(x, counts):
    """:func:`_median` of whole numbers ``x`` from their counts (``counts``: scratch space), when
    their range fits it; else by selection."""
    lo = x.min()
    span = int(x.max() - lo) + 1
    if span > counts.size:
        return _median(x)
    counts[:span] = 0
    for v in x:
        counts[int(v - lo)] += 1
    m = x.size // 2
    below = -1
    acc = 0
    for b in range(span):
        acc += counts[b]
        if below < 0 and acc > m - 1:
            below = b
        if acc > m:
            return lo + b if x.size % 2 else ((lo + below) + (lo + b)) / 2.0
    return lo
