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

import numpy as np

SKEW_CONSTANT = 0.0
KURT_CONSTANT = 3.0


def as_f64(a: np.ndarray) -> np.ndarray:
    """``a`` as float64 (exact for every integer dtype up to 2**53 and float32)."""
    return np.asarray(a, dtype=np.float64)


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
    mean = total / n
    if presorted:
        lo, hi = x[..., 0].copy(), x[..., -1].copy()
    else:
        lo, hi = x.min(axis=-1), x.max(axis=-1)
    rng = hi - lo
    const = rng == 0
    scale = np.where(const, 1.0, rng)
    # shift to the minimum and scale by the range first, centre afterwards:
    # z lies in [0, 1], so its mean and deviations never underflow
    z = np.subtract(x, lo[..., None], out=x if overwrite else None)
    z /= scale[..., None]  # not * (1 / scale): 1 / a subnormal range overflows
    z -= (z.sum(axis=-1) / n)[..., None]
    z2 = z * z
    m2 = z2.sum(axis=-1) / n
    m3 = np.einsum("...i,...i->...", z2, z) / n
    m4 = np.einsum("...i,...i->...", z2, z2) / n
    # variance with ddof=1 (0 for n == 1), back in the input's units
    var = np.where(const, 0.0, m2 * scale * scale * (n / (n - 1) if n > 1 else 0.0))
    s2 = m2 * (n / (n - ddof_scale) if n > ddof_scale else 1.0)
    s2 = np.where(const, 1.0, s2)
    skew = np.where(const, SKEW_CONSTANT, m3 / s2**1.5)
    kurt = np.where(const, KURT_CONSTANT, m4 / (s2 * s2))
    return {"sum": total, "mean": mean, "var": var, "skew": skew, "kurt": kurt, "min": lo, "max": hi, "range": np.where(const, 0.0, rng)}


def hazen_quantiles(sorted_x: np.ndarray, probs: tuple[float, ...]) -> list[np.ndarray]:
    """Quantiles of already-sorted data along the last axis, MATLAB's method.

    MATLAB's ``quantile``/``prctile``/``iqr`` (which Gaus et al. used) put
    the i-th smallest of n values (1-based) at probability ``(i - 0.5)/n``,
    interpolate linearly between, and return the min/max beyond the first /
    last point: numpy's ``method="hazen"``.
    """
    n = sorted_x.shape[-1]
    out = []
    for p in probs:
        pos = min(max(n * p - 0.5, 0.0), n - 1.0)
        i = int(np.floor(pos))
        j = min(i + 1, n - 1)
        f = pos - i
        a = sorted_x[..., i]
        out.append(a + f * (sorted_x[..., j] - a) if f else a.astype(np.float64, copy=True))
    return out


def total_variation(x: np.ndarray) -> np.ndarray:
    """Sum of absolute consecutive differences along the last axis (0 for one sample).

    Integer input (up to 16 bits) is differenced exactly in int32, anything
    else in float64.
    """
    if x.shape[-1] < 2:
        return np.zeros(x.shape[:-1])
    if x.dtype.kind in "biu" and x.dtype.itemsize <= 2:
        return np.abs(np.diff(x.astype(np.int32), axis=-1)).sum(axis=-1, dtype=np.int64).astype(np.float64)
    return np.abs(np.diff(as_f64(x), axis=-1)).sum(axis=-1)


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
