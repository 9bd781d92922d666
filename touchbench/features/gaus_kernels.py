"""Compiled loops for the five Gaus et al. (2015) feature sets (``msd``, ``sd``, ``bmh``,
``smmhh``, ``lbptop``), used when numba is installed.

A sibling of :mod:`touchbench.features.touch_kernels` with the same rules: one capture at a time (a
capture's values never depend on its batch), the numpy code of each set stays the path without
numba and the reference (tests/test_gaus_kernels.py: within 1e-9 on every real HAART capture and on
edge cases). Order statistics, counts and comparisons are numpy's exactly (the same values
compared in the same dtype); only sums are taken in another order. Readings are read in their own
dtype and made float64 one at a time (exact for every integer up to 2**53 and float32).

Imported on first use (:func:`touchbench.core.compiled.kernels`: never without numba),
compiled once per machine (numba's on-disk cache).
"""

from __future__ import annotations

import numpy as np

from .touch_kernels import jit

#: a series of integers is counted (bins from its minimum to its maximum) when it spans fewer than
#: this many bins per reading plus ``_BINS_EXTRA``; a capture with a wider one is left to numpy
_BINS_PER_VALUE, _BINS_EXTRA = 4, 64


@jit
def _ends(xi, lo, hi, total, tv):
    """Minimum and maximum (in the readings' dtype), sum and total variation (sum of absolute
    consecutive differences, int64) of every column of the integer readings ``xi`` ``(T, P)``,
    frames outer."""
    t, p = xi.shape
    for j in range(p):
        lo[j] = hi[j] = xi[0, j]
        total[j] = xi[0, j]
        tv[j] = 0
    for k in range(1, t):
        for j in range(p):
            v = xi[k, j]
            lo[j] = min(lo[j], v)
            hi[j] = max(hi[j], v)
            total[j] += v
            tv[j] += abs(np.int64(v) - np.int64(xi[k - 1, j]))


@jit
def _counted(hist, s0, nb, lo, ranks, stats):
    """The order statistics ``ranks`` (ascending, 0-based) of a series held as counts
    ``hist[s0:s0 + nb]`` of the values ``lo + b`` into ``stats``."""
    cum = 0
    r = 0
    for b in range(nb):
        cum += hist[s0 + b]
        while r < ranks.size and ranks[r] < cum:
            stats[r] = lo + b
            r += 1


@jit
def _count_moments(hist, s0, nb, n, scale):
    """Second to fourth central moments (1/n) of a series held as counts ``hist[s0:s0 + nb]`` of
    the values ``lo + b``, scaled by its range (:meth:`SeriesCounts.moments`' sums)."""
    zs = 0.0
    for b in range(nb):
        if hist[s0 + b]:
            zs += hist[s0 + b] * (b / scale)
    zm = zs / n
    m2 = m3 = m4 = 0.0
    for b in range(nb):
        c = hist[s0 + b]
        if c:
            z = b / scale - zm
            cz2 = c * z * z
            m2 += cz2
            m3 += cz2 * z
            m4 += cz2 * z * z
    return m2 / n, m3 / n, m4 / n


@jit
def _msd_row(out, i, j, n, ends, q, central):
    """The twelve statistics of cell ``j`` of capture ``i`` into ``out`` ``(N, 12, P)``: ``ends``
    (min, max, sum, total variation), ``q`` its quartiles, ``central`` its scaled central moments."""
    lo, hi, total, tv = ends
    m2, m3, m4 = central
    const = hi == lo
    scale = 1.0 if const else hi - lo
    s2 = 1.0 if const else m2
    row = (lo, hi, total / n, q[0], q[1], q[2], total, tv, q[2] - q[0],
           0.0 if const else m2 * scale * scale * (n / (n - 1) if n > 1 else 0.0),
           0.0 if const else m3 / s2**1.5, 3.0 if const else m4 / (s2 * s2))
    for c in range(12):
        out[i, c, j] = row[c]


@jit
def _fill(xi, lo, start, hist):
    """Every column ``j`` of integer readings ``xi`` ``(T, P)`` counted into
    ``hist[start[j]:start[j + 1]]`` (value ``lo[j] + b`` in bin ``b``), frames outer."""
    t, p = xi.shape
    base = np.empty(p, dtype=np.int64)
    for j in range(p):
        base[j] = start[j] - np.int64(lo[j])
    hist[:start[p]] = 0
    for k in range(t):
        for j in range(p):
            hist[np.uint64(base[j] + xi[k, j])] += 1


@jit
def msd(x, order, at, fracs, out, ok):
    """``msd``'s statistics ``out`` ``(N, 12, P)`` of every cell's series along axis 1 of the integer
    readings ``x`` ``(N, T, P)``, counted (no sort): quartiles at the Hazen points (``order``: the
    order statistics the quartiles interpolate between, ascending; quartile ``m`` is
    ``a + fracs[m] * (b - a)`` with ``a``, ``b`` the statistics ``at[2m]``, ``at[2m + 1]`` of
    ``order``), moments of the series scaled by its range (:mod:`touchbench.features.numerics`'
    limits for a constant cell). A capture with a cell spanning too many bins is left out:
    ``ok[i]`` False, its row to be computed otherwise."""
    n, t, p = x.shape
    lo, hi = np.empty(p, x.dtype), np.empty(p, x.dtype)
    total, tv = np.empty(p, np.int64), np.empty(p, np.int64)
    stats, q = np.empty(order.size), np.empty(fracs.size)
    limit = _BINS_PER_VALUE * t + _BINS_EXTRA
    start = np.zeros(p + 1, dtype=np.int64)
    hist = np.zeros(p * limit, dtype=np.int32)
    for i in range(n):
        xi = x[i]
        _ends(xi, lo, hi, total, tv)
        ok[i] = True
        for j in range(p):
            span = np.float64(hi[j]) - np.float64(lo[j])
            ok[i] &= span < limit
            start[j + 1] = start[j] + int(span) + 1
        if not ok[i]:
            continue
        _fill(xi, lo, start, hist)
        for j in range(p):
            a, b = np.float64(lo[j]), np.float64(hi[j])
            s0, nb = start[j], start[j + 1] - start[j]
            _counted(hist, s0, nb, a, order, stats)
            central = _count_moments(hist, s0, nb, t, 1.0 if b == a else b - a)
            for m in range(fracs.size):
                c = stats[at[2 * m]]
                q[m] = c + fracs[m] * (stats[at[2 * m + 1]] - c) if fracs[m] else c
            _msd_row(out, i, j, t, (a, b, np.float64(total[j]), np.float64(tv[j])), q, central)


@jit
def _median(xi, imin, nb, ranks, hist):
    """Mean of the order statistics ``ranks`` (two) of all integer readings of ``xi`` ``(T, P)``,
    counted into ``hist[:nb]`` (``imin + b`` in bin ``b``)."""
    t, p = xi.shape
    stats = np.empty(2)
    hist[:nb] = 0
    base = -np.int64(imin)
    for k in range(t):
        for j in range(p):
            hist[np.uint64(base + xi[k, j])] += 1
    _counted(hist, 0, nb, np.float64(imin), ranks, stats)
    return (stats[0] + stats[1]) / 2.0


@jit
def _frame_ends(xi, fmin, fmax):
    """Every frame's minimum and maximum of ``xi`` ``(T, P)``."""
    t, p = xi.shape
    for k in range(t):
        a = b = xi[k, 0]
        for j in range(1, p):
            a = min(a, xi[k, j])
            b = max(b, xi[k, j])
        fmin[k], fmax[k] = a, b


@jit
def sd(x, off, fixed, has_fixed, lut, out, ok):
    """``sd``'s histograms: ``out`` ``(N, columns)`` int64 counts of frames of the integer readings
    ``x`` ``(N, T, P)``, each frame's count of cells in every condition (in ``conditions``' order;
    no touch ``x == min`` counted as ``x <= min``, high ``x >= max - off``: with ``off`` 0,
    ``x == max``; compared in float64 as numpy does) put in its column by ``lut`` (condition ``c``,
    count ``k`` -> ``lut[c * (P + 1) + k]``). The capture's median is counted; a capture whose
    readings span too many bins is left out: ``ok[i]`` False, its row to be computed otherwise."""
    n, t, p = x.shape
    fmin, fmax = np.empty(t, x.dtype), np.empty(t, x.dtype)
    ranks = np.array([(t * p - 1) // 2, (t * p) // 2])
    limit = _BINS_PER_VALUE * t * p + _BINS_EXTRA
    hist = np.zeros(limit, dtype=np.int32)
    n_cond = 6 if has_fixed else 5
    cnt = np.zeros(n_cond, dtype=np.int64)
    for i in range(n):
        xi = x[i]
        _frame_ends(xi, fmin, fmax)
        imin, imax = np.float64(fmin.min()), np.float64(fmax.max())
        ok[i] = imax - imin < limit
        if not ok[i]:
            continue
        imed = _median(xi, fmin.min(), int(imax - imin) + 1, ranks, hist)
        ihigh = imax - off
        for k in range(t):
            flo, fhigh = np.float64(fmin[k]), np.float64(fmax[k]) - off
            c0 = c1 = c2 = c3 = c4 = c5 = 0
            for j in range(p):
                v = np.float64(xi[k, j])
                c0 += v <= flo
                c1 += v <= imin
                c2 += v >= imed
                c3 += v >= fixed
                c4 += v >= fhigh
                c5 += v >= ihigh
            cnt[0], cnt[1], cnt[2] = c0, c1, c2
            if has_fixed:
                cnt[3] = c3
            cnt[n_cond - 2], cnt[n_cond - 1] = c4, c5
            for c in range(n_cond):
                out[i, lut[c * (p + 1) + cnt[c]]] += 1


@jit
def _motion_runs(a, b, thr, run, least, exact):
    """One frame pair of ``smmhh``: each pixel's current motion run ``run`` (0 without motion) grown
    by the motion ``|a - b| > thr``, and ``least[m]`` counting the pixels whose run reaches
    ``m + 1`` frames. ``exact``: integer pixels whose differences fit int32 (compared in int32,
    so the loop runs on eight pixels at once)."""
    one = np.int32(1)
    for j in range(run.size):
        th = thr[j]
        if exact:
            x = np.int32(np.int32(a[j] - b[j]) > th) | np.int32(np.int32(b[j] - a[j]) > th)
        else:
            x = np.int32(a[j] - b[j] > th) | np.int32(b[j] - a[j] > th)
        run[j] = np.int32((run[j] + one) * x)
    for m in range(least.shape[0]):
        reach = np.int32(m + 1)
        for j in range(run.size):
            least[m, j] = np.int32(least[m, j] + np.int32(run[j] == reach))


@jit
def _run_hist(vi, thr, skips, edges, exact, run, least, out_i):
    """``smmhh``'s row ``out_i`` of one capture's video ``vi`` ``(T, pixels)``: a run counts in bin
    ``m`` when it lasts exactly ``m + 1`` frames, in the last when at least ``max_len`` (the runs
    reaching each length counted, those of exactly ``m + 1`` the difference of two counts); ordered
    scale (pixels ``edges[k]..edges[k + 1]``), skip, run length, pixel."""
    t = vi.shape[0]
    max_len = least.shape[0]
    for si in range(skips.size):
        s = skips[si]
        run[:] = 0
        least[:] = 0
        for k in range(t - s):
            _motion_runs(vi[k + s], vi[k], thr, run, least, exact)
        for g in range(edges.size - 1):
            a0, b0 = edges[g], edges[g + 1]
            base = a0 * skips.size * max_len + si * max_len * (b0 - a0)
            for m in range(max_len):
                for j in range(a0, b0):
                    c = least[m, j] - least[m + 1, j] if m < max_len - 1 else least[m, j]
                    out_i[base + m * (b0 - a0) + j - a0] = c


@jit
def _pyramid(xi, levels, vid):
    """The integer pyramid video ``vid`` ``(T, pixels)`` of one capture ``xi`` ``(T, H, W)``: level
    0 the cells, each next level (``levels[k]``: its rows and columns) the sums of 2 x 2 blocks of
    the previous one (every level but the last halves exactly), row-major, levels side by side."""
    t, h, w = xi.shape
    for k in range(t):
        for y in range(h):
            for x in range(w):
                vid[k, y * w + x] = xi[k, y, x]
    src = 0
    for g in range(1, levels.shape[0]):
        ph, pw = levels[g - 1, 0], levels[g - 1, 1]
        lh, lw = levels[g, 0], levels[g, 1]
        dst = src + ph * pw
        for k in range(t):
            for y in range(lh):
                r0 = src + 2 * y * pw
                for x in range(lw):
                    c = r0 + 2 * x
                    vid[k, dst + y * lw + x] = vid[k, c] + vid[k, c + 1] + vid[k, c + pw] + vid[k, c + pw + 1]
        src = dst


@jit
def smmhh(x, levels, thr, skips, max_len, edges, out):
    """``smmhh``'s run-length histograms ``out`` ``(N, columns)`` of the integer readings ``x``
    ``(N, T, H, W)`` (at most 16 bits, on a grid every pooling halves exactly), each capture's
    pyramid video built here in int32 (:func:`_pyramid`; ``thr`` each pixel's integer threshold on
    the sums: :func:`touchbench.features.gaus_smmhh.pyramid_video`'s equivalence)."""
    n, t = x.shape[:2]
    p = edges[-1]
    vid = np.empty((t, p), dtype=np.int32)
    run = np.zeros(p, dtype=np.int32)
    least = np.zeros((max_len, p), dtype=np.int32)
    for i in range(n):
        _pyramid(x[i], levels, vid)
        _run_hist(vid, thr, skips, edges, True, run, least, out[i])


@jit
def smmhh_video(video, thr, skips, max_len, edges, out):
    """:func:`smmhh` of a pyramid video ``video`` ``(N, T, pixels)`` made by numpy (float64 means of
    :func:`touchbench.features.gaus_smmhh.pool2`), ``thr`` each pixel's threshold."""
    n, t, p = video.shape
    run = np.zeros(p, dtype=np.int32)
    least = np.zeros((max_len, p), dtype=np.int32)
    for i in range(n):
        _run_hist(video[i], thr, skips, edges, False, run, least, out[i])


@jit
def lbptop(flat, offsets, lo, hi, inner, counts, code):
    """``lbptop``'s code counts ``counts`` ``(N, 3, 2**P)``: every voxel ``m`` of ``flat[i, lo:hi]``
    (frames laid end to end) gets per plane the code whose bit ``k`` is
    ``flat[m + offsets[plane, k]] >= flat[m]`` (built in ``code``, unsigned integers of at least
    ``P`` bits); the codes of the voxels ``lo + inner`` are counted."""
    n = flat.shape[0]
    n_planes, n_points = offsets.shape
    size = hi - lo
    one = code.dtype.type(1)
    part = np.zeros((4, counts.shape[2]), dtype=np.int64)  # four tallies: a run of equal codes waits less
    for i in range(n):
        c = flat[i, lo:hi]
        for pl in range(n_planes):
            code[:] = 0
            for k in range(n_points):
                a = flat[i, lo + offsets[pl, k]:hi + offsets[pl, k]]
                bit = code.dtype.type(one << k)
                for m in range(size):
                    code[m] += bit * code.dtype.type(a[m] >= c[m])
            part[:] = 0
            for m in range(inner.size):
                part[m & 3, code[inner[m]]] += 1
            for b in range(counts.shape[2]):
                counts[i, pl, b] = part[0, b] + part[1, b] + part[2, b] + part[3, b]


@jit
def bmh(x, off, frame, out):
    """``bmh``'s cells ``out`` ``(N, P)`` of the readings ``x`` ``(N, T, P)``: 1 where a cell's value
    (made float64) reaches ``max - off`` in some frame, the maximum the capture's (``frame`` False)
    or each frame's own; taken in the readings' dtype and made float64 (rounding keeps the order)."""
    n, t, p = x.shape
    peak = np.empty(p, x.dtype)
    for i in range(n):
        xi = x[i]
        if frame:
            out[i, :] = 0.0
            for k in range(t):
                top = xi[k, 0]
                for j in range(1, p):
                    top = max(top, xi[k, j])
                thr = np.float64(top) - off
                for j in range(p):
                    if np.float64(xi[k, j]) >= thr:
                        out[i, j] = 1.0
            continue
        peak[:] = xi[0]
        for k in range(1, t):
            for j in range(p):
                peak[j] = max(peak[j], xi[k, j])
        thr = np.float64(peak.max()) - off
        for j in range(p):
            out[i, j] = 1.0 if np.float64(peak[j]) >= thr else 0.0
