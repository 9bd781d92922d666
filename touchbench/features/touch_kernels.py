"""Compiled loops for touchbench's own feature sets (``touch-rhythm``, ``contact-motion``; ``cell-rhythm``'s
in :mod:`touchbench.features.cell_kernels`), used when numba is installed.

Each kernel computes, for one capture at a time, what the vectorised numpy code of
:mod:`touchbench.features.touch` computes with many whole-array passes: one loop over the
capture's frames and cells instead. The numpy code stays the path without numba (and the reference
the kernels are tested against, tests/test_touch_kernels.py): the values agree within 1e-9 (sums
are taken in another order). A capture's values never depend on the other captures of its batch:
the loops run capture by capture.

Imported on first use (:func:`touchbench.core.compiled.kernels`: never without numba),
compiled once per machine (numba's on-disk cache).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .motion_kernels import contact_spectra, contact_tracks, contact_weights  # noqa: F401  (contact-motion's)
from .motion_kernels import numpy_sum
from .order_kernels import counted

jit = numba.njit(cache=True, nogil=True)


@jit
def pressure(x, k, integral, c, s, base):
    """The common preprocessing of :func:`touchbench.features.touch._pressure` for readings ``x``
    ``(N, T, C)`` (``integral``: whole numbers): the values ``c`` as float64, each cell's baseline
    ``base`` ``(N, C)``, its ``k``-th smallest reading (0-based), and the pressure
    ``s = max(c - base, 0)``, elementwise as numpy computes them. The baseline is numpy's
    partition's value exactly: read off the cells' counts of each value where the readings are
    whole numbers of a short span, else selected frame by frame (:func:`_lowest`)."""
    n, t, nc = x.shape
    lo = np.empty(nc)
    hi = np.empty(nc)
    counts = np.zeros((nc, 4 * t + 1), dtype=np.int32)
    for i in range(n):
        ci = c[i]
        for j in range(nc):
            lo[j] = hi[j] = x[i, 0, j]
        for kk in range(t):
            for j in range(nc):
                v = float(x[i, kk, j])
                ci[kk, j] = v
                lo[j] = min(lo[j], v)
                hi[j] = max(hi[j], v)
        if integral and (hi - lo).max() < counts.shape[1]:
            _counted(ci, lo, hi, k, counts, base[i])
        else:
            _lowest(ci, k, base[i])
        bi = base[i]
        si = s[i]
        for kk in range(t):
            for j in range(nc):
                si[kk, j] = max(ci[kk, j] - bi[j], 0.0)


@jit
def _counted(ci, lo, hi, k, counts, out):
    """Each cell's ``k``-th smallest of whole numbers ``ci`` ``(T, C)`` from its counts of each value
    (``lo``, ``hi``: the cells' extremes, their span within ``counts``)."""
    t, nc = ci.shape
    for j in range(nc):
        counts[j, :int(hi[j] - lo[j]) + 1] = 0
    for kk in range(t):
        for j in range(nc):
            counts[j, int(ci[kk, j] - lo[j])] += 1
    rank = np.full(1, k)
    for j in range(nc):
        counted(counts[j], 0, int(hi[j] - lo[j]) + 1, lo[j], rank, out[j:j + 1])


@jit
def _lowest(ci, k, out):
    """Each cell's ``k``-th smallest of ``ci`` ``(T, C)``: the cells keep their ``k + 1`` smallest
    values so far, sorted, frame by frame (a value above the largest of them costs one comparison)."""
    t, nc = ci.shape
    low = np.empty((nc, k + 1))
    for kk in range(t):
        for j in range(nc):
            v = ci[kk, j]
            top = min(kk, k + 1)  # values held
            if top == k + 1:
                if v >= low[j, k]:
                    continue
                top = k
            m = top
            while m > 0 and low[j, m - 1] > v:
                low[j, m] = low[j, m - 1]
                m -= 1
            low[j, m] = v
    for j in range(nc):
        out[j] = low[j, k]


@jit
def rhythm_frames(s, c, base, h, w, floor, area_rel, ranks):
    """``touch-rhythm``'s eleven frame series ``(N, 11, T)`` and its capture scalars ``(N, 33)``
    from the pressure ``s``, the values ``c`` (both ``(N, T, C)``) and the baseline ``(N, C)``."""
    n, t, nc = s.shape
    series = np.zeros((n, 11, t))
    extra = np.zeros((n, 7 + 3 * (len(ranks) + 1) + 2))
    yy = np.empty(nc)
    xx = np.empty(nc)
    for j in range(nc):
        yy[j] = j // w
        xx[j] = j % w
    y2 = yy * yy
    x2 = xx * xx
    cm = np.empty(nc)
    csd = np.empty(nc)
    cdf = np.empty(nc)
    psa = np.empty(t)
    gh = np.zeros(max(nc - 1, 0))
    gv = np.zeros(max(nc - w, 0))
    for i in range(n):
        gh[:] = 0.0
        gv[:] = 0.0
        cm[:] = 0.0
        cdf[:] = 0.0
        si = s[i]
        out = series[i]
        peak = si[0, 0]  # the largest pressure (its first, for ties), in the same walk
        for k in range(t):
            row = si[k]
            crow = c[i, k]
            p_ = 0.0
            ps = 0.0
            m_ = crow[0]
            my = 0.0
            mx = 0.0
            myy = 0.0
            mxx = 0.0
            for j in range(nc):
                v = row[j]
                cv = crow[j]
                p_ += cv
                ps += v
                m_ = max(m_, cv)
                if v > peak:
                    peak = v
                my += v * yy[j]
                mx += v * xx[j]
                myy += v * y2[j]
                mxx += v * x2[j]
            _cell_sums(row, si[max(k - 1, 0)], k, w, cm, cdf, gh, gv)
            out[0, k] = p_
            psa[k] = ps
            out[3, k] = m_
            if ps <= 0:
                out[5, k] = (h - 1) / 2.0
                out[6, k] = (w - 1) / 2.0
            else:
                cy = my / ps
                cx = mx / ps
                out[5, k] = cy
                out[6, k] = cx
                out[7, k] = math.sqrt(max(myy / ps - cy * cy, 0.0))
                out[8, k] = math.sqrt(max(mxx / ps - cx * cx, 0.0))
        thr = max(area_rel * peak, floor)
        grad = gv.sum()
        for j in range(nc - 1):
            if (j + 1) % w:  # neighbours along a row
                grad += gh[j]
        _rhythm_series(out, psa, thr)
        _rhythm_cells(si, base[i], out, psa, extra[i], ranks, peak, thr, grad, cm, csd, cdf)
    return series, extra


@jit
def _cell_sums(row, prev, k, w, cm, cdf, gh, gv):
    """A frame's pressure ``row`` (the one before: ``prev``) into each cell's sum ``cm``, absolute
    change ``cdf`` (from the second frame ``k``), absolute differences with the cell to its right
    ``gh`` and below ``gv``."""
    nc = row.size
    for j in range(nc):
        cm[j] += row[j]
    if k:
        for j in range(nc):
            cdf[j] += abs(row[j] - prev[j])
    right = row[1:]
    for j in range(nc - 1):
        gh[j] += abs(right[j] - row[j])
    below = row[w:]
    for j in range(nc - w):
        gv[j] += abs(below[j] - row[j])


@jit
def _rhythm_series(out, psa, thr):
    """Speed, log and level-normalised pressure sum ``psa``, change of P."""
    t = psa.size
    mean_ps = psa.sum() / t
    for k in range(t):
        lo, hi = max(k - 1, 0), min(k + 1, t - 1)
        vy = (out[5, hi] - out[5, lo]) / (hi - lo)
        vx = (out[6, hi] - out[6, lo]) / (hi - lo)
        ps = psa[k]
        out[1, k] = math.log1p(ps)
        out[9, k] = math.hypot(vx, vy) if ps > thr else 0.0
        out[2, k] = ps / mean_ps if mean_ps > 0 else 0.0
        if k:
            out[10, k] = abs(out[0, k] - out[0, k - 1])


@jit
def _rhythm_cells(si, base, out, ps, ex, ranks, peak, thr, grad, cm, csd, cdf):
    """``touch-rhythm``'s capture scalars (``ps``: the frames' pressure sums) and its frames' areas
    (the cells above ``thr``), with the cells' deviations from their means in the same walk."""
    t, nc = si.shape
    bsum = 0.0
    bmax = base[0]
    for j in range(nc):
        bsum += base[j]
        bmax = max(bmax, base[j])
        csd[j] = 0.0
    for j in range(nc):
        cm[j] /= t
    for k in range(t):
        row = si[k]
        a_ = 0
        for j in range(nc):
            v = row[j]
            d = v - cm[j]
            csd[j] += d * d
            a_ += v > thr
        out[4, k] = a_
    dsum = 0.0
    for j in range(nc):
        csd[j] = math.sqrt(csd[j] / t)
        dsum += cdf[j]
        cdf[j] /= t - 1
    pmax = ps.max()
    tot = ps.sum()
    act = 0.0
    path = 0.0
    for k in range(t):
        if ps[k] > 0.2 * pmax:
            act += 1.0
        if k:
            path += math.hypot(out[6, k] - out[6, k - 1], out[5, k] - out[5, k - 1])
    ex[0] = bsum / nc
    ex[1] = bmax
    ex[2] = peak
    ex[3] = math.log1p(peak)
    ex[4] = act / t if pmax > 0 else 0.0
    ex[5] = path
    ex[6] = math.hypot(out[6, t - 1] - out[6, 0], out[5, t - 1] - out[5, 0])
    at = 7
    for v in (cm, csd, cdf):
        srt = np.sort(v)
        for r in ranks:
            ex[at] = srt[r]
            at += 1
        ex[at] = srt.sum()
        at += 1
    mp = tot / t
    ex[at] = grad / t / mp if mp > 0 else 0.0
    ex[at + 1] = dsum / tot if tot > 0 else 0.0


@jit
def windowed(s, hann, out):
    """Every series ``s[i, c]`` of ``(N, M, T)`` (C-ordered) less its mean, times the Hann window,
    into ``out`` ``(N, M, T)`` (0 for a constant series): numpy's ``centred_spectrum`` input,
    elementwise, so the same numbers (``touch-rhythm``'s series; the cells' are ``cell_kernels.cell_series``').
    The mean is numpy's ``mean(axis=-1)``: the series summed in numpy's order (:func:`numpy_sum`)
    over its length."""
    n, m, t = s.shape
    halves, lefts = np.empty((3, 64), dtype=np.int64), np.empty(64)
    for i in range(n):
        for c in range(m):
            mean = (0.0 + numpy_sum(s[i, c], 0, t, halves, lefts)) / t  # numpy sums from 0
            lo = s[i, c, 0]
            hi = lo
            for k in range(t):
                v = s[i, c, k]
                lo = min(lo, v)
                hi = max(hi, v)
                out[i, c, k] = (v - mean) * hann[k]
            if lo == hi:
                out[i, c, :] = 0.0
