"""Compiled loops for ``contact-motion`` (:mod:`touchbench.features.touch`), used when numba is
installed: its contact weights, tracks and spectra's summaries, one capture at a time (what the
numpy code of ``ContactMotion`` computes with whole-array passes; the values agree within 1e-9,
tests/test_touch_kernels.py). Reached through :mod:`touchbench.features.touch_kernels` (imported on
first use, never without numba), compiled once per machine (numba's on-disk cache).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .order_kernels import select

jit = numba.njit(cache=True, nogil=True)


@jit
def contact_tracks(ws, num, area, h, w, out, pos, act):
    """``contact-motion``'s features without spectra into ``out`` ``(N, R, 18)`` (columns 0-9), the
    position along the axis of motion into ``pos`` and the on/off activity into ``act`` (both
    ``(N, R, T)``), from each threshold's contact weight ``ws`` ``(N, R, T)``, the weighted row and
    column ``num`` ``(M, 2)`` of each frame with contact (``ws > 0``; in the order of
    :func:`contact_weights`' rows) and the areas ``(N, R, T)``. The weighted rows and columns come
    from numpy: the reversals count signs of position changes, which for a position that does not
    move are the signs of rounding (the same ones as numpy's)."""
    n, nr, t = ws.shape
    cyx = np.empty((2, t))
    j = 0
    for i in range(n):
        for r in range(nr):
            j = _track(ws[i, r], num, j, cyx, area[i, r], h, w, out[i, r], pos[i, r], act[i, r])


@jit
def _track(ws, num, j, cyx, area, h, w, o, pos, act):
    """One threshold's track: activity, onsets, area, speed, range, path, reversals; its frames with
    contact take the rows of ``num`` from ``j`` on (the next row is returned); ``cyx`` ``(2, T)``
    holds the position."""
    t = ws.size
    nact = 0
    msum = np.zeros(2)
    for k in range(t):
        if ws[k] > 0:
            act[k] = 1.0
            nact += 1
            for a in range(2):
                cyx[a, k] = num[j, a] / ws[k]
                msum[a] += cyx[a, k]
            j += 1
        else:
            act[k] = 0.0
    for a in range(2):
        fill = msum[a] / max(nact, 1) if nact > 0 else ((h - 1) / 2.0 if a == 0 else (w - 1) / 2.0)
        for k in range(t):
            if ws[k] <= 0:
                cyx[a, k] = fill
    rng = np.empty(2)
    hi, lo = int(round(0.95 * (t - 1))), int(round(0.05 * (t - 1)))
    for a in range(2):
        srt = cyx[a].copy()
        top = select(srt, hi)  # leaves the values below it first: the lower rank among them
        rng[a] = top - (select(srt[:hi], lo) if lo < hi else top)
    major = 0 if rng[0] >= rng[1] else 1
    sp = np.zeros(t - 1)
    onsets = 0
    nboth = 0
    spsum = 0.0
    nz = 0
    rev = 0
    prev = 0.0
    for k in range(t - 1):
        both = act[k] > 0 and act[k + 1] > 0
        onsets += act[k + 1] > 0 and not act[k] > 0
        sg = 0.0
        if both:
            nboth += 1
            sp[k] = math.hypot(cyx[1, k + 1] - cyx[1, k], cyx[0, k + 1] - cyx[0, k])
            spsum += sp[k]
            sg = np.sign(cyx[major, k + 1] - cyx[major, k])
        nz += sg != 0
        if k and sg * prev < 0:
            rev += 1
        prev = sg
    o[0] = nact / t
    o[1] = onsets
    o[2] = area.sum() / max(nact, 1)
    o[3] = area.max()
    o[4] = spsum / max(nboth, 1)
    o[5] = select(sp, int(round(0.9 * (t - 2))))  # the last use of sp
    o[6] = rng[0]
    o[7] = rng[1]
    o[8] = spsum
    o[9] = rev / max(nz, 1) if nz > 0 else 0.0
    pos[:] = cyx[major]
    return j


@jit
def contact_weights(s, rank, rel, floor, wt, area, peak, ws):
    """``contact-motion``'s robust peak ``(N,)`` (the order statistic ``rank`` of the frames' maximum
    pressure), each threshold's contact weights, the pressure above ``max(rel[r] * peak, floor)``
    clipped at 0, their nonzero counts ``area`` and their sums ``ws`` (both ``(N, R, T)``): the
    operations of the numpy path, elementwise, and each sum numpy's (:func:`numpy_sum`), so the
    same numbers. The weights of the frames with contact (a nonzero count) go to the rows of ``wt``
    ``(N * R * T, C)``, one after another (capture, threshold, frame); their number is returned
    (the other frames' weights are zeros, their sums +0.0 in any order)."""
    n, t, nc = s.shape
    top = np.empty(t)
    halves, lefts = np.empty((3, 64), dtype=np.int64), np.empty(64)
    m = 0
    for i in range(n):
        for k in range(t):
            top[k] = s[i, k].max()
        peak[i] = select(top, rank)
        for r in range(rel.size):
            thr = max(peak[i] * rel[r], floor)
            for k in range(t):
                cnt = 0
                row = wt[m]
                for c in range(nc):
                    v = max(s[i, k, c] - thr, 0.0)
                    row[c] = v
                    cnt += v != 0.0
                area[i, r, k] = cnt
                ws[i, r, k] = 0.0
                if cnt:
                    ws[i, r, k] += numpy_sum(row, 0, nc, halves, lefts)  # numpy's reduction starts from 0
                    m += 1
    return m


@jit
def numpy_sum(a, lo, n, halves, lefts):
    """The sum of ``a[lo:lo + n]`` in the order numpy's ``add.reduce`` adds a contiguous float64 row
    (its pairwise summation): up to 128 values a block (:func:`_block`); more, the sum of the first
    half (a multiple of 8 values) plus the sum of the rest, each summed so. Walked without recursion
    (numba's cache cannot hold a recursive loop): ``halves`` ``(3, 64)`` int64 and ``lefts`` ``(64,)``
    hold the pending halves (start, size, whether the first half is summed) and the first halves'
    sums. The same number as numpy's ``sum`` of the row, bit for bit (tests/test_touch_kernels.py
    checks it on many lengths)."""
    top = -1
    at, size = lo, n
    while True:
        while size > 128:  # down the first halves, the second ones pending
            half = size // 2 - (size // 2) % 8
            top += 1
            halves[0, top], halves[1, top], halves[2, top] = at + half, size - half, 0
            size = half
        v = _block(a, at, size)
        while top >= 0 and halves[2, top] == 1:  # a second half summed: first + second
            v = lefts[top] + v
            top -= 1
        if top < 0:
            return v
        lefts[top] = v  # a first half summed: now its second half
        halves[2, top] = 1
        at, size = halves[0, top], halves[1, top]


@jit
def _block(a, lo, n):
    """numpy's sum of ``a[lo:lo + n]``, up to 128 values: under 8 one after another; else eight
    running sums over the values eight apart, combined in pairs, then the rest one after another."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@jit
def contact_spectra(p, f, starts, ends, tracks, peak, out):
    """``contact-motion``'s rows ``out`` ``(N, R * 18 + 1)``: each threshold's ``tracks`` columns 0-9
    (:func:`contact_tracks`), then from the power spectra ``p`` ``(2, N, R, F)`` of the position
    along the axis of motion and of the on/off activity (numpy's, so the peaks are numpy's): the
    position's peak and centroid frequency and band fractions, the activity's peak and centroid
    frequency (0 without power); last log(1 + peak)."""
    _, n, nr, nf = p.shape
    nb = starts.size
    for i in range(n):
        for r in range(nr):
            o = out[i, r * (10 + 4 + nb):(r + 1) * (10 + 4 + nb)]
            o[:10] = tracks[i, r, :10]
            for m in range(2):
                q = p[m, i, r]
                tot = q.sum()
                at = 10 if m == 0 else 12 + nb
                o[at] = f[np.argmax(q)] if tot > 0 and nf else 0.0
                cen = 0.0
                for k in range(nf):
                    cen += q[k] * f[k]
                o[at + 1] = cen / tot if tot > 0 else 0.0
                for b in range(nb if m == 0 else 0):
                    acc = 0.0
                    for k in range(starts[b], ends[b]):
                        acc += q[k]
                    o[12 + b] = acc / tot if tot > 0 else 0.0
        out[i, -1] = math.log1p(peak[i])
