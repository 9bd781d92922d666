"""``msd``: motion statistical distribution, twelve statistics per cell
(Gaus et al. 2015, section 3.2.3)."""

from __future__ import annotations

import numpy as np

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureSet, cell_names
from ..core.compiled import kernels
from .gaus_common import GAUS_PAPER
from .numerics import SeriesCounts, as_f64, as_integers, hazen_points, hazen_quantiles, moments, sort_last, total_variation

MSD_STATS = ("min", "max", "mean", "q1", "median", "q3", "area", "tv", "iqr", "var", "skew", "kurt")
QUARTILES = (0.25, 0.5, 0.75)


def sorted_f64(series: np.ndarray) -> np.ndarray:
    """Sort along the last axis in the native dtype (faster for integers), then float64."""
    return as_f64(sort_last(series))


@FEATURES.register("msd", description="12 statistics of every cell's time series")
class MotionStatisticalDistribution(FeatureSet):
    """Motion statistical distribution (MSD): 12 statistics per cell.

    Gaus et al. 2015, section 3.2.3: from each sensor (cell) sequence
    ``F = (f_1..f_L)``: minimum, maximum, mean, first quartile, median,
    third quartile, area ("the sum of all values of each sensor in all
    frames"), total variation ("the sum of changes in values for each
    sensor in all frames"), interquartile range, variance, skewness and
    kurtosis. 12 x 64 = 768 values for an 8 x 8 grid, statistic-major:
    ``msd_{stat}_r{i}_c{j}``.

    Interpretations:

    - "on the changing information for each sensor": the statistics are of
      the raw cell series (the paper defines area on the values), not of
      their differences.
    - Total variation = sum of |f_{t+1} - f_t| (Flagg 2012, section 3.4.2,
      from which these 12 statistics come).
    - Quartiles, median and IQR follow MATLAB's ``quantile`` / ``iqr`` (the
      authors' tool): numpy ``method="hazen"``.
    - Variance: MATLAB ``var`` (ddof = 1; 0 for one frame). Skewness and
      kurtosis: MATLAB ``skewness`` / ``kurtosis`` defaults (biased,
      Pearson kurtosis, 3 for a normal).
    - Limits (see :mod:`touchbench.features.numerics`): a constant cell
      (no touch, all zero, saturated at 1023) has variance, IQR and total
      variation 0, skewness 0 and kurtosis 3; a one-frame capture is
      constant in every cell.
    - No normalisation by the number of frames (area and total variation
      grow with length), as in the paper.
    """

    paper = f"{GAUS_PAPER}.3"
    cost = "cheap"
    fold_dependent = False
    compiled_loops = "features.gaus_kernels"
    _parameter_docs = {"sensor": "unused; nothing depends on the sensor."}

    def __init__(self, sensor: SensorSpec | None = None):
        self.sensor = sensor

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        cells = cell_names(grid)
        return [f"msd_{s}_{c}" for s in MSD_STATS for c in cells]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t = stack.shape[:2]
        frames = stack.reshape(n, t, -1)  # (N, T, P): every cell's series along axis 1, in place
        kern = kernels("features.gaus_kernels")
        if kern is None:
            return msd_rows(frames)
        ints = as_integers(frames)
        if ints is None:  # fractions in the batch: each capture alone, so its row never depends on its batch
            return np.concatenate([msd_one(kern, frames[i:i + 1]) for i in range(n)])
        return msd_one(kern, ints)


def msd_one(kern, frames: np.ndarray) -> np.ndarray:
    """The statistics of ``frames`` ``(N, T, P)`` by the compiled loop where its readings are
    integers of a narrow span, else by numpy, capture by capture."""
    ints = as_integers(frames)
    if ints is None:
        return msd_rows(frames)
    out, ok = compiled_msd(kern, ints)
    for i in np.flatnonzero(~ok):  # a cell spans too many values to count: this capture alone, as numpy
        out[i] = msd_rows(frames[i:i + 1])[0]
    return out


def msd_rows(frames: np.ndarray) -> np.ndarray:
    """The twelve statistics of every cell of ``frames`` ``(N, T, P)`` (the numpy path): counted
    for a capture of integer readings over a narrow range, else sorted; decided capture by capture
    (:meth:`SeriesCounts.countable`: the moments' last bits differ between the two), so a row never
    depends on its batch."""
    ok = SeriesCounts.countable(frames)
    if ok.all() or not ok.any():
        return _msd_rows(frames)
    out = np.empty((frames.shape[0], len(MSD_STATS) * frames.shape[2]))
    out[ok], out[~ok] = _msd_rows(frames[ok]), _msd_rows(frames[~ok])
    return out


def _msd_rows(frames: np.ndarray) -> np.ndarray:
    """:func:`msd_rows` of captures that are all countable, or none of them."""
    n = frames.shape[0]
    counts = SeriesCounts.of(frames)
    if counts is not None:  # integer readings over a narrow range: counted, not sorted
        q1, med, q3 = counts.quantiles(QUARTILES)
        m = {k: v.reshape(n, -1) for k, v in counts.moments().items()}
        q1, med, q3 = (q.reshape(n, -1) for q in (q1, med, q3))
    else:
        srt = sorted_f64(np.ascontiguousarray(frames.transpose(0, 2, 1)))
        q1, med, q3 = hazen_quantiles(srt, QUARTILES)
        m = moments(srt, presorted=True, overwrite=True)  # srt is scratch from here on
    tv = total_variation(frames, axis=1)
    cols = [m["min"], m["max"], m["mean"], q1, med, q3, m["sum"], tv, q3 - q1, m["var"], m["skew"], m["kurt"]]
    return np.concatenate(cols, axis=1)


def compiled_msd(kern, ints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`msd_rows` of the integer readings ``ints`` ``(N, T, P)`` by the compiled loop
    (:func:`touchbench.features.gaus_kernels.msd`: the quartiles at the same Hazen points), and
    which captures it computed (one with a cell spanning too many values to count is left out)."""
    n, t, p = ints.shape
    points = [hazen_points(t, q) for q in QUARTILES]
    ranks = [k for i, j, _ in points for k in (i, j)]
    order = np.array(sorted(set(ranks)), dtype=np.intp)
    fracs = np.array([f for _, _, f in points], dtype=np.float64)
    out, ok = np.empty((n, len(MSD_STATS), p)), np.zeros(n, dtype=bool)
    kern.msd(ints, order, np.searchsorted(order, ranks), fracs, out, ok)
    return out.reshape(n, -1), ok
