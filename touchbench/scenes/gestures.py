"""The gesture: the kinematics that make gestures differ.

A gesture is performed as a sequence of contact *events*. Each event is one
contact of a hand primitive (:mod:`touchbench.scenes.hand`) with an onset, a
duration, a force time profile (rise, hold, fall; optionally kneaded), a
starting position, a glide (travel during the contact) and an oscillation
of the contact point. The gestures differ only in these parameters
(:data:`LIBRARY`):

- pat: repeated brief contacts of the flat hand (Flagg Sec. 4.3: "gently and
  quickly touching the body with the flat of the hand");
- stroke: the hand glides one way, lifts, and again (Flagg: "moving hand
  gently over the body, often repeatedly"; Zhou Table 1: "multiple fingers,
  gentle repeating actions");
- rub: firm palm contact moved back and forth (Flagg: "to and fro with
  firm pressure");
- scratch: fast, small back-and-forth of several fingertips (Zhou Table 1:
  "multiple finger tips, quick repeating actions");
- tickle: light, irregular fingertip touches scattered about (Flagg: "light
  finger movements");
- poke: one fingertip, short and firm (Zhou: "one finger, quick and
  forceful"); tap: brief fingertip contacts, repeated;
- press: fingertips, slow (Zhou); push: the whole palm, slow (Zhou: "whole
  hand including palm, slow action");
- pinch: two opposing fingertips closing (Zhou: "on a small area,
  forceful"); pull: light pinches of the fur (Flagg: "gently and randomly
  pulling at hairs");
- grab and squeeze: the hand wrapping the surface; squeeze firmer and
  longer, with a kneading pulse (CoST; Flagg: "firmly pressing between the
  fingers");
- hit and slap: a short, high-force impact; slap with the flat hand
  (wider), hit with the palm/fist (CoST);
- massage: fingertips kneading: force modulated, small circular motion;
- constant: still contact of the flat hand (HAART; Flagg: "contact without
  movement"); notouch: nothing (HAART, Flagg).

The numbers are our interpretation (the papers give definitions, not
kinematics): rates and durations from the dominant frequencies and contact
fractions of the real HAART recordings and from CoST's reported length range
(75 ms .. 9.6 s); forces are round figures for a hand on a soft surface.
Scenes override any parameter per gesture in their YAML.

Interpretations: "repetition rate" is contact events per second for tapping
and gliding gestures and the oscillation frequency for sustained ones;
``cycles`` fixes the number of movements per capture (an instruction such as
Zhou's "quick burst of three repetitions").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from ..core.yamlsafe import number_as_text

PRIMITIVES = ("fingertip", "fingertips", "palm", "hand", "wrap", "pinch", "none")


@dataclass(frozen=True)
class GestureParams:
    """Kinematic parameters of one gesture (normal variant, average person)."""

    primitive: str = "palm"
    fingers: int = 1
    force_n: float = 5.0
    rate_hz: float | None = None  # contact events per second; None = one sustained contact
    contact_s: float = 0.2  # contact time of each event (tapping/gliding gestures)
    rise_s: float = 0.05
    fall_s: float = 0.05
    travel_mm: float = 0.0  # glide during each contact
    osc_hz: float = 0.0  # back-and-forth of the contact point
    osc_mm: float = 0.0  # its amplitude (half the peak-to-peak excursion)
    knead_hz: float = 0.0  # force modulation
    knead_depth: float = 0.0  # 0..1
    scatter_mm: float = 0.0  # event-to-event position scatter
    jitter: float = 0.0  # timing irregularity, sd as a fraction of the period
    force_cv: float = 0.1  # event-to-event force variation (log-sd)
    duration_s: float = 2.0  # length of one performance (contact segmentation)
    duration_cv: float = 0.3  # its capture-to-capture spread (log-sd)
    cycles: int | None = None  # fixed number of movements per capture
    pace: float = 1.0  # speed factor of an instruction (bursts are quick)
    closing_mm: float = 0.0  # pinch: how far the two fingertips close
    spread: float = 1.0  # multiplier on the population's style spread for this gesture
    angle_deg: float = 90.0  # hand axis / motion direction on the grid (0 = +x, 90 = +y)
    size: float = 1.0  # footprint scale beyond the hand's (fingers spread, heel of the hand)
    wobble: float = 0.0  # independent slow fluctuation of each blob's force (relative amplitude)
    wobble_hz: float = 2.0  # its typical frequency

    _POSITIVE = ("force_n", "contact_s", "duration_s", "pace", "size", "wobble_hz")
    _NONNEG = (
        "rise_s",
        "fall_s",
        "travel_mm",
        "osc_hz",
        "osc_mm",
        "knead_hz",
        "scatter_mm",
        "jitter",
        "force_cv",
        "duration_cv",
        "closing_mm",
        "spread",
        "wobble",
    )

    @classmethod
    def check_value(cls, name: str, value: Any) -> None:
        """Raise ValueError if ``value`` is not valid for field ``name``."""
        if name == "primitive":
            if value not in PRIMITIVES:
                raise ValueError(f"{value!r} is not a primitive ({', '.join(PRIMITIVES)})")
            return
        if name in ("fingers", "cycles"):
            if value is None and name == "cycles":
                return
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ValueError("must be a whole number >= 1")
            return
        if name == "rate_hz" and value is None:
            return
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            why = number_as_text(value)
            raise ValueError(f"must be a number, got {value!r}" + (f": {why}" if why else ""))
        if not math.isfinite(value):
            raise ValueError(f"must be a finite number, got {value!r}")
        if name in ("knead_depth", "wobble") and not 0 <= value <= 1:
            raise ValueError("must be within 0..1")
        if (name in cls._POSITIVE or name == "rate_hz") and not value > 0:
            raise ValueError("must be positive")
        if name in cls._NONNEG and value < 0:
            raise ValueError("must not be negative")

    def replace(self, **changes: Any) -> "GestureParams":
        for k, v in changes.items():
            self.check_value(k, v)
        return replace(self, **changes)

    @property
    def touches(self) -> bool:
        return self.primitive != "none"


G = GestureParams
LIBRARY: dict[str, GestureParams] = {
    "pat": G("hand", force_n=6.0, rate_hz=2.5, contact_s=0.13, rise_s=0.03, fall_s=0.06, scatter_mm=8, jitter=0.1, duration_s=1.6),
    "stroke": G("hand", force_n=4.0, rate_hz=0.8, contact_s=0.8, rise_s=0.12, fall_s=0.15, travel_mm=110, scatter_mm=8, jitter=0.1, duration_s=3.0),
    "rub": G("palm", force_n=10.0, osc_hz=1.6, osc_mm=30, rise_s=0.2, fall_s=0.2, duration_s=3.0),
    "scratch": G("fingertips", fingers=4, force_n=4.0, osc_hz=4.5, osc_mm=7, rise_s=0.1, fall_s=0.1, duration_s=2.5),
    "tickle": G("fingertips", fingers=2, force_n=1.2, rate_hz=4.0, contact_s=0.15, rise_s=0.03, fall_s=0.05, travel_mm=10, osc_hz=6, osc_mm=3, scatter_mm=35, jitter=0.5, force_cv=0.5, duration_s=2.5),
    "poke": G("fingertip", force_n=8.0, rise_s=0.07, fall_s=0.1, duration_s=0.45, duration_cv=0.35),
    "tap": G("fingertips", fingers=2, force_n=4.0, rate_hz=3.0, contact_s=0.08, rise_s=0.02, fall_s=0.04, scatter_mm=5, jitter=0.1, duration_s=1.0),
    "press": G("fingertips", fingers=3, force_n=12.0, rise_s=0.5, fall_s=0.4, duration_s=2.0),
    "push": G("palm", force_n=20.0, rise_s=0.6, fall_s=0.5, duration_s=2.5),
    "pinch": G("pinch", force_n=8.0, rise_s=0.15, fall_s=0.15, closing_mm=20, duration_s=1.2),
    "pull": G("pinch", force_n=1.5, rate_hz=1.5, contact_s=0.35, rise_s=0.08, fall_s=0.1, closing_mm=12, travel_mm=15, scatter_mm=30, jitter=0.3, force_cv=0.3, duration_s=2.0),
    "grab": G("wrap", force_n=25.0, rise_s=0.2, fall_s=0.25, duration_s=1.8),
    "squeeze": G("wrap", force_n=40.0, rise_s=0.4, fall_s=0.35, knead_hz=1.0, knead_depth=0.3, duration_s=2.6),
    "hit": G("palm", force_n=60.0, rise_s=0.025, fall_s=0.06, duration_s=0.13, duration_cv=0.35),
    "slap": G("hand", force_n=45.0, rise_s=0.015, fall_s=0.05, duration_s=0.11, duration_cv=0.35),
    "massage": G("fingertips", fingers=4, force_n=15.0, osc_hz=1.2, osc_mm=10, knead_hz=1.2, knead_depth=0.7, rise_s=0.3, fall_s=0.3, duration_s=4.5),
    "constant": G("hand", force_n=12.0, rise_s=0.3, fall_s=0.3, duration_s=3.0),
    "notouch": G("none", force_n=1.0, duration_s=2.0),
}
del G


# ------------------------------------------------------------------ events
@dataclass(frozen=True)
class Factors:
    """How this person performs this gesture in this capture: multiplicative
    factors on force, rate (speed), contact time, amplitude and oscillation
    frequency; the hand axis angle (radians) and the location offset (mm)
    from the sensor centre; whether the left hand mirrors the motion."""

    force: float = 1.0
    rate: float = 1.0
    contact: float = 1.0
    amplitude: float = 1.0
    osc: float = 1.0
    angle: float = 0.0
    dx: float = 0.0
    dy: float = 0.0
    mirror: bool = False


@dataclass
class Events:
    """One capture's contact events (arrays of length E) and the span of
    time (s) the capture covers."""

    onset: np.ndarray
    dur: np.ndarray
    rise: np.ndarray
    fall: np.ndarray
    peak: np.ndarray
    x0: np.ndarray  # start position, mm (sensor plane, origin at the grid's corner)
    y0: np.ndarray
    gx: np.ndarray  # glide during the event, mm
    gy: np.ndarray
    angle: np.ndarray  # hand axis, radians
    osc_amp: np.ndarray
    osc_hz: np.ndarray
    osc_phase: np.ndarray
    knead_hz: np.ndarray
    knead_depth: np.ndarray
    knead_phase: np.ndarray
    closing: np.ndarray
    wobble: float
    wobble_hz: float
    t_start: float
    t_end: float

    def __len__(self) -> int:
        return len(self.onset)

    def select(self, keep: np.ndarray) -> "Events":
        """The events where ``keep`` is true."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = v[keep] if isinstance(v, np.ndarray) else v
        return Events(**out)


def _empty(t_start: float, t_end: float) -> Events:
    z = np.zeros(0)
    return Events(z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, 0.0, 1.0, t_start, t_end)


def plan_events(
    p: GestureParams,
    f: Factors,
    *,
    surface_mm: tuple[float, float],
    rng: np.random.Generator,
    window_s: float | None = None,
    pad_s: float = 0.0,
    min_s: float | None = None,
    max_s: float | None = None,
) -> Events:
    """The contact events of one capture.

    ``window_s`` given (fixed segmentation): the gesture is performed
    continuously and the capture is the window [0, window_s) of it, so
    tapping starts at a random phase and sustained contacts cover the
    window. Otherwise (contact segmentation) the capture runs from the first
    contact to the last, plus up to ``pad_s`` either side, kept within
    [``min_s``, ``max_s``]. ``surface_mm`` is the sensor's (height, width).
    """
    fixed = window_s is not None
    speed = f.rate * p.pace
    duration = p.duration_s * float(np.exp(p.duration_cv * rng.standard_normal())) / p.pace
    if not p.touches:
        if fixed:
            return _empty(0.0, float(window_s))
        return _empty(0.0, _clip_span(duration, min_s, max_s))

    osc_hz = p.osc_hz * f.osc * speed
    if p.rate_hz is None:
        onset, dur = _sustained_contact(p, f, duration, osc_hz, window_s)
    else:
        onset, dur = _tapping_contacts(p, f, speed, duration, window_s, rng)
    n = len(onset)
    rise, fall, peak = _force_envelopes(p, f, speed, dur, rng)
    x0, y0, gx, gy, ang = _strokes(p, f, surface_mm, n, rng)
    ev = Events(
        onset=onset,
        dur=dur,
        rise=rise,
        fall=fall,
        peak=peak,
        x0=x0,
        y0=y0,
        gx=gx,
        gy=gy,
        angle=ang,
        osc_amp=np.full(n, p.osc_mm * f.amplitude),
        osc_hz=np.full(n, osc_hz),
        osc_phase=rng.uniform(0, 2 * np.pi, n),
        knead_hz=np.full(n, p.knead_hz * speed),
        knead_depth=np.full(n, p.knead_depth),
        knead_phase=rng.uniform(0, 2 * np.pi, n),
        closing=np.full(n, p.closing_mm),
        wobble=p.wobble,
        wobble_hz=p.wobble_hz * speed,
        t_start=0.0,
        t_end=0.0,
    )
    if fixed:
        ev.t_start, ev.t_end = 0.0, float(window_s)
    else:
        ev.t_start, ev.t_end = _contact_window(onset, dur, pad_s, min_s, max_s, rng)
    return ev


def _sustained_contact(p: GestureParams, f: Factors, duration: float, osc_hz: float,
                       window_s: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The onset and duration of a sustained gesture's one contact: over the whole window (fixed
    segmentation), else its cycles of oscillation or its drawn duration."""
    if window_s is not None:
        return np.array([-1.0]), np.array([float(window_s) + 2.0])
    d = (p.cycles / osc_hz) if (p.cycles and osc_hz > 0) else duration * f.contact
    return np.array([0.0]), np.array([d])


def _tapping_contacts(p: GestureParams, f: Factors, speed: float, duration: float, window_s: float | None,
                      rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The onsets and durations of a repeated gesture's contacts, one per period: from a random phase
    through the window (fixed segmentation), else its cycles or its drawn duration's worth; jittered."""
    fixed = window_s is not None
    rate = float(p.rate_hz) * speed
    period = 1.0 / rate
    contact = min(p.contact_s * f.contact / speed ** 0.5, 0.95 * period) if p.cycles is None else p.contact_s * f.contact / speed ** 0.5
    if fixed:
        t0 = -rng.uniform(0.0, period)
        n = int(np.ceil((float(window_s) - t0) / period)) + 1
    else:
        t0 = 0.0
        n = p.cycles if p.cycles is not None else max(1, int(round(duration * rate)))
    k = np.arange(n, dtype=np.float64)
    onset = t0 + k * period
    if p.jitter > 0 and n > 1:
        onset = onset + p.jitter * period * rng.standard_normal(n)
        onset.sort()
        if not fixed:
            onset -= onset[0]
    dur = np.full(n, contact) * np.exp(0.15 * rng.standard_normal(n))
    return onset, dur


def _force_envelopes(p: GestureParams, f: Factors, speed: float, dur: np.ndarray,
                     rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each contact's rise and fall times (shrunk to fit in 90 % of the contact) and peak force."""
    n = len(dur)
    rise = np.full(n, p.rise_s / speed ** 0.5)
    fall = np.full(n, p.fall_s / speed ** 0.5)
    over = (rise + fall) / (0.9 * dur)
    scale = np.where(over > 1.0, 1.0 / np.maximum(over, 1e-12), 1.0)
    rise *= scale
    fall *= scale
    peak = p.force_n * f.force * np.exp(p.force_cv * rng.standard_normal(n) - 0.5 * p.force_cv**2)
    return rise, fall, peak


def _strokes(p: GestureParams, f: Factors, surface_mm: tuple[float, float], n: int,
             rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Each contact's start point, travel vector and angle: about the surface's centre, along the hand's
    axis (the left hand mirrors the x direction)."""
    angle = np.deg2rad(p.angle_deg) + f.angle
    dx = f.dx
    if f.mirror:
        angle = np.pi - angle
        dx = -dx
    h_mm, w_mm = surface_mm
    travel = p.travel_mm * f.amplitude
    cx = w_mm / 2 + dx + p.scatter_mm * rng.standard_normal(n)
    cy = h_mm / 2 + f.dy + p.scatter_mm * rng.standard_normal(n)
    cx = np.clip(cx, 0.0, w_mm)
    cy = np.clip(cy, 0.0, h_mm)
    ang = np.full(n, angle) + (np.deg2rad(20.0) * rng.standard_normal(n) if p.scatter_mm > 20 else 0.0)
    gx = travel * np.cos(ang)
    gy = travel * np.sin(ang)
    return cx - gx / 2, cy - gy / 2, gx, gy, ang


def _contact_window(onset: np.ndarray, dur: np.ndarray, pad_s: float, min_s: float | None, max_s: float | None,
                    rng: np.random.Generator) -> tuple[float, float]:
    """The capture's start and end under contact segmentation: the first contact to the last, padded by
    up to ``pad_s`` either side, kept within [``min_s``, ``max_s``] (a short one padded evenly)."""
    first = float(onset.min())
    last = float((onset + dur).max())
    a = first - rng.uniform(0.0, pad_s)
    b = last + rng.uniform(0.0, pad_s)
    span = _clip_span(b - a, min_s, max_s)
    if span > b - a:  # too short: pad both sides evenly
        a -= (span - (b - a)) / 2
    return a, a + span


def _clip_span(span: float, min_s: float | None, max_s: float | None) -> float:
    if min_s is not None:
        span = max(span, min_s)
    if max_s is not None:
        span = min(span, max_s)
    return span
