"""Shared numerics for the feature sets: float64 moments, quantiles and
the limits we define where a statistic is undefined.

Every function reduces along the LAST axis and is vectorised over the
leading ones, so a feature set computes a statistic for every cell of every
capture of a batch in one call.

Limits (the choices every feature set inherits; each set's docstring refers
here):

- **Constant series** (max == min exactly, which includes a single sample):
  variance, standard deviation, range, total variation = 0; skewness =
  ``SKEW_CONSTANT`` = 0 (a point mass is symmetric); kurtosis =
  ``KURT_CONSTANT`` = 3, the Pearson kurtosis of a normal distribution,
  i.e. excess kurtosis 0 (pandas' convention for a zero variance; MATLAB
  and scipy return NaN). No value is the limit (a symmetric two-point
  series has kurtosis 1 at every scale, a Gaussian 3): 3 is the neutral
  choice that does not make a constant cell look heavy- or light-tailed.
- **Sample variance of one value** (ddof=1, n=1): 0 (MATLAB's ``var`` of a
  scalar).
- Constancy is tested exactly on the input values, not on a computed
  variance, so the limit does not depend on rounding in the mean.
- Higher moments are computed on the series divided by its range, so tiny
  (even subnormal) but non-constant series give finite skewness and
  kurtosis: the series is shifted to its minimum and divided by its range
  before centring, so it lies in [0, 1], some deviation from its mean is
  at least 1/2 and the second moment is at least 1/(4n).
"""

from __future__ import annotations

import functools
from typing import Callable, Sequence

import numpy as np

SKEW_CONSTANT = 0.0
KURT_CONSTANT = 3.0


def as_f64(a: np.ndarray) -> np.ndarray:
    """``a`` as float64 (exact for every integer dtype up to 2**53 and float32)."""
    return np.asarray(a, dtype=np.float64)


def as_integers(x: np.ndarray) -> np.ndarray | None:
    """The readings ``x`` as integers of at most 32 bits, or None: integers of up to 4 bytes as they
    are (booleans as uint8), floats that are all whole numbers within int32 as int32 (the same
    values); None for other floats and wider integers."""
    if x.dtype.kind == "b":
        return x.view(np.uint8)
    if x.dtype.kind == "f":
        whole = bool(x.size) and np.abs(x).max() < 2**31 and np.array_equal(x, np.rint(x))
        return x.astype(np.int32) if whole else None
    return x if x.dtype.itemsize <= 4 else None


def sort_last(x: np.ndarray) -> np.ndarray:
    """``numpy.sort`` along the last axis, by radix sort for integers of up to 16 bits (numpy's
    ``kind="stable"`` for them; several times faster than its quicksort there). The sorted values are
    the same whatever the algorithm."""
    small_int = x.dtype.kind in "biu" and x.dtype.itemsize <= 2
    return np.sort(x, axis=-1, kind="stable" if small_int else None)


def moments(x: np.ndarray, *, ddof_scale: int = 0, presorted: bool = False, overwrite: bool = False) -> dict[str, np.ndarray]:
    """Sum, mean, variance (ddof=1), skewness, kurtosis, min, max and range along the last axis.

    ``x`` float64, ``(..., n)`` (``presorted``: already sorted along the
    last axis, so min and max are its ends; ``overwrite``: ``x`` may be
    used as scratch space). Skewness is ``m3 / s**3`` and kurtosis
    ``m4 / s**4`` (Pearson, not excess) with ``m_k`` the biased central
    moments (1/n) and ``s`` the standard deviation with ``ddof_scale`` (0:
    MATLAB's ``skewness``/``kurtosis`` with their default flag 1, as
    scipy's ``skew``/``kurtosis(fisher=False)``; 1: Zhou et al. 2017,
    section 4.1.1, who divide by the ddof=1 standard deviation). Constant
    series get the limits of the module docstring.
    """
    n = x.shape[-1]
    total = x.sum(axis=-1)
    if presorted:
        lo, hi = x[..., 0].copy(), x[..., -1].copy()
    else:
        lo, hi = x.min(axis=-1), x.max(axis=-1)
    scale = _scale(lo, hi)
    # shift to the minimum and scale by the range first, centre afterwards:
    # z lies in [0, 1], so its mean and deviations never underflow
    z = np.subtract(x, lo[..., None], out=x if overwrite else None)
    z /= scale[..., None]  # not * (1 / scale): 1 / a subnormal range overflows
    z -= (z.sum(axis=-1) / n)[..., None]
    z2 = z * z
    m2 = z2.sum(axis=-1) / n
    m3 = np.einsum("...i,...i->...", z2, z) / n
    m4 = np.einsum("...i,...i->...", z2, z2) / n
    return _moment_stats(n, total, lo, hi, (m2, m3, m4), ddof_scale)


def _scale(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The range ``hi - lo``, 1 where it is 0 (a constant series): the divisor of the scaled moments."""
    rng = hi - lo
    return np.where(rng == 0, 1.0, rng)


def _moment_stats(n: int, total: np.ndarray, lo: np.ndarray, hi: np.ndarray, central: tuple, ddof_scale: int) -> dict[str, np.ndarray]:
    """:func:`moments`' statistics from the sum, the ends and the second to fourth central moments
    (1/n) of the series scaled by its range (``central``)."""
    m2, m3, m4 = central
    mean = total / n
    rng = hi - lo
    const = rng == 0
    scale = _scale(lo, hi)
    # variance with ddof=1 (0 for n == 1), back in the input's units
    var = np.where(const, 0.0, m2 * scale * scale * (n / (n - 1) if n > 1 else 0.0))
    s2 = m2 * (n / (n - ddof_scale) if n > ddof_scale else 1.0)
    s2 = np.where(const, 1.0, s2)
    skew = np.where(const, SKEW_CONSTANT, m3 / s2**1.5)
    kurt = np.where(const, KURT_CONSTANT, m4 / (s2 * s2))
    return {"sum": total, "mean": mean, "var": var, "skew": skew, "kurt": kurt, "min": lo, "max": hi, "range": np.where(const, 0.0, rng)}


def hazen_points(n: int, p: float) -> tuple[int, int, float]:
    """Where MATLAB's quantile ``p`` of ``n`` sorted values lies: the 0-based order statistics ``i``
    and ``j`` it interpolates between and the weight ``f`` of ``j`` (see :func:`hazen_quantiles`)."""
    pos = min(max(n * p - 0.5, 0.0), n - 1.0)
    i = int(np.floor(pos))
    return i, min(i + 1, n - 1), pos - i


def hazen_quantiles(sorted_x: np.ndarray, probs: tuple[float, ...]) -> list[np.ndarray]:
    """Quantiles of already-sorted data along the last axis, MATLAB's method.

    MATLAB's ``quantile``/``prctile``/``iqr`` (which Gaus et al. used) put
    the i-th smallest of n values (1-based) at probability ``(i - 0.5)/n``,
    interpolate linearly between, and return the min/max beyond the first /
    last point: numpy's ``method="hazen"``.
    """
    return _interpolate(sorted_x.shape[-1], probs, lambda k: sorted_x[..., k])


def _interpolate(n: int, probs: tuple[float, ...], order_stat: Callable[[int], np.ndarray]) -> list[np.ndarray]:
    """Hazen quantiles from ``order_stat(k)``, the k-th smallest (0-based) of every series."""
    out = []
    for p in probs:
        i, j, f = hazen_points(n, p)
        a = order_stat(i)
        out.append(a + f * (order_stat(j) - a) if f else np.array(a, dtype=np.float64))
    return out


class SeriesCounts:
    """Integer series held as their value counts: every order statistic and moment of each series
    from one ``bincount``, with no sort.

    ``x`` ``(N, T, P)`` integers: ``N * P`` series of ``T`` readings along axis 1 (series ``g = i * P
    + p``; a stack of captures' frames, cells last, is read in place). Series ``g``'s values
    ``lo[g]..hi[g]`` get bins of their own in one count array (value ``v`` -> bin ``v + shift[g]``),
    so its bins hold ``hi - lo + 1`` counts: little when readings vary over a small part of the
    sensor's range, as pressure readings of a cell do. Floats that are all whole numbers (within
    int32) are counted as those integers, so a capture gives the same statistics in any dtype.
    :meth:`of` returns None for other floats and when the bins would outnumber
    ``max_bins_per_value`` times the readings (a sort is then cheaper).
    """

    def __init__(self, lo: np.ndarray, hi: np.ndarray, shift: np.ndarray, counts: np.ndarray, n: int):
        self.lo, self.hi, self.shift, self.counts, self.n = lo, hi, shift, counts, n

    @staticmethod
    def countable(x: np.ndarray, max_bins_per_value: float = 2.0) -> np.ndarray:
        """Which blocks ``x[i]`` of ``x`` ``(N, T, P)`` :meth:`of` would count on their own: integer
        (or whole) readings whose bins number at most ``max_bins_per_value`` times the block's
        readings. :meth:`of` decides for the whole of ``x``; a statistic whose last bits differ
        between counting and sorting (the moments) splits a batch by this, so a capture's value
        never depends on the captures beside it."""
        n = x.shape[0]
        flat = x.reshape(n, -1)
        if x.dtype.kind == "f":
            ok = (np.abs(flat).max(axis=1, initial=0) < 2**31) & (flat == np.rint(flat)).all(axis=1)
        else:
            ok = np.full(n, as_integers(x[:0]) is not None)
        if not ok.any():
            return ok
        span = (x.max(axis=1).astype(np.float64) - x.min(axis=1) + 1).reshape(n, -1).sum(axis=1)
        return ok & (span <= max_bins_per_value * flat.shape[1])

    @classmethod
    def of(cls, x: np.ndarray, max_bins_per_value: float = 2.0) -> "SeriesCounts | None":
        x = as_integers(x)  # whole readings held as floats are counted as the integers they are
        if x is None:
            return None
        n_series, t, p = x.shape
        lo = x.min(axis=1).astype(np.int64)
        hi = x.max(axis=1).astype(np.int64)
        span = (hi - lo + 1).ravel()
        start = np.cumsum(span) - span
        bins = int(start[-1] + span[-1]) if span.size else 0
        if bins > max_bins_per_value * x.size:
            return None
        shift = start - lo.ravel()
        key = np.add(x, shift.reshape(n_series, 1, p), dtype=np.int64)
        return cls(lo.ravel(), hi.ravel(), shift, np.bincount(key.ravel(), minlength=bins), t)

    def order_stats(self, ranks: Sequence[int]) -> dict[int, np.ndarray]:
        """The ``k``-th smallest (0-based) reading of every series for each ``k`` in ``ranks``, int64."""
        cum = np.cumsum(self.counts)
        base = np.arange(self.lo.size, dtype=np.int64) * self.n
        return {k: np.searchsorted(cum, base + k, side="right") - self.shift for k in sorted(set(ranks))}

    def quantiles(self, probs: tuple[float, ...]) -> list[np.ndarray]:
        """Hazen quantiles of every series (:func:`hazen_quantiles`' values), float64."""
        ranks = [k for p in probs for k in hazen_points(self.n, p)[:2]]
        stats = {k: v.astype(np.float64) for k, v in self.order_stats(ranks).items()}
        return _interpolate(self.n, probs, stats.__getitem__)

    def moments(self, ddof_scale: int = 0) -> dict[str, np.ndarray]:
        """:func:`moments` of every series, each distinct value weighted by its count."""
        bins = np.flatnonzero(self.counts)
        counts = self.counts[bins].astype(np.float64)
        first = np.searchsorted(bins, self.shift + self.lo)  # each series' first (lowest) bin
        series = np.repeat(np.arange(self.lo.size), np.diff(np.append(first, bins.size)))
        lo, hi = self.lo.astype(np.float64), self.hi.astype(np.float64)
        value = (bins - self.shift[series]).astype(np.float64)
        total = np.add.reduceat(counts * value, first)
        z = (value - lo[series]) / _scale(lo, hi)[series]
        z -= (np.add.reduceat(counts * z, first) / self.n)[series]
        cz2 = counts * z * z
        central = [np.add.reduceat(w, first) / self.n for w in (cz2, cz2 * z, cz2 * z * z)]
        return _moment_stats(self.n, total, lo, hi, tuple(central), ddof_scale)


def total_variation(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Sum of absolute consecutive differences along ``axis`` (0 for one sample).

    Unsigned integers of up to 16 bits are differenced exactly in their own
    dtype (``max - min`` of each pair), other integers up to 16 bits in
    int32, anything else in float64.
    """
    axis = axis % x.ndim
    if x.shape[axis] < 2:
        return np.zeros(x.shape[:axis] + x.shape[axis + 1:])
    before = (slice(None),) * axis
    a, b = x[before + (slice(1, None),)], x[before + (slice(None, -1),)]
    if x.dtype.kind in "biu" and x.dtype.itemsize <= 2:
        if x.dtype.kind == "u":
            d = np.maximum(a, b)
            d -= np.minimum(a, b)
        else:
            d = np.abs(np.subtract(a, b, dtype=np.int32))
        return d.sum(axis=axis, dtype=np.int64).astype(np.float64)
    return np.abs(np.subtract(as_f64(a), b)).sum(axis=axis)


def count_true(a: np.ndarray) -> np.ndarray:
    """The number of True values of the boolean ``a`` ``(R, L, P)`` along axis 1, int64 ``(R, P)``.

    Summed as bytes (``einsum`` over blocks of at most 255 samples, which cannot overflow a byte):
    several times faster than ``sum(axis=1)``, which casts every value to the accumulator's type.
    """
    u = a.view(np.uint8)
    out = np.zeros((a.shape[0], a.shape[2]), dtype=np.int64)
    for i in range(0, a.shape[1], 255):
        out += np.einsum("rtp->rp", u[:, i:i + 255])
    return out


def weighted_centroid(frames: np.ndarray, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pressure centroid (row, column) of each ``(..., H, W)`` frame, and its total weight.

    Weights are the values above ``floor`` (the sensor's low end), negative
    parts clipped to 0 (bicubic overshoot, noise below the floor). A frame
    with no weight (all cells at or below the floor) has no centroid: we
    define it as the grid centre ``((H-1)/2, (W-1)/2)``, the point every
    symmetric pressure distribution has, so an empty frame reads as
    "no displacement".
    """
    h, w = frames.shape[-2:]
    wts = np.clip(frames - floor, 0.0, None)
    total = wts.sum(axis=(-2, -1))
    rows = np.arange(h, dtype=np.float64)
    cols = np.arange(w, dtype=np.float64)
    r_num = (wts.sum(axis=-1) * rows).sum(axis=-1)
    c_num = (wts.sum(axis=-2) * cols).sum(axis=-1)
    empty = total <= 0
    safe = np.where(empty, 1.0, total)
    r = np.where(empty, (h - 1) / 2.0, r_num / safe)
    c = np.where(empty, (w - 1) / 2.0, c_num / safe)
    return r, c, total


@functools.lru_cache(maxsize=64)
def grid_coords(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column of every cell, row-major (read-only, cached)."""
    yy = np.repeat(np.arange(h, dtype=np.float64), w)
    xx = np.tile(np.arange(w, dtype=np.float64), h)
    yy.flags.writeable = False
    xx.flags.writeable = False
    return yy, xx


@functools.lru_cache(maxsize=64)
def same_row(h: int, w: int) -> np.ndarray:
    """``(H*W - 1,)``: 1 where flat cells ``i`` and ``i + 1`` lie in one row, else 0 (read-only, cached)."""
    out = (np.arange(1, h * w) % w != 0).astype(np.float64)
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=64)
def moment_coords(h: int, w: int) -> np.ndarray:
    """``(4, H*W)``: row, column, row squared, column squared of every cell (read-only, cached)."""
    yy, xx = grid_coords(h, w)
    out = np.stack([yy, xx, yy * yy, xx * xx])
    out.flags.writeable = False
    return out


def gradient(x: np.ndarray) -> np.ndarray:
    """``numpy.gradient`` along the last axis (unit spacing, first-order edges; at least 2 samples)."""
    g = np.empty_like(x)
    g[..., 1:-1] = (x[..., 2:] - x[..., :-2]) / 2.0
    g[..., 0] = x[..., 1] - x[..., 0]
    g[..., -1] = x[..., -1] - x[..., -2]
    return g
