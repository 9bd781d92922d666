"""Compiled statistics of frame series (``touch-rhythm``'s and ``touch-windows``'), used when numba
is installed: :func:`series_stats`, what the numpy code of
:func:`touchbench.features.touch_spectra._series_stats` computes, series by series (the values agree
within 1e-9, tests/test_touch_kernels.py). Each series takes two passes over its frames, every sum
in them an accumulator of its own (the same terms in the same order as one loop per sum would add
them: the same numbers), side by side, so that no sum waits on the one before it. Imported on
first use (:func:`touchbench.core.compiled.kernels`: never without numba), compiled once per
machine (numba's on-disk cache).
"""

from __future__ import annotations

import math

import numba
import numpy as np

jit = numba.njit(cache=True, nogil=True)
#: a helper inlined where it is called (numba's own inlining: the same operations in the loop)
inline = numba.njit(cache=True, nogil=True, inline="always")


@jit
def series_stats(x, xs, mean, p, f, starts, ends, order, lags):
    """Statistics of series ``x`` ``(N, K, T)`` given them sorted (``xs``), their means (numpy's sum
    of the sorted values: the mean-crossings of a series with values at its mean are the signs of its
    rounding) and their power spectra ``p`` ``(N, K, F)`` at the
    frequencies ``f``: ``(N, K, 22 + bands + len(lags))`` in the order of ``touch-rhythm``'s names
    (``order``: the ranks of the order statistics; ``starts``/``ends``: the bands' slices of ``f``)."""
    n, nk, t = x.shape
    nb = starts.size
    nf = f.size
    nl = len(lags)
    out = np.zeros((n, nk, 10 + len(order) + nb + 4 + nl))
    d = np.empty(t)
    zs = np.empty(t)
    acs = np.empty(nl + 8)  # the lags' sums, four at a time
    lognf = math.log(max(nf, 2))
    a = 2 + len(order)
    b = a + 12 + nb
    for i in range(n):
        for q in range(nk):
            o = out[i, q]
            s = x[i, q]
            srt = xs[i, q]
            mu = mean[i, q]
            lo, hi = srt[0], srt[t - 1]
            ac0, mad, tot, cross, zm = _first_pass(s, srt, mu, lo, hi, d, zs, lags, acs)
            m2, m3, m4, var = _second_pass(s, zs, zm / t, tot / (t - 1), d, lags, acs)
            for g in range(8, nl, 4):
                _lag_pass(d, lags, g, acs)
            sd = math.sqrt(ac0 / t)
            o[0] = mu
            o[1] = sd
            for m in range(len(order)):
                o[2 + m] = srt[order[m]]
            o[a] = hi
            if hi - lo != 0:
                m2 /= t
                o[a + 1], o[a + 2] = (m3 / t) / m2 ** 1.5, (m4 / t) / (m2 * m2)
            else:
                o[a + 1], o[a + 2] = 0.0, 3.0
            flat = sd <= 1e-12 * (1.0 + abs(mu))
            mad1 = mad / (t - 1)
            o[a + 3] = mad1
            o[a + 4] = math.sqrt(var / (t - 1))
            if not flat:
                o[a + 5] = sd / max(abs(mu), sd * 1e-6 + 1e-12)
                o[a + 6] = mad1 / sd
                o[a + 7] = cross / (t - 1)
                for m in range(nl):
                    if lags[m] < t:
                        o[b + m] = acs[m] / ac0
            _spectral(p[i, q, 1:], f, starts, ends, lognf, o[a + 8:a + 12 + nb])
    return out


@jit
def _lag(lags, m, t):
    """The ``m``-th lag, or ``t`` (no terms) past the last."""
    return lags[m] if m < len(lags) else t


@inline
def _four_lags(lags, g, t):
    """The lags ``g`` to ``g + 3`` (:func:`_lag`)."""
    return _lag(lags, g, t), _lag(lags, g + 1, t), _lag(lags, g + 2, t), _lag(lags, g + 3, t)


@inline
def _lag_terms(d, k, dk, l0, l1, l2, l3, a0, a1, a2, a3):
    """Four lags' sums of products of the centred values ``d`` with the term of frame ``k`` (``dk``)
    added where the lag reaches back that far."""
    if k >= l0:
        a0 += dk * d[k - l0]
    if k >= l1:
        a1 += dk * d[k - l1]
    if k >= l2:
        a2 += dk * d[k - l2]
    if k >= l3:
        a3 += dk * d[k - l3]
    return a0, a1, a2, a3


@jit
def _first_pass(s, srt, mu, lo, hi, d, zs, lags, acs):
    """One pass over a series ``s``: its centred values ``d`` and their energy, the sorted values
    scaled to 0..1 (``zs``, :func:`touchbench.features.numerics.moments`) and their sum, the first
    differences' absolute and plain sums, the mean-crossings and the first four lags' sums of
    products (into ``acs``)."""
    t = s.size
    scale = hi - lo if hi - lo != 0 else 1.0  # a constant series' moments are not read
    l0, l1, l2, l3 = _four_lags(lags, 0, t)
    ac0 = zm = mad = tot = 0.0
    a0 = a1 = a2 = a3 = 0.0
    cross = 0
    for k in range(t):
        dk = s[k] - mu
        d[k] = dk
        ac0 += dk * dk
        z = (srt[k] - lo) / scale
        zs[k] = z
        zm += z
        if k:
            dd = s[k] - s[k - 1]
            mad += abs(dd)
            tot += dd
            cross += (dk > 0) != (d[k - 1] > 0)
        a0, a1, a2, a3 = _lag_terms(d, k, dk, l0, l1, l2, l3, a0, a1, a2, a3)
    acs[0], acs[1], acs[2], acs[3] = a0, a1, a2, a3
    return ac0, mad, tot, cross, zm


@jit
def _second_pass(s, zs, zm, dmean, d, lags, acs):
    """The second pass over a series ``s``: the central moments of the scaled sorted values ``zs``
    (mean ``zm``), the squared deviations of the first differences from their mean ``dmean``, and
    the next four lags' sums of products of the centred values ``d`` (into ``acs``)."""
    t = s.size
    l0, l1, l2, l3 = _four_lags(lags, 4, t)
    m2 = m3 = m4 = var = 0.0
    a0 = a1 = a2 = a3 = 0.0
    for k in range(t):
        z = zs[k] - zm
        z2 = z * z
        m2 += z2
        m3 += z2 * z
        m4 += z2 * z2
        if k:
            e = s[k] - s[k - 1] - dmean
            var += e * e
        dk = d[k]
        a0, a1, a2, a3 = _lag_terms(d, k, dk, l0, l1, l2, l3, a0, a1, a2, a3)
    acs[4], acs[5], acs[6], acs[7] = a0, a1, a2, a3
    return m2, m3, m4, var


@jit
def _lag_pass(d, lags, g, acs):
    """The sums of products of the centred values ``d`` at lags ``g`` to ``g + 3`` (into ``acs``):
    past the eighth lag."""
    t = d.size
    l0, l1, l2, l3 = _four_lags(lags, g, t)
    a0 = a1 = a2 = a3 = 0.0
    for k in range(t):
        dk = d[k]
        a0, a1, a2, a3 = _lag_terms(d, k, dk, l0, l1, l2, l3, a0, a1, a2, a3)
    acs[g], acs[g + 1], acs[g + 2], acs[g + 3] = a0, a1, a2, a3


@jit
def _spectral(p, f, starts, ends, lognf, o):
    """Band fractions, peak and centroid frequency, normalised entropy, log power into ``o``."""
    nb = starts.size
    tot = 0.0
    cen = 0.0
    for k in range(p.size):
        tot += p[k]
        cen += p[k] * f[k]
    if tot <= 0:
        o[nb + 3] = math.log1p(0.0)
        return
    for b in range(nb):
        acc = 0.0
        for k in range(starts[b], ends[b]):
            acc += p[k]
        o[b] = acc / tot
    o[nb] = f[np.argmax(p)]
    ent = 0.0
    for k in range(p.size):
        qk = p[k] / tot
        if qk > 0:
            ent -= qk * math.log(qk)
    o[nb + 1] = cen / tot
    o[nb + 2] = ent / lognf
    o[nb + 3] = math.log1p(tot)
