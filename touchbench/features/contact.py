"""Contact evidence: how far a capture's readings stand above the sensor's zero and its noise.

Not from a paper: designed so that a capture with no touch looks the same
under another recording setup (docs/research/contact-features.md). The
level-free sets of :mod:`touchbench.features.touch` remove each capture's
level (a per-cell baseline, level-normalised series): for a capture with
no touch that leaves only the sensor's noise, whose shape (white, slowly
wandering) differs between setups, so a model trained under one setup may
read another setup's noise as a touch. This set keeps what those sets
remove, kept beside them (``touch-et-contact`` combines them):

- the capture's level as a fraction of the sensor's full scale, as Gaus et
  al. 2015, Sec. 3.2.1 (Table 3) separate "no touch" (the minimum pressure)
  from "touched" cells by their level;
- how much of the capture stands above its rest level by ``k`` units of
  the capture's own noise floor, for ``k`` in 3, 10 and 30; a threshold
  relative to the capture's spread as Zhou et al. 2017, Sec. 4.1's contact
  area ``D6`` (pixels above mean + standard deviation), but with the spread
  of the untouched cells only, so a large contact does not raise its own
  threshold;
- peak-over-noise ratios and the temporal spread of the cells relative to
  the noise floor.

Definitions (``lo``, ``hi`` the sensor's value range, ``F = hi - lo`` its
full scale; ``u`` a reading's height above the sensor's zero, ``x - lo``,
or ``hi - x`` on a sensor whose higher values mean less pressure):

- ``level_mean``, ``level_p50``, ``level_p95``, ``level_max``: the mean,
  the 50 % and 95 % order statistics (rank ``round(q (n - 1))`` of the
  ``n = T * H * W`` readings, 0-based, Python's rounding) and the maximum of
  ``u``, divided by ``F``; ``cellmean_min``, ``cellmean_max``: the lowest
  and highest of the cells' means over the frames, divided by ``F``.
- Quiet cells: the ``max(1, floor(H * W / 4))`` cells of lowest median
  over the frames (ties: the first in row-major order). An interpretation:
  no gesture of HAART or CoST covers more than three quarters of the grid
  all the time, so the quiet cells are untouched, and a hand held still
  (``constant``) does not pass for quiet as it would if cells were ranked
  by their variation.
- Rest level ``r``: the median of the quiet cells' medians. Noise floor
  ``s``: ``1.4826`` x the median of the quiet cells' MADs (each cell's
  median absolute deviation from its median over the frames: the standard
  deviation for Gaussian noise), at least ``min_noise * F``. An
  interpretation: the spread of the readings themselves, not of their
  frame-to-frame differences: differences see only the fast part of the
  noise, so a slowly wandering (low-pass) noise would count as many noise
  units and pass for a touch. ``min_noise`` (default ``1 / 1023``, one step
  of HAART's 10-bit converter as a fraction of full scale) keeps the ratios
  finite on integer readings whose noise is below one step.
- A sensor whose higher values mean less pressure
  (``higher_is_more_pressure=False``) is read from the top of its range
  (``u = hi - x``), an interpretation: its rest is near ``hi``.
- ``above{k}_frac``: the fraction of readings above ``r + k s``;
  ``above{k}_frames``: the fraction of frames with at least one such
  reading; ``above{k}_cells``: the fraction of cells whose mean is above
  ``r + k s``; for ``k`` in ``NOISE_UNITS`` (3, 10, 30).
- ``peak_over_noise``: ``(max u - r) / s``; ``cellmean_over_noise``:
  ``(highest cell mean - r) / s``; ``tstd_mean_over_noise``,
  ``tstd_max_over_noise``: the mean and the maximum over cells of each
  cell's standard deviation over the frames (population), divided by ``s``.

Properties: a capture's features depend on that capture alone
(``fold_dependent = False``), every feature is finite for finite input (a
constant capture: levels, rest level, zero exceedances and ratios). Gain:
with ``lo = 0``, readings multiplied by ``g > 0`` multiply the six level
features by ``g`` and leave the others unchanged, as long as the noise
floor stays above ``min_noise * F`` in both. An offset added to every
reading moves the level features only.

Sensors: grids of pressure readings with a value range (the sensor's, or
``value_range`` from Python). Refused: no sensor and no ``value_range``
(nothing is a fraction of full scale without one), and channel sensors
(``sensor.channels``: their readings are signals of separate channels, not
pressure of cells on one full scale).
"""

from __future__ import annotations

from numbers import Real

from typing import Any

import numpy as np

from sklearn.utils._param_validation import Interval

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, SensorNeededError
from .numerics import sort_last
from ..core.compiled import kernels

#: multiples of the noise floor above the rest level at which contact is counted
NOISE_UNITS: tuple[int, ...] = (3, 10, 30)
#: the default floor of the noise estimate, as a fraction of full scale (one step of a 10-bit converter)
MIN_NOISE = 1.0 / 1023.0
#: MAD -> standard deviation for Gaussian noise
MAD_TO_SD = 1.4826
QUIET_SHARE = 0.25


class FullScaleSet(FeatureSet):
    """A set that reads pressure on the sensor's full scale: ``value_range`` (from Python) or the
    sensor's; refused without either, and for a channel sensor (its channels are not cells of one
    pressure surface). Subclasses set ``name`` and keep ``value_range`` and ``sensor`` as parameters."""

    name = "a full-scale set"
    _parameter_constraints = {"value_range": ["array-like", None]}
    value_range: Any = None
    sensor: Any = None

    def _range(self) -> tuple[float, float]:
        if self.value_range is not None:
            try:
                lo, hi = (float(v) for v in self.value_range)
            except (TypeError, ValueError):
                lo, hi = np.nan, np.nan
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise FeatureInputError(f"{self.name}: value_range must be (low, high) with low < high, "
                                        f"got {self.value_range!r}")
            return lo, hi
        if self.sensor is None:
            raise SensorNeededError(f"{self.name}: needs the sensor's value range (its levels are fractions "
                                    "of full scale): pass sensor=SensorSpec(...) or value_range=(low, high)")
        lo, hi = self.sensor.value_range
        return float(lo), float(hi)

    def _check_params(self) -> None:
        sensor = self.sensor
        if sensor is not None and getattr(sensor, "channels", None) is not None:
            raise FeatureInputError(
                f"{self.name}: sensor {sensor.describe()} is a channel sensor ({', '.join(sensor.channels)}): its "
                "channels are not cells of a pressure surface, so a level on one full scale and quiet cells have no "
                "meaning there")
        self._range()

    def _flipped(self) -> bool:
        return self.sensor is not None and not self.sensor.higher_is_more_pressure


@FEATURES.register("contact-evidence",
                   description="level as a fraction of full scale and contact above the capture's noise floor (touchbench)")
class ContactEvidence(FullScaleSet):
    """``contact-evidence``: level, contact above noise, peak and spread over noise (module docstring).

    Parameters: ``value_range`` (replaces the sensor's, from Python),
    ``min_noise`` (the noise floor's lower bound as a fraction of full
    scale, in (0, 1)), ``sensor``.

    Interpretations (the module docstring has each one's reason): the quiet
    cells are the quarter of lowest median; the noise floor is the spread
    of their readings, not of their frame-to-frame differences; its lower
    bound is one step of a 10-bit converter; a sensor whose higher values
    mean less pressure is read from the top of its range.
    """

    name = "contact-evidence"
    _parameter_constraints = {**FullScaleSet._parameter_constraints, "min_noise": [Interval(Real, 0, 1, closed="neither")]}
    paper = "touchbench (docs/research/contact-features.md), after Gaus et al. 2015 section 3.2.1 and Zhou et al. 2017 section 4.1"
    cost = "cheap"
    fold_dependent = False

    def __init__(self, value_range: tuple[float, float] | None = None, min_noise: float = MIN_NOISE,
                 sensor: SensorSpec | None = None):
        self.value_range = value_range
        self.min_noise = min_noise
        self.sensor = sensor

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        names = ["level_mean", "level_p50", "level_p95", "level_max", "cellmean_min", "cellmean_max"]
        for k in NOISE_UNITS:
            names += [f"above{k}_frac", f"above{k}_frames", f"above{k}_cells"]
        return names + ["peak_over_noise", "cellmean_over_noise", "tstd_mean_over_noise", "tstd_max_over_noise"]

    def _heights(self, stack: np.ndarray) -> tuple[np.ndarray, float]:
        """``(N, T, H, W)`` -> heights above the sensor's zero ``(N, T, C)`` float64 and the full scale."""
        lo, hi = self._range()
        return heights(stack, (lo, hi), self._flipped()), hi - lo

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        u, full = self._heights(stack)
        n, t, c = u.shape
        kern = kernels("features.evidence_kernels")
        if kern is not None:
            lo, hi = self._range()
            # whole-number heights of a short span (readings of up to 16 bits): read off counts, unsorted
            integral = (stack.dtype.kind in "biu" and stack.dtype.itemsize <= 2 and float(lo).is_integer()
                        and float(hi).is_integer())
            out = np.zeros((n, 10 + 3 * len(NOISE_UNITS)))
            kern.evidence(u, np.empty((n, 0)) if integral else sorted_heights(stack, (lo, hi), self._flipped()),
                          self.min_noise * full, np.array(NOISE_UNITS, dtype=np.float64),
                          max(1, int(np.floor(QUIET_SHARE * c))),
                          np.array([round(0.5 * (t * c - 1)), round(0.95 * (t * c - 1))]), full, integral, out)
            return out
        flat = sorted_heights(stack, self._range(), self._flipped())
        cell_mean = u.mean(axis=1)
        level = [flat.mean(axis=1), flat[:, round(0.5 * (t * c - 1))], flat[:, round(0.95 * (t * c - 1))],
                 flat[:, -1], cell_mean.min(axis=1), cell_mean.max(axis=1)]
        rest, noise = noise_floor(u, self.min_noise * full)
        cols = [v / full for v in level]
        thr = rest[:, None] + np.multiply.outer(noise, NOISE_UNITS)  # (N, units)
        # readings above a threshold counted in the sorted readings; a frame has one above it when its
        # highest reading is
        above = t * c - np.stack([np.searchsorted(row, x, side="right") for row, x in zip(flat, thr)])
        frame_max = u.max(axis=2)
        for i in range(len(NOISE_UNITS)):
            cols += [above[:, i] / (t * c), (frame_max > thr[:, i, None]).mean(axis=1), (cell_mean > thr[:, i, None]).mean(axis=1)]
        dev = u - cell_mean[:, None, :]
        tstd = np.sqrt(np.einsum("ntc,ntc->nc", dev, dev) / t)  # population standard deviation
        cols += [(flat[:, -1] - rest) / noise, (cell_mean.max(axis=1) - rest) / noise,
                 tstd.mean(axis=1) / noise, tstd.max(axis=1) / noise]
        return np.column_stack(cols)


def heights(stack: np.ndarray, value_range: tuple[float, float], flipped: bool = False) -> np.ndarray:
    """Readings ``(N, T, H, W)`` as heights above the sensor's zero, ``(N, T, H * W)`` float64:
    ``x - lo``, or ``hi - x`` on a sensor whose higher values mean less pressure (``flipped``)."""
    lo, hi = (float(v) for v in value_range)
    n, t, h, w = np.shape(stack)
    x = np.asarray(stack, dtype=np.float64).reshape(n, t, h * w)
    return hi - x if flipped else x - lo


def sorted_heights(stack: np.ndarray, value_range: tuple[float, float], flipped: bool = False) -> np.ndarray:
    """Each capture's heights (:func:`heights`) sorted, ``(N, T * H * W)``: the readings are sorted
    first (by radix sort for integers of up to 16 bits) and mapped after, the same values as sorting
    the heights, since a height is a monotone function of the reading."""
    n = np.shape(stack)[0]
    srt = heights(sort_last(np.asarray(stack).reshape(n, -1)).reshape(n, 1, -1, 1), value_range, flipped).reshape(n, -1)
    return srt[:, ::-1] if flipped else srt


def noise_floor(u: np.ndarray, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """Rest level and noise floor ``(N,)`` of heights ``u`` ``(N, T, C)``: the quiet cells' median
    level and 1.4826 x their median MAD, at least ``floor`` (module docstring). Only the quiet
    cells' MADs are computed."""
    c = u.shape[2]
    med = _median_last(np.ascontiguousarray(np.swapaxes(u, 1, 2)))
    q = max(1, int(np.floor(QUIET_SHARE * c)))
    quiet = np.argsort(med, axis=1, kind="stable")[:, :q]
    qmed = np.take_along_axis(med, quiet, axis=1)
    dev = np.abs(np.take_along_axis(u, quiet[:, None, :], axis=2) - qmed[:, None, :])  # (N, T, quiet)
    dev = np.ascontiguousarray(np.swapaxes(dev, 1, 2))
    rest = np.median(qmed, axis=1)
    noise = MAD_TO_SD * np.median(_median_last(dev), axis=1)
    return rest, np.maximum(noise, floor)


def _median_last(x: np.ndarray) -> np.ndarray:
    """``numpy.median`` along the last axis (the mean of the two middle values of an even count),
    partitioning ``x`` in place (once: a partition at two ranks costs twice as much)."""
    m = x.shape[-1] // 2
    x.partition(m, axis=-1)
    if x.shape[-1] % 2:
        return x[..., m].copy()
    return (x[..., :m].max(axis=-1) + x[..., m]) / 2.0  # the largest below the middle: the other middle value
