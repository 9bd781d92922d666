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

import numba
import numpy as np

from .order_kernels import counted
from .touch_kernels import jit

#: a loop run once per frame pair, inlined where it is called (a call per frame costs as much as its work)
inline = numba.njit(cache=True, nogil=True, inline="always")

#: a series of integers is counted (bins from its minimum to its maximum) when it spans fewer than
#: this many bins per reading plus ``_BINS_EXTRA``; a capture with a wider one is left to numpy
_BINS_PER_VALUE, _BINS_EXTRA = 4, 64
#: ``smmhh``'s counters are laid out in rows of a multiple of this many pixels (the bytes of the
#: counting loop's step: four vectors) and an integer pyramid video in rows of a multiple of
#: ``_INT_BLOCK`` (the int32 motion loop's step), the extra pixels never moving, so that no pixel
#: is left to a scalar tail
_PIXEL_BLOCK, _INT_BLOCK = 128, 32


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
            counted(hist, s0, nb, a, order, stats)
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
    counted(hist, 0, nb, np.float64(imin), ranks, stats)
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


@inline
def _motion(a, b, thr, mo, exact):
    """``mo[j]`` all ones where ``|a[j] - b[j]| > thr[j]`` (one frame pair of ``smmhh``), else 0, for the
    pixels of ``thr``. ``exact``: integer pixels whose differences fit int32 (compared in int32)."""
    for j in range(thr.size):
        th = thr[j]
        if exact:
            d = np.int32(a[j] - b[j])
            x = np.uint8(d > th) | np.uint8(np.int32(-d) > th)
        else:
            x = np.uint8(a[j] - b[j] > th) | np.uint8(b[j] - a[j] > th)
        mo[j] = np.uint8(0) - x  # unsigned: all ones


@inline
def _grow(mo, run, least, lens):
    """Each pixel's current motion run ``run`` (0 without motion) grown by ``mo`` (all ones: motion), held at
    ``lens[-1] + 1`` (so it fits the counters' dtype), and ``least[m]`` counting the pixels whose
    run reaches ``lens[m]`` frames."""
    top = lens[lens.size - 1]
    for j in range(run.size):
        r = run[j]
        run[j] = (r + (r <= top)) & mo[j]
    for m in range(lens.size):
        reach = lens[m]
        for j in range(run.size):
            least[m, j] += run[j] == reach


@jit
def _run_hist(vi, thr, skips, edges, exact, bufs, out_i):
    """``smmhh``'s row ``out_i`` of one capture's video ``vi`` ``(T, pixels)``: a run counts in bin
    ``m`` when it lasts exactly ``m + 1`` frames, in the last when at least ``max_len`` (the runs
    reaching each length counted, those of exactly ``m + 1`` the difference of two counts); ordered
    scale (pixels ``edges[k]..edges[k + 1]``), skip, run length, pixel. ``bufs``: :func:`_buffers`;
    the narrow counters are added to ``total`` every ``chunk`` frames, before they could wrap."""
    mo, run, least, lens, total, chunk = bufs
    t = vi.shape[0]
    max_len = lens.size
    for si in range(skips.size):
        s = skips[si]
        run[:] = 0
        total[:] = 0
        for k0 in range(0, max(t - s, 0), chunk):
            least[:] = 0
            for k in range(k0, min(k0 + chunk, t - s)):
                _motion(vi[k + s], vi[k], thr, mo, exact)
                _grow(mo, run, least, lens)
            total += least
        for g in range(edges.size - 1):
            a0, b0 = edges[g], edges[g + 1]
            base = a0 * skips.size * max_len + si * max_len * (b0 - a0)
            for m in range(max_len):
                for j in range(a0, b0):
                    c = total[m, j] - total[m + 1, j] if m < max_len - 1 else total[m, j]
                    out_i[base + m * (b0 - a0) + j - a0] = c


@jit
def _pool_index(levels):
    """For every pixel above the cells of the pyramid with ``levels`` (each level's rows and columns;
    every level but the last halves exactly), row-major, levels side by side: the 2 x 2 pixels of
    the level below that it sums (:func:`_pyramid`), unsigned (indices taken as they are)."""
    n = 0
    for g in range(1, levels.shape[0]):
        n += levels[g, 0] * levels[g, 1]
    index = np.empty((n, 4), dtype=np.uint64)
    src, q = 0, 0
    for g in range(1, levels.shape[0]):
        pw = levels[g - 1, 1]
        for y in range(levels[g, 0]):
            for x in range(levels[g, 1]):
                a = src + 2 * y * pw + 2 * x
                index[q, 0], index[q, 1], index[q, 2], index[q, 3] = a, a + 1, a + pw, a + pw + 1
                q += 1
        src += levels[g - 1, 0] * pw
    return index


@jit
def _pyramid(xi, index, vid):
    """The integer pyramid video ``vid`` ``(T, pixels)`` of one capture ``xi`` ``(T, cells)``: the
    cells, then each pooled pixel the sum of the 2 x 2 pixels of the level below (:func:`_pool_index`),
    row-major, levels side by side."""
    t, c = xi.shape
    for k in range(t):
        row, cells = vid[k], xi[k]
        for j in range(c):
            row[j] = cells[j]
        for q in range(index.shape[0]):
            row[np.uint64(c + q)] = row[index[q, 0]] + row[index[q, 1]] + row[index[q, 2]] + row[index[q, 3]]


@jit
def _buffers(p, lens):
    """The work arrays of :func:`_run_hist` for ``p`` pixels (a multiple of ``_PIXEL_BLOCK``) and run
    lengths ``lens`` (1..max_len, in the unsigned dtype of the counters: uint8 while ``max_len`` < 255)."""
    chunk = np.iinfo(lens.dtype).max
    return (np.zeros(p, lens.dtype), np.zeros(p, lens.dtype), np.zeros((lens.size, p), lens.dtype), lens,
            np.zeros((lens.size, p), np.int64), chunk)


@jit
def smmhh(x, levels, thr, skips, lens, edges, out):
    """``smmhh``'s run-length histograms ``out`` ``(N, columns)`` of the integer readings ``x``
    ``(N, T, H, W)`` (at most 16 bits, on a grid every pooling halves exactly), each capture's
    pyramid video built here in int32 (:func:`_pyramid`; ``thr`` each pixel's integer threshold on
    the sums: :func:`touchbench.features.gaus_smmhh.pyramid_video`'s equivalence), in rows padded
    to whole blocks of pixels that never move."""
    n, t = x.shape[:2]
    p = edges[-1]
    pm = -(-p // _INT_BLOCK) * _INT_BLOCK
    vid = np.zeros((t, pm), dtype=np.int32)
    thr_p = np.zeros(pm, dtype=np.int32)
    thr_p[:p] = thr
    bufs = _buffers(-(-p // _PIXEL_BLOCK) * _PIXEL_BLOCK, lens)
    index = _pool_index(levels)
    for i in range(n):
        _pyramid(x[i].reshape((t, x.shape[2] * x.shape[3])), index, vid)
        _run_hist(vid, thr_p, skips, edges, True, bufs, out[i])


@jit
def smmhh_video(video, thr, skips, lens, edges, out):
    """:func:`smmhh` of a pyramid video ``video`` ``(N, T, pixels)`` made by numpy (float64 means of
    :func:`touchbench.features.gaus_smmhh.pool2`), ``thr`` each pixel's threshold."""
    p = video.shape[2]
    bufs = _buffers(-(-p // _PIXEL_BLOCK) * _PIXEL_BLOCK, lens)
    for i in range(video.shape[0]):
        _run_hist(video[i], thr, skips, edges, False, bufs, out[i])


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
