"""Compiled loops for ``contact-evidence`` (:mod:`touchbench.features.contact`), used when numba is
installed: a sibling of :mod:`touchbench.features.touch_kernels` (the same rules: one capture at a
time, numpy's values within 1e-9, numpy's thresholds exactly)."""

from __future__ import annotations

import math

import numpy as np

from .touch_kernels import jit


@jit
def evidence(u, flat, floor, units, quiet, ranks, full, integral, out):
    """``contact-evidence``'s features into ``out`` ``(N, 6 + 3 * units + 4)`` from the heights ``u``
    ``(N, T, C)``, them sorted per capture ``flat`` ``(N, T * C)``, the noise floor's lower bound
    ``floor``, the ``quiet`` cells' count, the ranks of the level's order statistics and the full scale
    (``integral``: every height is a whole number, so a cell's median is read off its counts).
    Medians, the quiet cells and the thresholds are numpy's values exactly (a reading is counted
    above a threshold by comparison)."""
    n, t, nc = u.shape
    col = np.empty(t)
    med = np.empty(nc)
    mads = np.empty(quiet)
    cm = np.empty(nc)
    counts = np.zeros(4 * t + 1, dtype=np.int64)
    for i in range(n):
        ui = u[i]
        o = out[i]
        for c in range(nc):
            col[:] = ui[:, c]
            med[c] = _median_counted(col, counts) if integral else _median(col)
        qcells = np.argsort(med, kind="mergesort")[:quiet]
        for m in range(quiet):
            c = qcells[m]
            for k in range(t):
                col[k] = abs(ui[k, c] - med[c])
            mads[m] = _median(col)
        rest = _median(med[qcells])
        noise = max(1.4826 * _median(mads), floor)
        cm[:] = 0.0
        for k in range(t):
            for c in range(nc):
                cm[c] += ui[k, c]
        cm /= t
        fi = flat[i]
        total = fi.size
        o[0] = fi.sum() / total / full
        o[1] = fi[ranks[0]] / full
        o[2] = fi[ranks[1]] / full
        o[3] = fi[total - 1] / full
        o[4] = cm.min() / full
        o[5] = cm.max() / full
        for m in range(units.size):
            thr = rest + noise * units[m]
            o[6 + 3 * m] = (total - np.searchsorted(fi, thr, side="right")) / total
            frames = 0
            for k in range(t):
                frames += ui[k].max() > thr
            o[7 + 3 * m] = frames / t
            o[8 + 3 * m] = (cm > thr).sum() / nc
        b = 6 + 3 * units.size
        sd_sum = 0.0
        sd_max = 0.0
        for c in range(nc):
            acc = 0.0
            for k in range(t):
                d = ui[k, c] - cm[c]
                acc += d * d
            sd = math.sqrt(acc / t)
            sd_sum += sd
            sd_max = max(sd_max, sd)
        o[b] = (fi[total - 1] - rest) / noise
        o[b + 1] = (cm.max() - rest) / noise
        o[b + 2] = sd_sum / nc / noise
        o[b + 3] = sd_max / noise


@jit
def _median(x):
    """``numpy.median`` of ``x`` (reordered in place): the middle value, or the mean of the two middle
    ones (the largest below the middle, as :func:`touchbench.features.contact._median_last`)."""
    m = x.size // 2
    lo, hi = 0, x.size - 1
    while lo < hi:  # Hoare's selection: x[m] the m-th smallest, nothing larger before it
        pivot = x[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while x[i] < pivot:
                i += 1
            while x[j] > pivot:
                j -= 1
            if i <= j:
                x[i], x[j] = x[j], x[i]
                i += 1
                j -= 1
        if m <= j:
            hi = j
        elif m >= i:
            lo = i
        else:
            break
    return x[m] if x.size % 2 else (x[:m].max() + x[m]) / 2.0


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
