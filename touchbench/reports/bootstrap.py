"""Owen's pigeonhole bootstrap: the interval of a mean over test captures crossed with replicates.

One test set scored several times varies with two crossed factors: the test
capture and the replicate (a method's seeds, :mod:`touchbench.reports.seeds`;
a data curve point's random draws, :mod:`touchbench.reports.curves`). An
interval over the captures alone treats the replicates as fixed and misses
their variation. One estimator serves both (float64):

- **The matrix**: rows the test captures, columns the replicates; a cell is
  capture ``i``'s correctness with replicate ``j`` (1 right, 0 wrong, or its
  mean over seeds), NaN where that replicate did not score the capture. The
  figure is the mean over the scored cells.
- **A resample** (A. B. Owen 2007, "The pigeonhole bootstrap", Annals of
  Applied Statistics 1(2):386-411, Sec. 2-3): the ``R`` rows drawn with
  replacement and, independently, the ``C`` columns, and the mean of the
  scored cells so chosen, each counted as often as its row and its column
  were drawn: with the draws' counts ``w_r``, ``w_c`` and ``S`` the 0/1
  matrix of scored cells, ``w_r' (Y * S) w_c / w_r' S w_c`` (without NaN
  ``w_r' Y w_c / (R C)``). Its variance estimates ``var(mean) = s_A^2 / R +
  s_B^2 / C + s_E^2 / (R C)`` (capture, replicate and interaction
  components), erring on the large side by about the interaction term
  (Owen 2007, Theorem 2: the pigeonhole bootstrap is mildly conservative),
  where a bootstrap over the captures alone misses ``s_B^2 / C``.
- **A difference** ``mean(a) - mean(b)`` of two matrices on the same captures
  (the same rows, in the same order): each resample draws the captures once
  for both, and takes the difference of the two resampled means. ``paired``
  (a method against another, seed by seed): the ``j``-th columns of ``a`` and
  ``b`` are drawn together (one shape; without NaN the resample of ``D = a -
  b``). Not ``paired`` (two points of a curve, whose draws are unrelated):
  each matrix's columns are drawn independently.
- :data:`PIGEONHOLE_RESAMPLES` resamples from :data:`PIGEONHOLE_SEED` (per
  block of resamples: the captures' counts, then ``a``'s columns', then
  ``b``'s when not paired); the interval is the 2.5 and 97.5 percentiles of
  the resampled statistics (``level`` 0.95).

**Degenerate input** (defined, never from resampling noise), in this order:

- a capture (row) neither matrix scored, and a replicate (column) that
  scored nothing (paired: in neither matrix), are left out first; no scored
  cell left: mean and interval NaN;
- fewer than two captures: the mean, no interval (NaN): resampling one
  capture cannot show how the captures vary, the interval's main part;
- every resample's statistic is the mean, exactly, when the scored cells of
  ``a`` hold one value (and those of ``b`` one value), or, paired, when ``a
  - b`` is one value on cells both score and neither scores alone (a zero
  difference everywhere): the interval ``[mean, mean]``, with no drawing;
- a resample that drew no scored cell has no statistic and is left out;
- a single replicate is a bootstrap over the captures alone;
- the interval always holds the observed mean: widened to it in the rare
  case resampling leaves it outside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["LEVEL", "PIGEONHOLE_RESAMPLES", "PIGEONHOLE_SEED", "Pigeonhole", "pigeonhole"]

#: resamples of the pigeonhole bootstrap
PIGEONHOLE_RESAMPLES = 10000
#: its seed: the same interval on every reading of the results
PIGEONHOLE_SEED = 0
#: the interval's coverage
LEVEL = 0.95
_CHUNK = 500  # resamples drawn at once (memory: _CHUNK x captures float64)


@dataclass(frozen=True)
class Pigeonhole:
    """``mean``: the observed statistic (mean of ``a``, or ``mean(a) - mean(b)``); ``low`` /
    ``high``: its interval (NaN with fewer than two captures); ``resampled``: each resample's
    statistic (float64; those that drew no scored cell left out; every one ``mean`` when ``fixed``,
    none without an interval); ``fixed``: every resample is the mean, known without drawing;
    ``captures``: the rows with a scored cell."""

    mean: float
    low: float
    high: float
    resampled: np.ndarray
    fixed: bool
    captures: int


def _matrix(y: Any, name: str) -> np.ndarray:
    x = np.asarray(y, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2:
        raise ValueError(f"{name}: a captures x replicates matrix is needed, not shape {x.shape}")
    return x


def _inputs(a: Any, b: Any, paired: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """``a`` and ``b`` as matrices, checked, without the rows and columns nothing scored."""
    xa = _matrix(a, "a")
    xb = None if b is None else _matrix(b, "b")
    if xb is not None and (xa.shape != xb.shape if paired else xa.shape[0] != xb.shape[0]):
        what = "shape" if paired else "number of captures (rows)"
        raise ValueError(f"the two matrices differ in {what}: {xa.shape} vs {xb.shape}")
    sa = np.isfinite(xa)
    rows = sa.any(axis=1) if xb is None else sa.any(axis=1) | np.isfinite(xb).any(axis=1)
    if xb is None:
        return xa[rows][:, sa.any(axis=0)], None
    sb = np.isfinite(xb)
    if paired:
        cols = sa.any(axis=0) | sb.any(axis=0)
        return xa[rows][:, cols], xb[rows][:, cols]
    return xa[rows][:, sa.any(axis=0)], xb[rows][:, sb.any(axis=0)]


def _cell_mean(x: np.ndarray) -> float:
    """The mean of the scored cells (their one value, exactly, when they hold one; NaN: none)."""
    v = x[np.isfinite(x)]
    if v.size == 0:
        return math.nan
    return float(v[0]) if np.ptp(v) == 0.0 else float(np.mean(v))


def _one_value(x: np.ndarray) -> bool:
    v = x[np.isfinite(x)]
    return v.size == 0 or bool(np.ptp(v) == 0.0)


def _observed(xa: np.ndarray, xb: np.ndarray | None, paired: bool) -> tuple[float, bool]:
    """The observed statistic and whether every resample's is it (module docstring)."""
    if xb is None:
        return _cell_mean(xa), _one_value(xa)
    if paired and np.array_equal(np.isfinite(xa), np.isfinite(xb)):
        d = xa - xb
        if _one_value(d):
            return _cell_mean(d), True
    return _cell_mean(xa) - _cell_mean(xb), _one_value(xa) and _one_value(xb)


def _counts(rng: np.random.Generator, n: int, size: int) -> np.ndarray:
    """How often each of ``n`` items is drawn in ``n`` draws with replacement, for ``size`` resamples."""
    return rng.multinomial(n, np.full(n, 1.0 / n), size=size).astype(np.float64)


def _resampled_mean(w_r: np.ndarray, w_c: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Each resample's mean over the scored cells it drew (NaN: none)."""
    scored = np.isfinite(x)
    num = np.einsum("br,br->b", w_r, w_c @ np.where(scored, x, 0.0).T)
    den = np.einsum("br,br->b", w_r, w_c @ scored.astype(np.float64).T)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)


def _resample(xa: np.ndarray, xb: np.ndarray | None, paired: bool, resamples: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r = xa.shape[0]
    out = np.empty(resamples, dtype=np.float64)
    for start in range(0, resamples, _CHUNK):
        size = min(_CHUNK, resamples - start)
        w_r, w_a = _counts(rng, r, size), _counts(rng, xa.shape[1], size)
        theta = _resampled_mean(w_r, w_a, xa)
        if xb is not None:
            w_b = w_a if paired else _counts(rng, xb.shape[1], size)
            theta = theta - _resampled_mean(w_r, w_b, xb)
        out[start:start + size] = theta
    return out[np.isfinite(out)]


def pigeonhole(a: Any, b: Any = None, *, paired: bool = True, level: float = LEVEL,
               resamples: int = PIGEONHOLE_RESAMPLES, seed: int = PIGEONHOLE_SEED) -> Pigeonhole:
    """Owen's pigeonhole bootstrap of the mean of ``a`` (rows: captures, columns: replicates; NaN:
    not scored), or of ``mean(a) - mean(b)`` with ``b`` on the same captures, its columns drawn with
    ``a``'s (``paired``) or on their own (module docstring, with its degenerate cases).

    Every capture right with every replicate: the interval is the mean, without drawing; one capture
    (a 1 x 2 matrix): its mean, and no interval.

    >>> p = pigeonhole([[1, 1], [1, 1], [1, 1]])
    >>> p.mean, p.low, p.high, p.fixed, p.captures
    (1.0, 1.0, 1.0, True, 3)
    >>> p = pigeonhole([[1, 0]])
    >>> p.mean, p.low, p.captures
    (0.5, nan, 1)
    """
    xa, xb = _inputs(a, b, paired)
    mean, fixed = _observed(xa, xb, paired)
    none = np.empty(0, dtype=np.float64)
    r = xa.shape[0]
    if not np.isfinite(mean) or r < 2:
        return Pigeonhole(mean, math.nan, math.nan, none, False, r)
    if fixed:
        return Pigeonhole(mean, mean, mean, np.full(resamples, mean), True, r)
    theta = _resample(xa, xb, paired, resamples, seed)
    if theta.size == 0:
        return Pigeonhole(mean, math.nan, math.nan, none, False, r)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(theta, [tail, 100.0 - tail])
    return Pigeonhole(mean, min(float(lo), mean), max(float(hi), mean), theta, False, r)
