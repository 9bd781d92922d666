"""``sd``: statistical distribution of the pressure surface (Gaus et al.
2015, section 3.2.1, Tables 3 and 4)."""

from __future__ import annotations

import functools
from numbers import Real

from typing import Any

import numpy as np

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet
from ..core.compiled import kernels
from .gaus_common import GAUS_PAPER, lookup, resolve_units, setting_for
from .numerics import SeriesCounts, as_integers, sort_last

_CONDITIONS = ("notouch", "touched", "high")
_VALUES = "bins for notouch, touched and high, high_offset and touched_fixed"

# Table 3 (conditions) and Table 4 (histcounts bin width, leading and
# trailing edge) per dataset. "high_offset": high pressure is
# value >= max - high_offset (HAART "= max. pressure" is offset 0).
# "touched_fixed": CoST's extra "touched" threshold (>= 100).
_TABLE: dict[str, dict[str, Any]] = {
    "haart": {
        "high_offset": 0.0,
        "touched_fixed": None,
        "bins": {"notouch": (5.0, -0.5, 55.5), "touched": (5.0, -0.5, 65.5), "high": (5.0, -0.5, 55.5)},
    },
    "cost": {
        "high_offset": 100.0,
        "touched_fixed": 100.0,
        "bins": {"notouch": (1.0, -0.5, 11.5), "touched": (10.0, -0.5, 80.5), "high": (10.0, -0.5, 100.5)},
    },
}


def conditions(fixed: float | None) -> list[tuple[str, str]]:
    """(feature prefix, bins key) in output order (``fixed``: the extra touched threshold or None)."""
    conds = [("notouch_frame", "notouch"), ("notouch_instance", "notouch"), ("touched_median", "touched")]
    if fixed is not None:
        conds.append((f"touched_ge{fixed:g}", "touched"))
    return conds + [("high_frame", "high"), ("high_instance", "high")]


def histcounts_edges(width: float, lead: float, trail: float) -> np.ndarray:
    """MATLAB ``histcounts(..., 'BinWidth', width, 'BinLimits', [lead trail])`` edges.

    ``ceil((trail - lead) / width)`` bins of ``width`` from ``lead``; the
    last edge is moved to ``trail``, so the last bin is narrower when the
    limits are not a whole number of widths apart (every HAART row of
    Table 4: 56/5 and 66/5).
    """
    if not (width > 0 and trail > lead):
        raise FeatureInputError(f"sd: bins need width > 0 and trailing > leading edge, got {(width, lead, trail)}")
    nb = max(int(np.ceil((trail - lead) / width - 1e-9)), 1)
    edges = lead + width * np.arange(nb + 1, dtype=np.float64)
    edges[-1] = trail
    return edges


def histogram_counts(counts: list[np.ndarray], n_cells: int, edges: dict[str, np.ndarray], keys: list[str],
                     clip: bool) -> np.ndarray:
    """Histogram each row of every ``counts[i]`` (N, T) of cells (integers ``0..n_cells``) over
    ``edges[keys[i]]`` -> (N, sum of the bins), the histograms side by side, in one ``bincount``.

    Bins are ``[e_k, e_k+1)``, the last one closed ``[e_-2, e_-1]``
    (MATLAB ``histcounts`` and ``numpy.histogram``): a count that falls
    exactly on an inner edge counts in the bin to its right. With
    ``clip``, counts below the first / above the last edge count in the
    first / last bin, so every frame is counted; without, they are dropped
    (into one extra column, cut off at the end).
    """
    lut, width = _count_to_column(n_cells, tuple(tuple(edges[k].tolist()) for k in keys), clip)
    n = counts[0].shape[0]
    key = np.stack(counts, axis=1)  # (N, conditions, T)
    key += (np.arange(len(keys)) * (n_cells + 1))[:, None]
    key = lut[key] + (np.arange(n) * width)[:, None, None]
    return np.bincount(key.ravel(), minlength=n * width).reshape(n, width)[:, :width - 1].astype(np.float64)


@functools.lru_cache(maxsize=32)
def _count_to_column(n_cells: int, edges: tuple[tuple[float, ...], ...], clip: bool) -> tuple[np.ndarray, int]:
    """:func:`histogram_counts`' table: count ``c`` of condition ``i`` (``i * (n_cells + 1) + c``) ->
    its column (the dropped ones: the last column), and the number of columns (read-only, cached)."""
    every = np.arange(n_cells + 1, dtype=np.float64)
    luts, start = [], 0
    for e in map(np.array, edges):
        nb = len(e) - 1
        idx = np.searchsorted(e, every, side="right") - 1
        idx = np.where(every == e[-1], nb - 1, idx)
        inside = (idx >= 0) & (idx < nb)
        idx = np.clip(idx, 0, nb - 1) + start
        luts.append(idx if clip else np.where(inside, idx, -1))
        start += nb
    lut = np.concatenate(luts)
    lut[lut < 0] = start
    lut.flags.writeable = False
    return lut, start + 1


@FEATURES.register("sd", description="no-touch / touched / high-pressure cell counts per frame, histogrammed")
class StatisticalDistribution(FeatureSet):
    """Statistical distribution (SD) of the pressure surface.

    Gaus et al. 2015, section 3.2.1, Tables 3 and 4. For every frame we
    count the cells in three conditions and histogram those per-frame counts
    over the capture (one histogram per condition and level):

    ====================  ==========================  ==========================
    condition             HAART (``preset="haart"``)  CoST (``preset="cost"``)
    ====================  ==========================  ==========================
    no touch, frame       value == frame minimum      same
    no touch, instance    value == capture minimum    same
    touched, instance     value >= capture median     same, and value >= 100
    high, frame           value == frame maximum      value >= frame max - 100
    high, instance        value == capture maximum    value >= capture max - 100
    ====================  ==========================  ==========================

    Histogram bins (Table 4, width / leading / trailing edge): HAART
    no touch 5 / -0.5 / 55.5, touched 5 / -0.5 / 65.5, high 5 / -0.5 /
    55.5; CoST 1 / -0.5 / 11.5, 10 / -0.5 / 80.5, 10 / -0.5 / 100.5.
    Output for an 8 x 8 grid: HAART 12 + 12 + 14 + 12 + 12 = 62 values,
    CoST 12 + 12 + 9 + 9 + 11 + 11 = 64.

    Interpretations (the paper is silent or ambiguous):

    - The histogrammed quantity is the number of cells per frame in the
      condition ("the distribution of the number of sensor cells per frames
      having such value/range"); each bin holds a number of frames. On the
      real HAART recordings the largest per-frame no-touch count is 55,
      exactly Table 4's trailing edge 55.5 - 0.5, which supports this reading.
    - "Touched" has no frame-level variant (Table 3 has "-"); for CoST the
      paper gives two thresholds (">= median pressure; >= 100"): we emit
      two histograms, both with the touched bins.
    - "max. pressure - 100" and the touched threshold 100 are in raw
      sensor units. "min/median/max pressure" at instance level are taken
      over all cells and frames of the capture.
    - Edges: MATLAB's BinWidth + BinLimits rule (see
      :func:`histcounts_edges`), so HAART's 56-wide range with width 5
      gives 11 bins of 5 and a last bin [54.5, 55.5].
    - A value exactly on an inner edge goes to the bin on its right; on the
      last edge, to the last bin (histcounts). With the paper's half-integer
      edges no count ever falls on an edge.
    - The paper chose the edges "to fit all instances" of its data, so no
      count fell outside them. On other data (other grids, other sensors)
      counts can: with ``clip=True`` (default) they are counted in the
      first / last bin, so each histogram always sums to the number of
      frames; ``clip=False`` drops them as histcounts does.
    - Values are raw frame counts, as in the paper (HAART captures all have
      432 frames); ``normalize=True`` divides by the number of frames for
      datasets of varying length.
    - The edges are the published constants (Table 4) chosen once on each
      whole dataset; nothing is learnt from the training fold, so
      ``fold_dependent = False``.
    - Another sensor (neither HAART's nor CoST's recording setting; rule in
      :mod:`touchbench.features.gaus_common`): HAART's conditions, which
      hold no sensor constant (= min, >= median, = max), and Table 4's
      HAART edges scaled to the grid. Table 4's edges count cells of an
      8 x 8 grid ("set to fit all instances", section 3.2.1): its touched
      edges end at 65.5, just above all 64 cells. On a grid of ``N`` cells
      every width and edge is multiplied by ``N / 64``, so each bin covers
      the same fraction of the grid as on HAART and the output keeps its
      62 values; e.g. on 19 x 24 (456 cells, factor 7.125) the no-touch
      bins are 35.625 cells wide from -3.5625 to 395.4375. Equivalently, a
      count ``c`` of ``N`` cells is binned as ``64 c / N`` with Table 4's
      edges. Without the scaling, 8 x 8 bins on a 456-cell grid would put
      every frame with more than 55 untouched cells into one clipped bin.
      Explicit ``bins`` are never scaled (they are in the sensor's cells).
    - A constant capture: every cell is at the minimum, the median and the
      maximum, so all counts equal the number of cells (clipped into the
      last bin on an 8 x 8 grid). Finite for every input.

    - The preset: named (as published), or the one of the sensor's
      recording setting (HAART's or CoST's), or HAART's scaled to any other
      grid sensor (above); a channel sensor is refused, and without a
      sensor a preset or every value must be given.

    Parameters: ``preset`` ("haart", "cost" or None: the sensor's);
    ``bins`` (dict condition ->
    (width, leading, trailing) overriding Table 4 for "notouch", "touched",
    "high"); ``high_offset`` (high pressure is value >= max - high_offset);
    ``touched_fixed`` (extra touched threshold, ``None`` = preset,
    ``False`` = none); ``clip``;
    ``normalize``; ``sensor`` (picks the preset or scales HAART's).
    """

    paper = f"{GAUS_PAPER}.1, Tables 3-4"
    cost = "cheap"
    fold_dependent = False
    compiled_loops = "features.gaus_kernels"

    _parameter_constraints = {"preset": [StrOptions(set(_TABLE)), None], "bins": [dict, None],
                              "high_offset": [Real, None], "touched_fixed": [Interval(Real, 0, None, closed="left"),
                                                                             "boolean", None],
                              "clip": ["boolean"], "normalize": ["boolean"]}

    def __init__(
        self,
        preset: str | None = None,
        bins: dict | None = None,
        high_offset: float | None = None,
        touched_fixed: float | bool | None = None,
        clip: bool = True,
        normalize: bool = False,
        sensor: SensorSpec | None = None,
    ):
        self.preset = preset
        self.bins = bins
        self.high_offset = high_offset
        self.touched_fixed = touched_fixed
        self.clip = clip
        self.normalize = normalize
        self.sensor = sensor

    # -------------------------------------------------------------- params
    def _resolved(self) -> tuple[float, float | None, dict[str, np.ndarray]]:
        name = "sd"
        off = float(resolve_units(name, self.preset, _TABLE, "high_offset", self.high_offset, self.sensor, _VALUES))
        fixed = resolve_units(name, self.preset, _TABLE, "touched_fixed", self.touched_fixed, self.sensor, _VALUES)
        if fixed is False:
            fixed = None
        given = dict(self.bins or {})
        unknown = set(given) - set(_CONDITIONS)
        if unknown:
            raise FeatureInputError(f"sd: unknown bins condition(s) {sorted(unknown)} (known: high, notouch, touched)")
        bins = {}
        if set(given) != set(_CONDITIONS):
            setting = setting_for(name, self.preset, self.sensor, _VALUES)
            # bin widths and edges count cells: scaled by the sensor's cells over the preset's
            bins = {k: tuple(float(v) * setting.cells for v in spec) for k, spec in lookup(name, _TABLE, setting, "bins").items()}
        bins.update(given)
        edges = {k: histcounts_edges(*map(float, v)) for k, v in bins.items()}
        return off, (None if fixed is None else float(fixed)), edges

    def _check_params(self) -> None:
        self._resolved()

    def _conditions(self) -> list[tuple[str, str]]:
        """(feature prefix, bins key) in output order."""
        return conditions(self._resolved()[1])

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        _, fixed, edges = self._resolved()
        return [f"sd_{p}_b{k:02d}" for p, key in conditions(fixed) for k in range(len(edges[key]) - 1)]

    # ----------------------------------------------------------- transform
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        off, fixed, edges = self._resolved()
        n, t = stack.shape[:2]
        x = stack.reshape(n, t, -1)
        kern = kernels("features.gaus_kernels")
        ints = as_integers(x) if kern is not None else None
        if ints is None:
            return self._numpy_rows(x, off, fixed, edges)
        conds = conditions(fixed)
        lut, width = _count_to_column(x.shape[2], tuple(tuple(edges[k].tolist()) for _, k in conds), self.clip)
        counts, ok = np.zeros((n, width), dtype=np.int64), np.zeros(n, dtype=bool)
        kern.sd(ints, off, 0.0 if fixed is None else fixed, fixed is not None, lut, counts, ok)
        h = counts[:, :width - 1].astype(np.float64)
        h = h / t if self.normalize else h
        for i in np.flatnonzero(~ok):  # readings spanning too many values to count: this capture alone, as numpy
            h[i] = self._numpy_rows(x[i:i + 1], off, fixed, edges)[0]
        return h

    def _numpy_rows(self, x: np.ndarray, off: float, fixed: float | None, edges: dict[str, np.ndarray]) -> np.ndarray:
        """The histograms of ``x`` ``(N, T, P)`` by numpy (the path without the compiled loop)."""
        n, t = x.shape[:2]
        if x.dtype.kind == "f":
            x = x.astype(np.float64)
        flat = x.reshape(n, -1)
        fmin = x.min(axis=2, keepdims=True)
        fmax = x.max(axis=2, keepdims=True)
        imin = fmin.min(axis=1, keepdims=True)
        imax = fmax.max(axis=1, keepdims=True)
        imed = median_rows(flat)[:, None, None]

        p = x.shape[2]

        def count(cond: np.ndarray) -> np.ndarray:
            if p < 256:  # summed as bytes: no bool-to-integer conversion
                return cond.view(np.uint8).sum(axis=2, dtype=np.uint8).astype(np.intp)
            return np.count_nonzero(cond, axis=2)

        # thresholds as float64 (exact for every integer sensor value)
        counts = {
            "notouch_frame": count(x == fmin),
            "notouch_instance": count(x == imin),
            "touched_median": count(x >= imed),
            "high_frame": count(x >= fmax - off) if off else count(x == fmax),
            "high_instance": count(x >= imax - off) if off else count(x == imax),
        }
        if fixed is not None:
            counts[f"touched_ge{fixed:g}"] = count(x >= fixed)
        conds = conditions(fixed)
        h = histogram_counts([counts[c] for c, _ in conds], p, edges, [k for _, k in conds], self.clip)
        return h / t if self.normalize else h


def median_rows(flat: np.ndarray) -> np.ndarray:
    """Median of each row of ``flat`` (N, M) as float64 (mean of the two middle values for even M).

    Integer rows over a narrow range: the two middle order statistics from the rows' value counts
    (:class:`touchbench.features.numerics.SeriesCounts`, one ``bincount``, cheaper than a sort);
    other rows: a sort.
    """
    m = flat.shape[1]
    ranks = ((m - 1) // 2, m // 2)
    counts = SeriesCounts.of(flat[:, :, None])
    if counts is not None:
        stats = counts.order_stats(ranks)
        return (stats[ranks[0]].astype(np.float64) + stats[ranks[1]].astype(np.float64)) / 2.0
    srt = sort_last(flat)
    return (srt[:, ranks[0]].astype(np.float64) + srt[:, ranks[1]].astype(np.float64)) / 2.0
