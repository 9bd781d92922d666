"""``touch-windows``: how touchbench's own features change within a capture.

Not from a paper. The sets of :mod:`touchbench.features.touch` summarise a
whole capture; a gesture whose rhythm or contact changes during the
capture (a tickle that wanders, a pat that slows, a rub that turns into a
stroke) looks the same to them as a steady one. This set computes the
``sets`` (default: ``touch-rhythm``, ``cell-rhythm``, ``contact-motion``)
on ``n_windows`` windows of ``window_s`` seconds each, and returns the mean
and the standard deviation (population, ``ddof=0``) of every feature over
the windows.

Choices (made by cross-validation inside the challenge's training subjects,
docs/research/touch-methods.md, experiment 15; the test subjects were never used):
4 windows of 2 s (108 frames at HAART's 54 Hz), i.e. the 8-s capture cut
into four quarters: +1.0 to +1.6 points over the whole-capture sets alone
with two forest seeds; 7 overlapping windows of 2 s gave the same.

Interpretations and limits:

- The window length is in seconds; its frames come from the sensor's frame
  rate (or an explicit ``frame_rate``); without either the set refuses to
  run. The inner sets get the same rate and value range (their contact
  floors scale with it). A run whose shortest capture is shorter than one window is refused
  before any task (:meth:`TouchWindows.check_sensor`): the windows would
  all be the whole capture.
- Window starts are ``round(linspace(0, T - L, n_windows))`` frames (evenly
  spaced, the first at the capture's start, the last ending at its end);
  ``L = round(window_s * frame rate)``, at least 1 frame, at most ``T``: a
  capture shorter than one window gives ``n_windows`` copies of the whole
  capture, so every standard deviation is 0 (up to rounding of the mean).
- Each window is a capture of its own for the inner sets: its baseline is
  its own 5 % order statistic per cell, and windows shorter than
  ``MIN_FRAMES`` frames are padded as those sets pad.
- Fold-independent: a capture's row depends on that capture alone.
"""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from sklearn.utils._param_validation import Interval

from ..core.suggest import did_you_mean
from ..datasets.model import SensorSpec
from ..datasets.windows import no_frame
from .base import FEATURES, FeatureInputError, FeatureSet
from .touch import _pressure, _TouchBase

OWN_SETS: tuple[str, ...] = ("touch-rhythm", "cell-rhythm", "contact-motion")


@FEATURES.register("touch-windows", description="mean and sd of touch-rhythm + cell-rhythm + contact-motion over 4 windows of 2 s (touchbench)")
class TouchWindows(_TouchBase):
    """Mean and standard deviation of the own feature sets over ``n_windows`` windows.

    Interpretations: the module docstring's (window placement, a capture
    shorter than a window, each window its own capture).
    """

    paper = "touchbench (docs/research/touch-methods.md, experiment 15), after Gaus et al. 2015 section 5"
    cost = "moderate"
    fold_dependent = False

    #: window_s: also at least one frame at the data's rate (``check_sensor``, or ``frame_rate`` when given)
    _parameter_constraints = {**_TouchBase._parameter_constraints,
                              "n_windows": [Interval(Integral, 1, None, closed="left")],
                              "window_s": [Interval(Real, 0, None, closed="neither")], "sets": ["array-like"]}

    def __init__(self, n_windows: int = 4, window_s: float = 2.0, sets: tuple[str, ...] = OWN_SETS,
                 frame_rate: float | None = None, value_range: tuple[float, float] | None = None,
                 sensor: SensorSpec | None = None):
        self.n_windows = n_windows
        self.window_s = window_s
        self.sets = sets
        self.frame_rate = frame_rate
        self.value_range = value_range
        self.sensor = sensor

    def _check_params(self) -> None:
        unknown = [s for s in self.sets if s not in OWN_SETS]
        if not len(self.sets) or unknown:
            hint = did_you_mean(unknown[0], OWN_SETS) if unknown else ""
            raise FeatureInputError(f"touch-windows: sets must name some of {list(OWN_SETS)}, got {self.sets!r}{hint}")
        rate = self.frame_rate if self.frame_rate is not None else getattr(self.sensor, "frame_rate", None)
        problem = None if rate is None else no_frame(self.window_s, rate)
        if problem:
            raise FeatureInputError(f"touch-windows: window_s {problem}")
        super()._check_params()

    def check_sensor(self, sensor: SensorSpec, min_frames: int | None = None) -> str | None:
        problem = super().check_sensor(sensor, min_frames)
        if problem is None and min_frames is not None:
            rate = float(self.frame_rate) if self.frame_rate is not None else float(sensor.frame_rate)
            length = round(float(self.window_s) * rate)
            if length > min_frames:
                problem = (f"touch-windows: its {float(self.window_s):g}-s windows ({length} frames at {rate:g} Hz) are longer "
                           f"than the shortest capture ({min_frames} frames); set window_s to at most {min_frames / rate:g} s")
        return problem

    def _inner(self) -> list[FeatureSet]:
        return [FEATURES.create(name, frame_rate=self._fs(), value_range=self._range()) for name in self.sets]

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        inner = [n for fs in self._inner() for n in fs.feature_names(grid)]
        return [f"win_mean_{n}" for n in inner] + [f"win_sd_{n}" for n in inner]

    def window_starts(self, t: int) -> tuple[np.ndarray, int]:
        """Start frames and length of the windows of a ``t``-frame capture."""
        length = int(min(t, round(float(self.window_s) * self._fs())))
        return np.round(np.linspace(0, t - length, int(self.n_windows))).astype(int), length

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        """Every window of every capture is a capture of its own: the windows are stacked (a group
        of them at a time, at most the chunk's frames), their pressure computed once for all the
        inner sets, and each capture's rows reduced to their mean and standard deviation."""
        n, t, h, w = stack.shape
        starts, length = self.window_starts(t)
        inner = self._inner()
        group = max(1, t // length)
        rows = []
        for k in range(0, len(starts), group):
            frames = starts[k:k + group, None] + np.arange(length)  # (windows, L)
            # (N * windows, ...), capture-major, C order (numpy's sums follow the memory order)
            pr = _pressure(np.ascontiguousarray(stack[:, frames]).reshape(-1, length, h, w))
            rows.append(np.hstack([fs._from_pressure((h, w), *pr) for fs in inner]).reshape(n, len(frames), -1))
        per_window = np.ascontiguousarray(np.concatenate(rows, axis=1).transpose(1, 0, 2))  # (windows, N, D)
        return np.hstack([per_window.mean(axis=0), per_window.std(axis=0)])
