"""``live-summary``: a few frame-level series of a short window, summarised; built to decide live.

Not from a paper: designed for live recognition on a robot skin
(docs/research/live-recognition.md), where a decision every 0.1 s classifies
windows of a few frames of hundreds of cells, and ``touch-rhythm``'s spectra,
autocorrelations and per-cell order statistics cost milliseconds a window.
It keeps the frame-level descriptors of Zhou et al. 2017, Sec. 4.1 (total
pressure, contact area, centroid) and the movement and rhythm cues Gaus et
al. 2015, Sec. 5 name (pat, tickle, scratch and stroke differ in rhythm and
movement more than in pressure), reduced to what a short window can show.

Readings are heights above the sensor's zero as fractions of its full scale
(``x = (v - lo) / (hi - lo)``, from the top for a sensor where lower means
more pressure). Each cell's baseline is its lowest reading in the window
(an interpretation: a window of a touch in progress still holds the cell's
rest, or its lowest pressure, and the skin's drift is slower than a
window); the pressure ``p = x - baseline``. Nine series over the window's
frames:

- ``level``: the mean of ``x`` over cells (the absolute level: it tells a
  skin pressed all over from one at rest, which the baseline removes);
- ``pressure``: the mean of ``p``; ``peak``: the largest ``p``;
- ``area``: the fraction of cells with ``p`` above ``contact`` (default 2 %
  of full scale);
- ``row``, ``col``: the centroid of ``p`` in the grid, 0 at the first row
  (column) and 1 at the last (0.5 on a frame without pressure, or a grid one
  cell wide);
- ``row_sd``, ``col_sd``: the ``p``-weighted spread about it, same units;
- ``change``: the mean absolute change of ``x`` from the frame before (0 for
  the first frame).

Each series gives seven numbers: mean, standard deviation, minimum,
maximum, last value, last minus first, and mean absolute first difference
(0 for a window of one frame); then the window's length in seconds (the
sensor's frame rate). 64 features, every one finite for finite input,
computed for all windows of one length at once with one pass per series.

Refused: no sensor and no ``value_range`` (nothing is a fraction of full
scale without one), a channel sensor, a ``contact`` outside (0, 1).
"""

from __future__ import annotations

from numbers import Real

import numpy as np

from sklearn.utils._param_validation import Interval

from ..datasets.model import SensorSpec
from .base import FEATURES, SensorNeededError
from .contact import FullScaleSet, heights

__all__ = ["LiveSummary"]

SERIES = ("level", "pressure", "peak", "area", "row", "col", "row_sd", "col_sd", "change")
STATS = ("mean", "sd", "min", "max", "last", "delta", "absdiff")
#: the default contact floor, as a fraction of full scale
CONTACT = 0.02


@FEATURES.register("live-summary", description="nine frame-level series of a short window (level, pressure, peak, "
                   "area, centroid, spread, change) summarised: built to decide live (touchbench)")
class LiveSummary(FullScaleSet):
    """Nine frame-level series of a window, seven statistics each, and its length (module docstring).

    Parameters: ``contact`` (the pressure, as a fraction of full scale, from which a cell is in
    contact), ``value_range`` (replaces the sensor's, from Python), ``sensor`` (its value range and
    frame rate).

    Interpretations (the module docstring has each one's reason): each cell's baseline is its lowest
    reading in the window; a frame without pressure has its centroid at the middle of the grid; a
    window of one frame has no changes (0).

    Examples
    --------
    >>> import numpy as np
    >>> from touchbench.datasets.model import SensorSpec
    >>> press = np.zeros((2, 1, 2))
    >>> press[1, 0, 1] = 100.0  # the right cell pressed to full scale in the second frame
    >>> fs = LiveSummary(sensor=SensorSpec("strip", (1, 2), 10.0, (0, 100)))
    >>> f = dict(zip(fs.feature_names((1, 2)), fs.fit_transform([press])[0]))
    >>> [float(f[k]) for k in ("pressure_max", "area_last", "col_last", "change_absdiff", "seconds")]
    [0.5, 0.5, 1.0, 0.5, 0.2]
    """

    name = "live-summary"
    paper = ("touchbench (docs/research/live-recognition.md), after Zhou et al. 2017 section 4.1 and "
             "Gaus et al. 2015 section 5")
    cost = "cheap"
    fold_dependent = False

    _parameter_constraints = {**FullScaleSet._parameter_constraints, "contact": [Interval(Real, 0, 1, closed="neither")]}

    def __init__(self, contact: float = CONTACT, value_range: tuple[float, float] | None = None,
                 sensor: SensorSpec | None = None):
        self.contact = contact
        self.value_range = value_range
        self.sensor = sensor

    def _check_params(self) -> None:
        super()._check_params()
        if self.sensor is None:
            raise SensorNeededError("live-summary: needs the sensor's frame rate (a window's length in seconds): "
                                    "pass sensor=SensorSpec(...)")

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        return [f"{s}_{k}" for s in SERIES for k in STATS] + ["seconds"]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t, h, w = stack.shape
        lo, hi = self._range()
        x = heights(stack, (lo, hi), self._flipped()) / (hi - lo)  # (N, T, C)
        p = x - x.min(axis=1, keepdims=True)
        mass = p.sum(axis=2)  # (N, T)
        rows = np.repeat(np.linspace(0.0, 1.0, h) if h > 1 else np.full(1, 0.5), w)
        cols = np.tile(np.linspace(0.0, 1.0, w) if w > 1 else np.full(1, 0.5), h)
        safe = np.where(mass > 0, mass, 1.0)
        r = np.where(mass > 0, p @ rows / safe, 0.5)
        c = np.where(mass > 0, p @ cols / safe, 0.5)
        r_sd = np.sqrt(np.maximum(np.where(mass > 0, p @ rows ** 2 / safe, 0.25) - r ** 2, 0.0))
        c_sd = np.sqrt(np.maximum(np.where(mass > 0, p @ cols ** 2 / safe, 0.25) - c ** 2, 0.0))
        change = np.zeros((n, t))
        change[:, 1:] = np.abs(np.diff(x, axis=1)).mean(axis=2)
        series = np.stack([x.mean(axis=2), p.mean(axis=2), p.max(axis=2), (p > float(self.contact)).mean(axis=2),
                           r, c, r_sd, c_sd, change], axis=1)  # (N, 9, T)
        absdiff = np.abs(np.diff(series, axis=2)).mean(axis=2) if t > 1 else np.zeros(series.shape[:2])
        stats = np.stack([series.mean(axis=2), series.std(axis=2), series.min(axis=2), series.max(axis=2),
                          series[:, :, -1], series[:, :, -1] - series[:, :, 0], absdiff], axis=2)  # (N, 9, 7)
        return np.hstack([stats.reshape(n, -1), np.full((n, 1), t / float(self.sensor.frame_rate))])
