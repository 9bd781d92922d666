"""Compiled loops for ``cell-rhythm`` (:mod:`touchbench.features.touch`), used when numba is installed:
a sibling of :mod:`touchbench.features.touch_kernels` (the same rules: one capture at a time,
numpy's values within 1e-9). The spectra are numpy's FFT of the same windowed series numpy's path
builds, and every sum these loops share with numpy's path adds the same terms in the same order, so
the compiled path gives the same numbers whatever its loops' layout: the loops walk the frames in
memory order, several accumulators side by side (cells, frames), each in its own order."""

from __future__ import annotations

import math

import numpy as np

from .motion_kernels import numpy_sum
from .touch_kernels import jit


@jit
def cell_series(s, hann, mean, out):
    """The cells' means ``mean`` ``(N, C)`` of the pressure ``s`` ``(N, T, C)`` and every cell's
    series less its mean, times the Hann window, into ``out`` ``(N, C, T)`` (0 for a constant
    series): numpy's ``centred_spectrum`` input, elementwise. A mean is numpy's mean of the cell's
    series: of more than one cell, a strided series, its frames summed in order from 0; of a single
    cell, a contiguous one, summed in numpy's pairwise order (:func:`numpy_sum`); over T."""
    n, t, nc = s.shape
    lo = np.empty(nc)
    hi = np.empty(nc)
    acc = np.empty(nc)
    halves, lefts = np.empty((3, 64), dtype=np.int64), np.empty(64)
    for i in range(n):
        si = s[i]
        m = mean[i]
        acc[:] = 0.0
        lo[:] = si[0]
        hi[:] = si[0]
        for k in range(t):  # the cells side by side
            for c in range(nc):
                v = si[k, c]
                lo[c] = v if v < lo[c] else lo[c]
                hi[c] = v if v > hi[c] else hi[c]
                acc[c] += v
        if nc == 1:
            acc[0] = 0.0 + numpy_sum(si[:, 0], 0, t, halves, lefts)
        for c in range(nc):
            m[c] = acc[c] / t
        oi = out[i]
        for k in range(t):  # the cells side by side (scattered stores: cheaper than gathered loads)
            hk = hann[k]
            for c in range(nc):
                oi[c, k] = (si[k, c] - m[c]) * hk
        for c in range(nc):
            if lo[c] == hi[c]:
                oi[c] = 0.0


@jit
def cell_pool(s, mean, amp, f, starts, ends, hann, h, w, floor, out):
    """``cell-rhythm``'s features into ``out`` ``(N, 20)`` from the pressure ``s`` ``(N, T, C)``, the
    cells' means ``(N, C)`` and the amplitudes of their spectra ``amp`` ``(N, C, F + 1)`` (numpy's
    ``abs`` of its FFT, DC first, left out; squared here as numpy squares them)."""
    n, t, nc = s.shape
    nb = starts.size
    nf = f.size
    pw = np.empty(nc)
    top = np.zeros(nc, dtype=np.int64)
    pooled = np.empty(nf)
    p = np.empty((nc, nf))
    x = np.empty(t)
    dev = np.empty((4, nc))  # each frame's deviations; squares, horizontal and vertical products
    up = np.empty(nc, dtype=np.int64)
    cross = np.empty(nc, dtype=np.int64)
    on = np.empty(nc, dtype=np.int64)
    for i in range(n):
        o = out[i]
        _powers(amp[i], p, pw, pooled, top)
        _deviations(s[i], mean[i], w, dev, up, cross)
        tot = pw.sum()
        o[:] = 0.0
        if tot > 0:
            for b in range(nb):
                acc = 0.0
                for k in range(starts[b], ends[b]):
                    acc += pooled[k]
                o[b] = acc / tot
            cen = 0.0
            for k in range(nf):
                cen += pooled[k] * f[k]
            o[nb] = cen / tot
            o[nb + 2] = f[top[np.argmax(pw)]] if nf else 0.0
            o[nb + 3] = _summed_power(s[i], mean[i], hann, x) / tot
            fpk = 0.0
            ent = 0.0
            mcr = 0.0
            for c in range(nc):
                wc = pw[c] / tot
                if nf:
                    fpk += f[top[c]] * wc
                if wc > 0:
                    ent -= wc * math.log(wc)
                mcr += cross[c] / (t - 1) * (pw[c] / tot)
            o[nb + 1] = fpk
            o[nb + 4] = ent
            o[nb + 5] = mcr
        o[nb + 6], o[nb + 7] = _neighbour_corr(dev, nc, w)
        o[nb + 8], o[nb + 9], o[nb + 10] = _blobs(s[i], h, w, floor, on)


@jit
def _powers(a, p, pw, pooled, top):
    """The cells' power spectra ``p`` ``(C, F)`` from their amplitudes ``a`` ``(C, F + 1)`` (DC left
    out), their totals ``pw`` (the frequencies in order, four cells side by side), their peaks'
    indices ``top`` (the first largest) and their sum ``pooled`` (the cells in order)."""
    nc, nf = p.shape
    pooled[:] = 0.0
    for c in range(nc):
        for k in range(nf):
            v = a[c, k + 1]
            p[c, k] = v * v
            pooled[k] += p[c, k]
        best = 0
        for k in range(1, nf):
            if p[c, k] > p[c, best]:
                best = k
        top[c] = best
    c = 0
    while c + 4 <= nc:
        a0 = a1 = a2 = a3 = 0.0
        for k in range(nf):
            a0 += p[c, k]
            a1 += p[c + 1, k]
            a2 += p[c + 2, k]
            a3 += p[c + 3, k]
        pw[c], pw[c + 1], pw[c + 2], pw[c + 3] = a0, a1, a2, a3
        c += 4
    for c in range(c, nc):
        acc = 0.0
        for k in range(nf):
            acc += p[c, k]
        pw[c] = acc


@jit
def _deviations(si, mean, w, dev, up, cross):
    """Frame by frame, the cells' deviations from their means: their sums of squares (``dev[1]``), of
    products with the next cell (``dev[2]``, across a row's end too: never read) and with the cell
    below (``dev[3]``), each in the frames' order, and the cells' mean-crossings ``cross`` (``up``:
    the previous frame's signs, 1 above the mean)."""
    t, nc = si.shape
    d = dev[0]
    sq = dev[1]
    ph = dev[2]
    pv = dev[3]
    dev[1:] = 0.0
    for c in range(nc):
        cross[c] = 0
        up[c] = 1 if si[0, c] - mean[c] > 0 else 0
    for k in range(t):
        for c in range(nc):
            dc = si[k, c] - mean[c]
            d[c] = dc
            sq[c] += dc * dc
            now = 1 if dc > 0 else 0
            cross[c] += now ^ up[c]
            up[c] = now
        for c in range(nc - 1):
            ph[c] += d[c] * d[c + 1]
        for c in range(nc - w):
            pv[c] += d[c] * d[c + w]


@jit
def _summed_power(si, mean, hann, x):
    """The power (DC left out) of the sum of the cells' mean-removed series, mean removed and Hann
    windowed, by Parseval's theorem: the sum of squares less the DC (and half the Nyquist bin)."""
    t, nc = si.shape
    k = 0
    while k + 4 <= t:  # each frame's sum in the cells' order; four frames side by side
        a0 = a1 = a2 = a3 = 0.0
        for c in range(nc):
            m = mean[c]
            a0 += si[k, c] - m
            a1 += si[k + 1, c] - m
            a2 += si[k + 2, c] - m
            a3 += si[k + 3, c] - m
        x[k], x[k + 1], x[k + 2], x[k + 3] = a0, a1, a2, a3
        k += 4
    for k in range(k, t):
        acc = 0.0
        for c in range(nc):
            acc += si[k, c] - mean[c]
        x[k] = acc
    if x.max() == x.min():
        return 0.0
    mu = x.sum() / t
    energy, dc, nyq = 0.0, 0.0, 0.0
    for k in range(t):
        y = (x[k] - mu) * hann[k]
        energy += y * y
        dc += y
        nyq += -y if k % 2 else y
    rest = t * energy - dc * dc
    return (rest + nyq * nyq) / 2.0 if t % 2 == 0 else rest / 2.0


@jit
def _neighbour_corr(dev, nc, w):
    """Correlation of horizontally and vertically adjacent cells, weighted by their deviations
    (:func:`_deviations`' sums)."""
    sd = np.sqrt(dev[1])
    res = np.zeros(2)
    for m in range(2):
        num = 0.0
        den = 0.0
        for c in range(nc):
            if m == 0 and (c + 1) % w == 0 or m == 1 and c + w >= nc:
                continue
            wgt = sd[c] * sd[c + 1 if m == 0 else c + w]
            if wgt > 0:
                num += dev[2 + m, c] / wgt * wgt
            den += wgt
        res[m] = num / den if den > 0 else 0.0
    return res[0], res[1]


@jit
def _blobs(si, h, w, floor, on):
    """Blobs per frame (nodes minus 4-neighbour edges of the cells above half the frame's maximum):
    mean over active frames, maximum, mean number of such cells."""
    t, nc = si.shape
    comp_sum = 0
    comp_max = -nc
    nodes_sum = 0
    active = 0
    for k in range(t):
        row = si[k]
        m0 = m1 = m2 = m3 = row[0]  # the largest value, four cells side by side
        c = 0
        while c + 4 <= nc:
            m0 = row[c] if row[c] > m0 else m0
            m1 = row[c + 1] if row[c + 1] > m1 else m1
            m2 = row[c + 2] if row[c + 2] > m2 else m2
            m3 = row[c + 3] if row[c + 3] > m3 else m3
            c += 4
        for c in range(c, nc):
            m0 = row[c] if row[c] > m0 else m0
        thr = max(0.5 * max(max(m0, m1), max(m2, m3)), floor)
        nodes = 0
        for c in range(nc):
            b = 1 if row[c] > thr else 0
            on[c] = b
            nodes += b
        edges = 0
        for c in range(1, nc):  # along the rows: every pair of cells in order, less those across a row's end
            edges += on[c] & on[c - 1]
        for c in range(w, nc, w):
            edges -= on[c] & on[c - 1]
        for c in range(w, nc):
            edges += on[c] & on[c - w]
        comp = nodes - edges if nodes > 0 else 0
        active += nodes > 0
        comp_sum += comp
        comp_max = max(comp_max, comp)
        nodes_sum += nodes
    nact = max(active, 1)
    return comp_sum / nact, float(comp_max if t else 0), nodes_sum / nact
