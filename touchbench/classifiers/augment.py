"""Training for shift: every training capture plus copies changed by the sensor's own effects.

``shift-augmented`` takes the captures as recorded (registry tag
``input="captures"``) with a pipeline to train, ``features`` (feature set
names, written as a candidate of ``nested-select``) -> ``estimator`` (with
``params``). ``fit`` trains that pipeline on the original captures plus
``copies`` changed copies of each; labels and subjects (``groups``, which
the run engine passes) are repeated for the copies, so an estimator's inner
cross-validation by subject keeps a capture's copies with it. ``predict``
and ``predict_proba`` compute the features of the captures as given: test
captures are never changed.

Why: a recogniser trained on one study loses accuracy on recordings of the
same sensor made elsewhere (docs/research/contact-features.md): the
sensor's response, its baseline and the shape of its noise differ between
set-ups. Drawing those differences at training time is data augmentation
(as in Um et al. 2017, "Data augmentation of wearable sensor data for
Parkinson's disease monitoring using convolutional neural networks", ICMI:
scaling, jittering, cropping of sensor series); the effects and their
order are the sensor stack of the synthetic scenes
(:mod:`touchbench.scenes.sensor`: gain, baseline, read noise, the ADC's
rounding and clipping), whose ``add_noise`` and ``adc`` make every copy.

Each copy of a ``(T, H, W)`` capture, with the sensor's value range
``lo..hi`` (full scale ``F = hi - lo``), draws from one generator seeded by
``random_state``, in this order (copies in turn, each over every capture):

1. crop: a contiguous window of ``L`` frames starting anywhere, ``L``
   uniform in ``max(ceil(crop T), n) .. T``, where ``n`` is the fewest
   frames the pipeline's feature sets and estimator accept (asked as the
   sensor checks ask them: ``check_sensor(sensor, min_frames=n)``); a capture
   shorter than ``n`` is kept whole;
2. gain ``g`` (uniform in ``gain``): ``x -> r + g (x - r)``, the height above
   the capture's rest level ``r`` multiplied, the rest level kept;
3. offset ``o`` (uniform in ``offset``): ``x -> x + o F`` (``- o F`` on a sensor
   whose higher values mean less pressure: a positive offset is always a
   baseline that reads as more pressure);
4. read noise: Gaussian, standard deviation ``k s`` with ``k`` uniform in
   ``noise`` and ``s`` the capture's own noise floor; its spectrum white, or
   with probability ``ar_share`` an AR(1) along the frames with a
   coefficient uniform in ``ar_coef`` (same standard deviation, a slow
   wander);
5. dead cells: ``round(d H W)`` cells (``d`` uniform in ``dead``; Python's
   rounding), drawn without replacement, held at the rest level after the
   offset (``r + o F``) in every frame;
6. the ADC: rounded (integer dtypes), clipped to ``lo..hi``, cast to the
   capture's dtype.

Interpretations: the rest level ``r`` and noise floor ``s`` are those of
``contact-evidence`` (:func:`touchbench.features.contact.noise_floor`: the
quarter of cells with the lowest median, their median level and 1.4826 x
their median absolute deviation, at least one step of a 10-bit converter),
estimated on the whole capture before cropping; the offset is one shift of
the whole grid (a baseline moved by the set-up), not a pattern per cell;
the added noise is independent between cells; a dead cell reads the rest
level, not zero, so it looks like an untouched cell, not like a broken
sensor.

Defaults, modest on purpose (a copy should look like the same gesture
recorded under another set-up, never like another gesture):

- ``copies=2``: the training set three times its size; the feature sets
  are computed inside every task (the run engine's feature cache holds
  the captures as recorded, not their copies), so training costs about
  ``copies + 1`` times the features of the training captures;
- ``gain=(0.8, 1.25)``: a response 20 % weaker to 25 % stronger,
  symmetric on a log scale;
- ``offset=(0.0, 0.005)``: a baseline up to half a percent of full scale
  higher (5 counts of a 10-bit converter, the cell offsets of the
  synthetic sessions in docs/research/contact-features.md); not lower: a
  sensor that rests near its zero would be clipped there, which no set-up
  shows;
- ``noise=(0.0, 1.0)``: at most as much noise again as the capture has
  (its total standard deviation at most sqrt(2) times its own);
- ``ar_share=0.5``, ``ar_coef=(0.8, 0.98)``: half the copies with a
  wandering noise, its coefficient around the 0.95 of the synthetic
  session that HAART-trained level-free features misread;
- ``dead=(0.0, 0.05)``: up to 5 % of the cells (3 of an 8 x 8 grid);
- ``crop=0.75``: windows from three quarters of the capture to all of it.

Checks: the ranges, fractions and ``copies`` are declared
(``_parameter_constraints``: a protocol's validation refuses a bad value
with its file, line and field; ``fit`` asks the same), ``copies`` at most
:data:`MAX_COPIES` (100), and copies that would take more than a quarter of
the available memory (:func:`touchbench.core.memory.memory_limit`) are
refused in ``fit``, by the training captures' bytes, before any copy is made.

Sensors: pressure grids with a value range. Refused: no sensor (nothing
gives the full scale or the range to round and clip to) and channel sensors
(``sensor.channels``: dead cells, a rest level and a grid-wide offset have
no meaning for separate signals), as ``contact-evidence`` refuses them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any, Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted

from ..core.constraints import ListOf
from ..core.errors import TouchbenchError
from ..core.memory import describe_bytes, memory_limit
from ..features.base import check_captures
from ..features.contact import MIN_NOISE, heights, noise_floor
from ..scenes.sensor import adc, add_noise
from ._util import build, seed_int
from .base import CLASSIFIERS, ParamError, check_declared, check_nested_params
from .fitting import capture_labels, feature_specs, fit_pipeline, pipeline_refusal, proba_over

NAME = "shift-augmented"
#: bytes a copy costs beyond its values (its array's header), at least
COPY_OVERHEAD = 128
SOURCE = ("touchbench (docs/research/contact-features.md, section Training for shift): the synthetic scenes' "
          "sensor effects as data augmentation, after Um et al. 2017 (ICMI), scaling, jittering and cropping")

#: the ranges drawn per copy, each a ``(low, high)`` pair (their domains: :attr:`ShiftAugmented._parameter_constraints`)
RANGES = ("gain", "offset", "noise", "ar_coef", "dead")
#: the most copies of each training capture: the training set at most 101 times its size, its feature
#: sets computed on every copy inside every task
MAX_COPIES = 100


def _pair(low: Interval) -> list:
    """The declared domain of a ``(low, high)`` range whose bounds lie in ``low``."""
    return [ListOf([low], length=2, ordered=True)]


@dataclass(frozen=True)
class Shift:
    """The effects drawn for one copy of one capture (module docstring)."""

    start: int
    length: int
    gain: float
    offset: float
    noise: float
    ar: float
    dead: float


def crop_window(frames: int, crop: float, need: int, rng: np.random.Generator) -> tuple[int, int]:
    """``(start, length)`` of a window of a ``frames``-long capture: ``length`` uniform in
    ``max(ceil(crop * frames), need) .. frames`` (all of it when ``need > frames``), ``start``
    uniform in ``0 .. frames - length``."""
    shortest = min(frames, max(int(need), math.ceil(round(crop * frames, 9))))
    length = int(rng.integers(shortest, frames + 1))
    return int(rng.integers(0, frames - length + 1)), length


def draw_shift(rng: np.random.Generator, ranges: dict[str, tuple[float, float]], ar_share: float, crop: float,
               frames: int, need: int) -> Shift:
    """One copy's effects, drawn in a fixed order (every value drawn whatever the others are)."""
    start, length = crop_window(frames, crop, need, rng)
    gain, offset, noise = (float(rng.uniform(*ranges[k])) for k in ("gain", "offset", "noise"))
    wander, coef = float(rng.random()), float(rng.uniform(*ranges["ar_coef"]))
    dead = float(rng.uniform(*ranges["dead"]))
    return Shift(start, length, gain, offset, noise, coef if wander < ar_share else 0.0, dead)


def dead_cells(cells: int, fraction: float, rng: np.random.Generator) -> np.ndarray:
    """``round(fraction * cells)`` distinct cell indices (row-major), drawn without replacement."""
    return np.sort(rng.permutation(cells)[:int(round(fraction * cells))])


def shifted_copy(capture: np.ndarray, sensor: Any, shift: Shift, rng: np.random.Generator) -> np.ndarray:
    """``capture`` ``(T, H, W)`` changed by ``shift`` (module docstring, steps 1-6), in its dtype."""
    lo, hi = (float(v) for v in sensor.value_range)
    full, flipped = hi - lo, not sensor.higher_is_more_pressure
    rest_h, noise_h = noise_floor(heights(capture[None], (lo, hi), flipped), MIN_NOISE * full)
    sign = -1.0 if flipped else 1.0
    rest = hi - float(rest_h[0]) if flipped else lo + float(rest_h[0])
    x = np.asarray(capture[shift.start:shift.start + shift.length], dtype=np.float64)
    x = rest + shift.gain * (x - rest) + sign * shift.offset * full
    x = add_noise(x, shift.noise * float(noise_h[0]), rng, ar=shift.ar)
    t, h, w = x.shape
    x = x.reshape(t, h * w)
    x[:, dead_cells(h * w, shift.dead, rng)] = rest + sign * shift.offset * full
    return adc(x.reshape(t, h, w), (lo, hi), capture.dtype)


def check_copies_fit(copies: int, capture_bytes: Sequence[int]) -> None:
    """Refuse ``copies`` copies of captures of ``capture_bytes`` bytes each when they would take more
    than :func:`touchbench.core.memory.memory_limit`: each copy costs at most its capture's bytes (a
    crop is never longer) and :data:`COPY_OVERHEAD` (its array)."""
    sizes = list(capture_bytes)
    need = int(copies) * sum(int(b) + COPY_OVERHEAD for b in sizes)
    limit = memory_limit()
    if need > limit:
        raise ParamError("copies", f"{NAME}: copies={copies} would make {int(copies) * len(sizes):,} copies of "
                                   f"{len(sizes):,} training captures, up to {describe_bytes(need)}, over the limit "
                                   f"of {describe_bytes(limit)} (a quarter of the memory available): make copies "
                                   "smaller")


def check_params(params: dict[str, Any]) -> None:
    """The pipeline's estimator's own checks of its ``params`` (the ranges, fractions and ``copies``
    are declared: :attr:`ShiftAugmented._parameter_constraints`)."""
    check_nested_params(params.get("estimator"), dict(params.get("params") or {}), ("params",))


class ShiftAugmented(ClassifierMixin, BaseEstimator):
    """A pipeline trained on captures plus copies changed by the sensor's effects (module docstring).

    Parameters
    ----------
    features : the pipeline's feature sets (names, ``{name, params}`` or ``[name, params]``);
        none for an estimator that takes the captures themselves.
    estimator, params : the registered estimator and its parameters.
    copies : changed copies of each training capture, besides the original (0: none).
    gain, offset, noise, ar_coef, dead : ``(low, high)`` ranges, each drawn uniformly per copy.
    ar_share : the probability that a copy's added noise is AR(1) rather than white.
    crop : the shortest window as a fraction of the capture, in (0, 1].
    sensor : the data's SensorSpec (the run engine passes it); required.
    random_state : seeds the draws and the estimator.
    """

    #: the ranges as the module docstring draws them (gain above 0; offset fractions of full scale
    #: in [-1, 1]; noise at least 0; ar_coef in [0, 1), a stationary AR(1); dead a fraction of the
    #: cells), each low <= high; ``copies`` 0..MAX_COPIES; the estimator's parameters are its own
    #: (``check_params``)
    _parameter_constraints = {
        "features": [list, tuple], "estimator": [str], "params": [dict, None],
        "copies": [Interval(Integral, 0, MAX_COPIES, closed="both")],
        "gain": _pair(Interval(Real, 0, None, closed="neither")),
        "offset": _pair(Interval(Real, -1, 1, closed="both")),
        "noise": _pair(Interval(Real, 0, None, closed="left")),
        "ar_coef": _pair(Interval(Real, 0, 1, closed="left")),
        "dead": _pair(Interval(Real, 0, 1, closed="both")),
        "ar_share": [Interval(Real, 0, 1, closed="both")], "crop": [Interval(Real, 0, 1, closed="right")],
        "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, features=(), estimator="touch-extra-trees", params=None, copies=2, gain=(0.8, 1.25),
                 offset=(0.0, 0.005), noise=(0.0, 1.0), ar_share=0.5, ar_coef=(0.8, 0.98), dead=(0.0, 0.05),
                 crop=0.75, sensor=None, random_state=None):
        self.features = features
        self.estimator = estimator
        self.params = params
        self.copies = copies
        self.gain = gain
        self.offset = offset
        self.noise = noise
        self.ar_share = ar_share
        self.ar_coef = ar_coef
        self.dead = dead
        self.crop = crop
        self.sensor = sensor
        self.random_state = random_state

    # -- parameters -------------------------------------------------------------
    def _ranges(self) -> dict[str, tuple[float, float]]:
        """Every range as floats, every parameter checked against its declared domain."""
        check_declared(self)
        return {name: (float(getattr(self, name)[0]), float(getattr(self, name)[1])) for name in RANGES}

    def _pipeline(self) -> tuple[list[tuple[str, dict[str, Any]]], str, dict[str, Any]]:
        return feature_specs(self.features), str(self.estimator), dict(self.params or {})

    def check_sensor(self, sensor: Any, min_frames: int | None = None) -> str | None:
        """Why this augmentation or its pipeline cannot serve ``sensor`` (a channel sensor, a feature
        set or estimator that refuses it), or None."""
        self._ranges()
        if getattr(sensor, "channels", None) is not None:
            return (f"sensor {sensor.describe()} is a channel sensor ({', '.join(sensor.channels)}): its channels "
                    "are not cells of a pressure surface, so dead cells, a rest level and an offset of one full "
                    "scale have no meaning there")
        return pipeline_refusal(*self._pipeline(), sensor, min_frames)

    def frames_needed(self, longest: int) -> int:
        """The fewest frames (at most ``longest``) the pipeline accepts for the sensor: the shortest
        window a crop may take. Found by bisection, the refusals being monotone in the frames."""
        sets, est, params = self._pipeline()

        def serves(n: int) -> bool:
            return pipeline_refusal(sets, est, params, self.sensor, n) is None

        if serves(1):
            return 1
        low, high = 1, max(1, int(longest))  # refused at low; served at high (else the sensor check refuses)
        while high - low > 1:
            mid = (low + high) // 2
            low, high = (low, mid) if serves(mid) else (mid, high)
        return high

    # -- the training set -----------------------------------------------------
    def _checked(self, X: Any) -> list[np.ndarray]:
        """The captures, checked against the sensor (present, a grid, the grid of the captures)."""
        captures = check_captures(X, name=NAME)
        sensor = self.sensor
        if sensor is None:
            raise TouchbenchError(f"{NAME}: needs the sensor's value range (the offset's full scale, the range "
                                  "every copy is rounded and clipped to): pass sensor=SensorSpec(...)")
        problem = self.check_sensor(sensor, min(len(c) for c in captures) if captures else None)
        if problem:
            raise TouchbenchError(f"{NAME} cannot serve sensor {sensor.describe()}: {problem}")
        grid = tuple(int(g) for g in sensor.grid)
        if captures and tuple(captures[0].shape[1:]) != grid:
            raise TouchbenchError(f"{NAME}: captures of grid {tuple(captures[0].shape[1:])} are not on the grid of "
                                  f"sensor {sensor.describe()}")
        return captures

    def augmented(self, X: Any) -> list[np.ndarray]:
        """The training captures: ``X`` as given, then copy 1 of every capture, copy 2... (the same
        list for the same captures and ``random_state``)."""
        return self._augment(self._checked(X))

    def _augment(self, captures: list[np.ndarray]) -> list[np.ndarray]:
        ranges, copies = self._ranges(), int(self.copies)
        if not captures or copies == 0:
            return list(captures)
        check_copies_fit(copies, [c.nbytes for c in captures])  # before any copy is made
        need = self.frames_needed(max(len(c) for c in captures))
        rng = np.random.default_rng(seed_int(self.random_state))
        out = list(captures)
        for _ in range(copies):
            for c in captures:
                shift = draw_shift(rng, ranges, float(self.ar_share), float(self.crop), len(c), need)
                out.append(shifted_copy(c, self.sensor, shift, rng))
        return out

    # -- API --------------------------------------------------------------------
    def fit(self, X: Sequence[np.ndarray], y: Any, groups: Any = None) -> "ShiftAugmented":
        """Fit the pipeline on the captures and their copies (labels and ``groups`` repeated)."""
        captures = self._checked(X)
        y = capture_labels(y, captures, NAME)
        self.classes_ = np.unique(y)
        train = self._augment(captures)
        reps = int(self.copies) + 1
        g = None if groups is None else np.tile(np.asarray(groups), reps)
        sets, est, params = self._pipeline()
        self.method_ = fit_pipeline(sets, est, params, seed_int(self.random_state), train, np.tile(y, reps), g,
                                    sensor=self.sensor)
        self.n_training_ = len(train)
        return self

    def predict(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """The labels of the captures as given (their features unchanged)."""
        check_is_fitted(self)
        return self.method_.predict(check_captures(X, name=NAME))

    def predict_proba(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """Probabilities over ``classes_`` of the captures as given."""
        check_is_fitted(self)
        return proba_over(self.method_.fitted, self.method_.transform(check_captures(X, name=NAME)), self.classes_)


DEFAULTS = {"features": (), "estimator": "touch-extra-trees", "params": {}, "copies": 2, "gain": (0.8, 1.25),
            "offset": (0.0, 0.005), "noise": (0.0, 1.0), "ar_share": 0.5, "ar_coef": (0.8, 0.98),
            "dead": (0.0, 0.05), "crop": 0.75}


@CLASSIFIERS.register(
    NAME,
    description="a pipeline (feature sets -> estimator) trained on the captures plus copies changed by the "
                "sensor's effects: gain, offset, read noise (white or AR(1)), dead cells, a window anywhere",
    source=SOURCE, defaults=DEFAULTS, extra=None, input="captures", check_params=check_params,
    cheap_params=dict(features=["contact-evidence"], estimator="zhou-tree", copies=1),
)
def shift_augmented(random_state=None, sensor=None, **params):
    return build(ShiftAugmented, DEFAULTS, random_state, {**params, "sensor": sensor}, name=NAME)
