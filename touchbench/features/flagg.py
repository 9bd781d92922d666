"""``flagg-stats``: seven sequence statistics per channel (Flagg 2012, seed
002, sections 3.4.2 and 4.3.2)."""

from __future__ import annotations

from numbers import Real

import numpy as np

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, SensorNeededError, cell_names
from .numerics import (
    as_f64,
    hazen_quantiles,
    moments,
    total_variation,
    weighted_centroid,
)

FLAGG_STATS = ("max", "min", "mean", "median", "area", "var", "tv")
GRID_CHANNELS = ("total_pressure", "contact_area", "centroid_x", "centroid_y")
# Default contact threshold, as a fraction of the sensor's value range above
# its low end: 1.5 % of 0..1023 is 15.3, above the 99th percentile (14) of
# the cell values of the real HAART no-touch captures.
CONTACT_FRACTION = 0.015


def grid_channels(stack: np.ndarray, floor: float, contact: float) -> np.ndarray:
    """Frame summaries of ``(N, T, H, W)`` captures -> ``(N, 4, T)``: total
    pressure, contact area, centroid x (column), centroid y (row)."""
    x = as_f64(stack)
    r, c, total = weighted_centroid(x, floor)
    n, t = x.shape[:2]
    area = np.count_nonzero(x.reshape(n, t, -1) > floor + contact, axis=-1).astype(np.float64)
    return np.stack([total, area, c, r], axis=1)


@FEATURES.register("flagg-stats", description="7 sequence statistics of total pressure, contact area and centroid")
class FlaggStats(FeatureSet):
    """Flagg's sequence statistics (Flagg 2012, sections 3.4.2 and 4.3.2).

    Per channel time series: maximum, minimum, mean, median, area under the
    curve, variance and total variation ("summing the absolute values of
    the differences between each consecutive point"), "calculated for each
    of the 4 time-series curves, resulting in a set of 28 features".
    ``flagg_{stat}_{channel}``.

    Channels (``channels``):

    - ``"auto"`` (default): the sensor's own channels if the sensor is a
      channel sensor (``sensor.channels``, e.g. Flagg's x, y, pressure,
      fur: the ``(T, 1, C)`` capture's C columns), else ``"grid"``;
    - ``"grid"``: four frame-level summaries of a pressure grid, the
      grid counterparts of Flagg's x, y, pressure and touch channels:
      total pressure (sum over cells of the value above the sensor's low
      end), contact area (cells above low end + ``contact_threshold``),
      pressure centroid x (column) and y (row), in cell units. 28 values;
    - ``"cells"``: every cell is a channel (7 x H x W values).

    Interpretations:

    - Area under the curve = sum of the samples (unit spacing, as Gaus's
      "area"), not divided by the frame rate.
    - Variance with ddof = 1 (0 for one frame); median is the usual middle
      value (mean of the two middle ones).
    - The ``"grid"`` channels need the sensor's value range (its low end
      is "no pressure"): the sensor's ``value_range``, or an explicit
      ``value_range`` (for use from Python without a sensor); with neither
      the set refuses to run rather than assume one sensor's range.
    - ``contact_threshold`` default: 1.5 % of the sensor's value range
      (15.3 on HAART's 0..1023), above the no-touch noise of the real
      HAART recordings.
    - An empty frame (nothing above the low end) has no centroid: we use
      the grid centre ((W-1)/2, (H-1)/2), so a no-touch capture has a
      centred, motionless centroid (variance and total variation 0).
    - No normalisation by length (area and total variation grow with T).
    """

    paper = "Flagg 2012 (MSc thesis, UBC), sections 3.4.2 and 4.3.2"
    cost = "cheap"
    fold_dependent = False

    _parameter_constraints = {"channels": [StrOptions({"auto", "grid", "cells"})],
                              "contact_threshold": [Interval(Real, 0, None, closed="left"), None],
                              "value_range": ["array-like", None]}
    _parameter_docs = {"channels": "``auto``, ``grid`` or ``cells`` (above).",
                       "contact_threshold": "the contact area's threshold above the low end (None: 1.5 % of the "
                                            "sensor's value range).",
                       "value_range": "replaces the sensor's (for use from Python without a sensor)."}

    def __init__(self, channels: str = "auto", contact_threshold: float | None = None,
                 value_range: tuple[float, float] | None = None, sensor: SensorSpec | None = None):
        self.channels = channels
        self.contact_threshold = contact_threshold
        self.value_range = value_range
        self.sensor = sensor

    def _mode(self) -> str:
        if self.channels == "auto":
            return "cells" if self.sensor is not None and self.sensor.channels is not None else "grid"
        return self.channels

    def _check_params(self) -> None:
        if self._mode() == "grid":
            self._range()

    def _range(self) -> tuple[float, float]:
        """The value range: ``value_range`` if given, else the sensor's; neither is refused."""
        if self.value_range is not None:
            lo, hi = (float(v) for v in self.value_range)
            if not lo < hi:
                raise FeatureInputError(f"flagg-stats: value_range must be (low, high) with low < high, got {self.value_range!r}")
            return lo, hi
        if self.sensor is not None:
            lo, hi = self.sensor.value_range
            return float(lo), float(hi)
        raise SensorNeededError("flagg-stats: the 'grid' channels need the sensor's value range (its low end is no pressure): "
                                "pass sensor=SensorSpec(...) or value_range=(low, high)")

    def _channel_names(self, grid: tuple[int, int]) -> list[str]:
        if self._mode() == "grid":
            return list(GRID_CHANNELS)
        if self.sensor is not None and self.sensor.channels is not None and tuple(self.sensor.grid) == tuple(grid):
            return [str(c) for c in self.sensor.channels]
        return cell_names(grid)

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        return [f"flagg_{s}_{c}" for s in FLAGG_STATS for c in self._channel_names(grid)]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t = stack.shape[:2]
        if self._mode() == "grid":
            lo, hi = self._range()
            contact = self.contact_threshold if self.contact_threshold is not None else CONTACT_FRACTION * (hi - lo)
            series = grid_channels(stack, lo, float(contact))
        else:
            series = as_f64(stack).reshape(n, t, -1).transpose(0, 2, 1)
        series = np.ascontiguousarray(series)  # (N, C, T)
        srt = np.sort(series, axis=-1)
        m = moments(srt, presorted=True)
        (median,) = hazen_quantiles(srt, (0.5,))
        cols = [m["max"], m["min"], m["mean"], median, m["sum"], m["var"], total_variation(series)]
        return np.concatenate(cols, axis=1)
