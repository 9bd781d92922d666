"""The scene description: a YAML file validated with pydantic.

A scene declares a sensor, a gesture vocabulary, a population and the
recording protocol, and lists the *effects* it needs (``effects:``). The
generator simulates those effects and nothing else, and the validator holds
the YAML to that: a configuration block for an effect that is not listed is
an error, and so is a listed effect without the configuration it needs
(``cover`` without ``protocol.covers``, ``curvature`` without a radius...).

Every validation error names the field (``protocol.covers.fur.transmission:
...``), and :mod:`touchbench.scenes.loading` adds the file and line. Numbers
are finite (``.inf`` and ``.nan`` are refused), the value range fits the
dtype, and a gain, noise or saturation level stays within what the float32
electronics compute (:data:`FLOAT32_COUNTS`). Units: millimetres, seconds,
newtons; sensor values in ADC counts.

Effects (see the module that implements each):

========== ==================================================================
style       persistent per-person, per-gesture style (person.py; Flagg 2012
            Sec. 4.4: people differ widely but are consistent)
handedness  left-handed people and hand alternation mirror the kinematics
variant     gentle / normal / rough scale force and speed (CoST)
session     a second recording drifts style and baseline (Zhou group A)
group       groups whose instructions differ (Zhou Sec. 3.2: group A did
            scratch and stroke as bursts of three)
substrate   soft substrate spreads and delays the pressure (HAART foam)
cover       a cover blurs and attenuates (HAART fur / minky)
curvature   a curved surface narrows flat contacts and adds wrap tension
crosstalk   neighbouring cells leak into each other
saturation  soft saturation of the sensing material below the ADC limit
baseline    resting per-cell offset
noise       Gaussian read noise
========== ==================================================================

The hand (contact primitives), gesture kinematics, the person's hand size,
force and tempo, and the ADC (gain, quantisation, clipping to the value
range) are the scene itself, always simulated.
"""

from __future__ import annotations

import re
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..core.suggest import did_you_mean
from .gestures import LIBRARY, GestureParams

Effect = Literal[
    "style",
    "handedness",
    "variant",
    "session",
    "group",
    "substrate",
    "cover",
    "curvature",
    "crosstalk",
    "saturation",
    "baseline",
    "noise",
]
CHANNELS = ("x", "y", "pressure", "fur")
#: the largest gain, noise or saturation level (counts) the float32 electronics take: a gain of
#: this many counts per newton still leaves a force of 10^6 N finite in float32 (3.4e38)
FLOAT32_COUNTS = 1e32

_NonNeg = Field(ge=0)


class _Strict(BaseModel):
    # a scene's numbers are finite: .inf or .nan in a scene file is refused, naming the field
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


# ----------------------------------------------------------------- sensor
class Curvature(_Strict):
    """The sensor wrapped round a cylinder of ``radius_mm`` (CoST: a
    mannequin arm; Zhou Sec. 3.1: only for grab). ``axis`` is the grid axis
    that runs round the circumference. ``gestures`` limits it to those
    gestures (the sensor was moved onto the arm for them)."""

    radius_mm: float = Field(gt=0)
    axis: Literal["x", "y"] = "x"
    gestures: list[str] | None = None
    tension: float = Field(0.0, ge=0, description="resting bias from wrapping, counts")


class Baseline(_Strict):
    """Resting offset: ``level`` counts on average, per-cell pattern with
    coefficient of variation ``spread`` (gamma), drifting from capture to
    capture by a log-normal factor with log-sd ``drift``."""

    level: float = Field(ge=0)
    spread: float = Field(0.5, ge=0)
    drift: float = Field(0.2, ge=0)
    structure: Literal["cells", "lines"] = "cells"


class ChannelResponse(_Strict):
    """How the channel sensor (Flagg Sec. 4.2) turns touch into x, y,
    pressure and fur readings: ``pressure_gain`` counts per newton of total
    force, ``fur_motion_gain`` counts per mm/s of hand motion in contact,
    ``fur_touch_gain`` counts per touching contact (light touches move the
    fur without pressure), ``contact_n`` the force above which x and y
    follow the touch, ``rest`` the channels' readings without touch."""

    pressure_gain: float = Field(gt=0)
    fur_motion_gain: float = Field(ge=0)
    fur_touch_gain: float = Field(ge=0)
    contact_n: float = Field(0.3, gt=0)
    rest: dict[str, float]

    @field_validator("rest")
    @classmethod
    def _rest_channels(cls, v: dict[str, float]) -> dict[str, float]:
        missing = [c for c in CHANNELS if c not in v]
        extra = [c for c in v if c not in CHANNELS]
        if missing or extra:
            raise ValueError(f"needs exactly the channels {list(CHANNELS)} (missing {missing}, unknown {extra})")
        return v


class SensorModel(_Strict):
    name: str | None = None
    kind: Literal["grid", "channels"] = "grid"
    grid: tuple[int, int] = Field(description="(H, W); for a channel sensor the touch surface it senses")
    pitch_mm: float = Field(gt=0)
    frame_rate: float = Field(gt=0)
    value_range: tuple[float, float] = (0.0, 1023.0)
    dtype: Literal["uint8", "uint16", "int16", "int32", "float32", "float64"] = "uint16"
    gain: float | None = Field(None, gt=0, description="counts per newton on one cell (grid sensors)")
    channels: list[str] | None = None
    response: ChannelResponse | None = None
    noise_sd: float | None = Field(None, ge=0)
    baseline: Baseline | None = None
    crosstalk: float | None = Field(None, ge=0, le=0.25)
    saturation: float | None = Field(None, gt=0)
    curvature: Curvature | None = None

    @field_validator("grid")
    @classmethod
    def _grid(cls, v: tuple[int, int]) -> tuple[int, int]:
        if v[0] < 1 or v[1] < 1:
            raise ValueError("must be at least 1 x 1")
        return v

    @model_validator(mode="after")
    def _kind(self) -> "SensorModel":
        lo, hi = self.value_range
        if not lo < hi:
            raise ValueError("value_range: low must be below high")
        self._check_representable()
        if self.kind == "channels":
            if self.channels is None or tuple(self.channels) != CHANNELS:
                raise ValueError(f"channels: a channel sensor has channels {list(CHANNELS)}")
            if self.response is None:
                raise ValueError("response: a channel sensor needs its channel response")
            if self.gain is not None:
                raise ValueError("gain: a channel sensor's gains are in its response")
        else:
            if self.gain is None:
                raise ValueError("gain: a grid sensor needs its gain (counts per newton on one cell)")
            if self.channels is not None:
                raise ValueError("channels: only a sensor of kind 'channels' names channels")
            if self.response is not None:
                raise ValueError("response: only a sensor of kind 'channels' has a channel response")
        return self

    def _check_representable(self) -> None:
        """The value range fits the dtype (else clipping then casting wraps round), and the
        counts the electronics compute in float32 stay finite there."""
        dt = np.dtype(self.dtype)
        info = np.iinfo(dt) if dt.kind in "iu" else np.finfo(dt)
        lo, hi = self.value_range
        if lo < info.min or hi > info.max:
            raise ValueError(f"value_range: [{lo:g}, {hi:g}] does not fit {self.dtype} ({info.min:g} .. {info.max:g})")
        for name in ("gain", "noise_sd", "saturation"):
            v = getattr(self, name)
            if v is not None and v > FLOAT32_COUNTS:
                raise ValueError(f"{name}: {v:g} is beyond what the sensor's electronics compute (float32 counts: "
                                 f"at most {FLOAT32_COUNTS:g})")


# ------------------------------------------------------------- population
class Spread(_Strict):
    """Log-sd of the multiplicative factors (force, rate, contact time,
    amplitude, oscillation frequency), sd of the direction in degrees and of
    the location in mm."""

    sd: float = Field(ge=0)
    angle_deg: float = Field(0.0, ge=0)
    location_mm: float = Field(0.0, ge=0)


class Population(_Strict):
    subjects: int | None = Field(None, ge=1)
    hand_length_mm: tuple[float, float] = (185.0, 10.0)
    force_sd: float = Field(0.25, ge=0, description="log-sd of a person's force")
    tempo_sd: float = Field(0.15, ge=0, description="log-sd of a person's tempo")
    left_handed: float | None = Field(None, ge=0, le=1)
    style: Spread | None = None
    repetition: Spread = Spread(sd=0.1, angle_deg=5.0, location_mm=5.0)


# -------------------------------------------------------------- protocol
class Variant(_Strict):
    force: float = Field(gt=0)
    speed: float = Field(gt=0)


class Substrate(_Strict):
    """What lies under the sensor: ``spread_mm`` widens every contact (sd
    added in quadrature), ``delay_s`` is the time constant of a first-order
    lag on the force (foam gives slowly), ``gain`` scales the transmitted
    force, ``radius_mm`` makes it curved (needs the curvature effect),
    ``tension`` the resting bias (counts) of a sensor stretched over it."""

    spread_mm: float = Field(0.0, ge=0)
    delay_s: float = Field(0.0, ge=0)
    gain: float = Field(1.0, gt=0)
    radius_mm: float | None = Field(None, gt=0)
    tension: float = Field(0.0, ge=0)

    @model_validator(mode="after")
    def _tension_needs_curve(self) -> "Substrate":
        if self.tension > 0 and self.radius_mm is None:
            raise ValueError("tension: only a curved substrate (radius_mm) stretches the sensor")
        return self


class Cover(_Strict):
    """What lies over the sensor: ``transmission`` of force, ``blur_mm``
    (sd added in quadrature), ``deadband_n`` force the pile absorbs before
    any reaches the sensor."""

    transmission: float = Field(1.0, gt=0, le=1)
    blur_mm: float = Field(0.0, ge=0)
    deadband_n: float = Field(0.0, ge=0)


class Group(_Strict):
    """A group of people recorded under its own instructions (Zhou Sec. 3.2)."""

    subjects: int = Field(ge=1)
    sessions: int = Field(1, ge=1)
    hands: Literal["dominant", "both"] = "dominant"
    instructions: dict[str, dict[str, Any]] = Field(default_factory=dict)


class Segmentation(_Strict):
    """``fixed``: windows of ``frames`` frames cut from a continuous
    performance (HAART, Flagg). ``contact``: cut at the touch, from first to
    last contact plus up to ``pad_s`` either side, kept within
    [``min_s``, ``max_s``] (CoST, Zhou)."""

    mode: Literal["fixed", "contact"]
    frames: int | None = Field(None, ge=1)
    pad_s: float = Field(0.0, ge=0)
    min_s: float | None = Field(None, gt=0)
    max_s: float | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _mode(self) -> "Segmentation":
        if self.mode == "fixed" and self.frames is None:
            raise ValueError("frames: a fixed segmentation needs the window length in frames")
        if self.mode == "contact" and self.frames is not None:
            raise ValueError("frames: only a fixed segmentation has a window length")
        if self.min_s is not None and self.max_s is not None and self.min_s > self.max_s:
            raise ValueError("min_s is above max_s")
        return self


class Split(_Strict):
    """A train/test split by subject; captures of other subjects, or of
    variants not in ``variants``, get split ``none``."""

    train: list[str]
    test: list[str]
    variants: list[str] | None = None

    @model_validator(mode="after")
    def _disjoint(self) -> "Split":
        both = sorted(set(self.train) & set(self.test))
        if both:
            raise ValueError(f"subjects {both} are in both train and test")
        return self


class Protocol(_Strict):
    repetitions: int = Field(1, ge=1)
    sessions: int = Field(1, ge=1)
    session_sd: float = Field(0.3, ge=0, description="session drift, as a fraction of the style spread")
    variants: dict[str, Variant] | None = None
    substrates: dict[str, Substrate] | None = None
    covers: dict[str, Cover] | None = None
    groups: dict[str, Group] | None = None
    segmentation: Segmentation
    split: Split | None = None
    lost: int = Field(0, ge=0, description="captures lost in recording, dropped at random")


# ------------------------------------------------------------ gestures
def _check_gesture_override(where: str, gesture: str, params: dict[str, Any]) -> None:
    fields = GestureParams.__dataclass_fields__  # type: ignore[attr-defined]
    for k, v in params.items():
        if k not in fields:
            raise ValueError(f"{where}.{gesture}.{k}: unknown gesture parameter (known: {', '.join(fields)})")
        try:
            GestureParams.check_value(k, v)
        except ValueError as e:
            raise ValueError(f"{where}.{gesture}.{k}: {e}") from None


# ------------------------------------------------------------ calibration
class Calibration(_Strict):
    """Where a calibrated value comes from: a property the paper leaves
    unstated (how noisy, how distinct two people are), chosen so that one
    named table of the paper is reproduced; the paper's other tables are
    the check."""

    table: str = Field(min_length=1, description="the table or figure the value was chosen on")
    protocols: list[str] = Field(min_length=1, description="the paper protocols that compute that table")
    measured_by: str = Field(min_length=1, description="the command that measured the candidates")


# ---------------------------------------------------------------- scene
class SceneSpec(_Strict):
    name: str
    description: str
    seed: int = Field(default=0, ge=0, description="the seed of every random draw (a whole number >= 0)")
    effects: list[Effect]
    sensor: SensorModel
    population: Population
    gestures: dict[str, dict[str, Any] | None]
    protocol: Protocol
    real_counterpart: str | None = None
    calibrated: dict[str, Calibration] = Field(default_factory=dict)

    @field_validator("calibrated")
    @classmethod
    def _calibrated_paths(cls, v: dict[str, Calibration]) -> dict[str, Calibration]:
        for path in v:
            if not re.fullmatch(r"[A-Za-z_]\w*(\.\w+)+", path):
                raise ValueError(f"{path}: a property's dotted path, e.g. population.repetition.sd")
        return v

    @field_validator("effects")
    @classmethod
    def _unique(cls, v: list[str]) -> list[str]:
        dup = sorted({e for e in v if v.count(e) > 1})
        if dup:
            raise ValueError(f"listed twice: {dup}")
        return v

    @field_validator("gestures")
    @classmethod
    def _gestures(cls, v: dict[str, dict[str, Any] | None]) -> dict[str, dict[str, Any] | None]:
        if not v:
            raise ValueError("a scene needs at least one gesture")
        for g, over in v.items():
            if g not in LIBRARY:
                hint = did_you_mean(g, LIBRARY, cutoff=0.6, quote=False)
                raise ValueError(f"{g}: unknown gesture{hint} (known: {', '.join(sorted(LIBRARY))})")
            _check_gesture_override("gestures", g, over or {})
        return v

    @model_validator(mode="after")
    def _effects_match_configuration(self) -> "SceneSpec":
        fx = set(self.effects)
        s, pro = self.sensor, self.protocol
        self._check_configured_effects(fx)
        self._check_curvature(fx)
        self._check_sessions_and_hands(fx)
        self._check_people()
        self._check_split()
        self._check_calibrated()
        if s.kind == "channels" and ("crosstalk" in fx or "curvature" in fx):
            raise ValueError("effects: crosstalk and curvature apply to grid sensors only")
        if pro.segmentation.mode == "fixed" and (pro.segmentation.min_s or pro.segmentation.max_s):
            raise ValueError("protocol.segmentation: min_s/max_s apply to contact segmentation only")
        n_total = n_captures(self)
        if pro.lost >= n_total:
            raise ValueError(f"protocol.lost: {pro.lost} is not fewer than the {n_total} captures")
        return self

    def _check_configured_effects(self, fx: set[str]) -> None:
        """Each effect that one field configures is listed exactly when that field is given."""
        s, pop, pro = self.sensor, self.population, self.protocol
        # (effect, configured?, field that configures it)
        pairs = [
            ("noise", s.noise_sd is not None, "sensor.noise_sd"),
            ("baseline", s.baseline is not None, "sensor.baseline"),
            ("crosstalk", s.crosstalk is not None, "sensor.crosstalk"),
            ("saturation", s.saturation is not None, "sensor.saturation"),
            ("style", pop.style is not None, "population.style"),
            ("handedness", pop.left_handed is not None, "population.left_handed"),
            ("variant", pro.variants is not None, "protocol.variants"),
            ("substrate", pro.substrates is not None, "protocol.substrates"),
            ("cover", pro.covers is not None, "protocol.covers"),
            ("group", pro.groups is not None, "protocol.groups"),
        ]
        for effect, configured, where in pairs:
            if configured and effect not in fx:
                raise ValueError(f"{where}: given, but effect {effect!r} is not listed in effects")
            if effect in fx and not configured:
                raise ValueError(f"effects: {effect!r} is listed but {where} is not given")

    def _check_curvature(self, fx: set[str]) -> None:
        """'curvature' is listed exactly when the sensor or a substrate is curved; the curved gestures are the scene's."""
        s, pro = self.sensor, self.protocol
        curved_substrates = [k for k, v in (pro.substrates or {}).items() if v.radius_mm is not None]
        has_curve = s.curvature is not None or bool(curved_substrates)
        if has_curve and "curvature" not in fx:
            where = "sensor.curvature" if s.curvature is not None else f"protocol.substrates.{curved_substrates[0]}.radius_mm"
            raise ValueError(f"{where}: given, but effect 'curvature' is not listed in effects")
        if "curvature" in fx and not has_curve:
            raise ValueError("effects: 'curvature' is listed but neither sensor.curvature nor a substrate radius_mm is given")
        if s.curvature is not None and s.curvature.gestures:
            bad = [g for g in s.curvature.gestures if g not in self.gestures]
            if bad:
                raise ValueError(f"sensor.curvature.gestures: {bad} not in the scene's gestures")

    def _check_sessions_and_hands(self, fx: set[str]) -> None:
        """'session' is listed exactly when someone has several sessions; 'handedness' when a group uses both hands."""
        pro = self.protocol
        multi_session = pro.sessions > 1 or any(g.sessions > 1 for g in (pro.groups or {}).values())
        if multi_session and "session" not in fx:
            raise ValueError("protocol.sessions: more than one session, but effect 'session' is not listed in effects")
        if "session" in fx and not multi_session:
            raise ValueError("effects: 'session' is listed but every subject has one session")
        both_hands = any(g.hands == "both" for g in (pro.groups or {}).values())
        if both_hands and "handedness" not in fx:
            raise ValueError("protocol.groups: a group uses both hands, but effect 'handedness' is not listed in effects")

    def _check_people(self) -> None:
        """The number of subjects (given, or the groups'), and each group's sessions and instructions."""
        pop, pro = self.population, self.protocol
        if pro.groups is not None:
            n = sum(g.subjects for g in pro.groups.values())
            if pop.subjects is not None and pop.subjects != n:
                raise ValueError(f"population.subjects: {pop.subjects}, but the groups hold {n} people")
            if pro.sessions != 1:
                raise ValueError("protocol.sessions: with groups, give sessions per group")
            for gname, grp in pro.groups.items():
                for g, over in grp.instructions.items():
                    if g not in self.gestures:
                        raise ValueError(f"protocol.groups.{gname}.instructions.{g}: not one of the scene's gestures")
                    _check_gesture_override(f"protocol.groups.{gname}.instructions", g, over)
        elif pop.subjects is None:
            raise ValueError("population.subjects: required (or give protocol.groups)")

    def _check_split(self) -> None:
        """The split's subjects and variants are the scene's (subject ids parsed, not listed: a
        scene of absurdly many people is refused by its size, not here)."""
        pro = self.protocol
        if pro.split is None:
            return
        n = n_subjects(self)
        unknown = sorted(s for s in set(pro.split.train) | set(pro.split.test) if not is_subject_id(s, n))
        if unknown:
            first, last = subject_id(1, n), subject_id(n, n)
            raise ValueError(f"protocol.split: unknown subjects {unknown} (the scene has {first}..{last})")
        if pro.split.variants is not None:
            bad = [v for v in pro.split.variants if v not in (pro.variants or {})]
            if bad:
                raise ValueError(f"protocol.split.variants: {bad} are not variants of the scene")

    def _check_calibrated(self) -> None:
        """Each calibrated property is one the scene sets."""
        for path in self.calibrated:
            try:
                property_value(self, path)
            except KeyError:
                raise ValueError(f"calibrated.{path}: the scene has no such property") from None

    # ------------------------------------------------------------ helpers
    def gesture_params(self, gesture: str, group: str | None = None) -> GestureParams:
        """Library defaults, then the scene's overrides, then the group's."""
        p = LIBRARY[gesture].replace(**(self.gestures.get(gesture) or {}))
        if group is not None and self.protocol.groups is not None:
            over = self.protocol.groups[group].instructions.get(gesture)
            if over:
                p = p.replace(**over)
        return p


def property_value(spec: BaseModel, path: str) -> Any:
    """The value at a dotted path of a scene (``population.repetition.sd``);
    KeyError when the scene has no such property."""
    node: Any = spec
    for key in path.split("."):
        if isinstance(node, BaseModel) and key in type(node).model_fields:
            node = getattr(node, key)
        elif isinstance(node, dict) and key in node:
            node = node[key]
        else:
            raise KeyError(path)
    return node


def n_subjects(spec: SceneSpec) -> int:
    """The scene's people: ``population.subjects``, or the groups' subjects."""
    pro = spec.protocol
    return (spec.population.subjects or 0) if pro.groups is None else sum(g.subjects for g in pro.groups.values())


def subject_id(i: int, n: int) -> str:
    """The id of subject ``i`` (1-based) of ``n``: ``s01``.. (HAART convention), wider for 100 or more."""
    return f"s{i:0{max(2, len(str(n)))}d}"


def is_subject_id(s: str, n: int) -> bool:
    m = re.fullmatch(r"s(\d+)", s) if isinstance(s, str) else None
    return m is not None and 1 <= int(m.group(1)) <= n and subject_id(int(m.group(1)), n) == s


def subject_ids(spec: SceneSpec) -> list[str]:
    """``s01``.. (HAART convention), numbered through the groups in order."""
    n = n_subjects(spec)
    return [subject_id(i + 1, n) for i in range(n)]


def n_captures(spec: SceneSpec) -> int:
    pro = spec.protocol
    per = len(spec.gestures) * pro.repetitions
    per *= len(pro.variants or {None: 0}) * len(pro.substrates or {None: 0}) * len(pro.covers or {None: 0})
    if pro.groups is None:
        return (spec.population.subjects or 0) * pro.sessions * per
    return sum(g.subjects * g.sessions for g in pro.groups.values()) * per
