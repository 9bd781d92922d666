"""Turn a scene into a :class:`touchbench.datasets.TouchDataset`.

The captures are enumerated in a fixed order (group, subject, session,
variant, substrate, cover, gesture, repetition); capture ``i`` is drawn from
its own generator ``numpy.random.default_rng([seed, i])`` and each person
from ``[seed, PERSON_STREAM, index]``, so a capture does not depend on the
order in which the others are generated, and the same seed gives the same
content hash. ``protocol.lost`` captures (CoST lost 7 of 7812) are dropped
at random, with their own stream; the survivors keep their draws.

Each capture: the person's factors (person.py) -> contact events
(gestures.py) -> blobs (hand.py) -> cover, substrate, curvature -> force per
cell (with the cross-talk) -> gain, saturation, tension, baseline, noise, ADC
(sensor.py); every step vectorised over frames and cells, and each effect
applied only if the scene lists it.

Metadata follows the real readers: ``capture_id``, ``subject`` (``s01``..),
``gesture`` and, only where the scene has them, ``group``, ``session``
(1-based int), ``variant``, ``substrate``, ``cover``, ``repetition``
(1-based int) and ``split`` (``train``/``test``/``none``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core.errors import DataError
from ..datasets.model import SensorSpec, TouchDataset
from . import sensor as S
from .gestures import Events, Factors, GestureParams, plan_events
from .hand import Tracks, active, footprint, render, tracks
from .person import Person, capture_factors, make_people
from .size import size_problem
from .spec import CHANNELS, SceneSpec

LOST_STREAM = 3_000_017
BASELINE_STREAM = 2_000_003


@dataclass(frozen=True)
class Row:
    subject: str
    person: int
    group: str | None
    session: int
    variant: str | None
    substrate: str | None
    cover: str | None
    gesture: str
    repetition: int


def sensor_spec(spec: SceneSpec) -> SensorSpec:
    s = spec.sensor
    channels = tuple(CHANNELS) if s.kind == "channels" else None
    grid = (1, len(CHANNELS)) if channels else tuple(s.grid)
    return SensorSpec(
        name=s.name or spec.name,
        grid=grid,  # type: ignore[arg-type]
        frame_rate=s.frame_rate,
        value_range=tuple(s.value_range),  # type: ignore[arg-type]
        higher_is_more_pressure=True,
        channels=channels,
    )


def enumerate_rows(spec: SceneSpec, people: list[Person]) -> list[Row]:
    pro = spec.protocol
    variants = list(pro.variants) if pro.variants else [None]
    substrates = list(pro.substrates) if pro.substrates else [None]
    covers = list(pro.covers) if pro.covers else [None]
    rows = []
    for p in people:
        for session in range(1, p.sessions + 1):
            for v in variants:
                for sub in substrates:
                    for cov in covers:
                        for g in spec.gestures:
                            for r in range(1, pro.repetitions + 1):
                                rows.append(Row(p.subject, p.index, p.group, session, v, sub, cov, g, r))
    return rows


def lost_indices(spec: SceneSpec, n: int, seed: int) -> set[int]:
    k = spec.protocol.lost
    if k == 0:
        return set()
    rng = np.random.default_rng([seed, LOST_STREAM, 0])
    return {int(i) for i in rng.choice(n, size=k, replace=False)}


class _Scene:
    """Everything shared by the captures of one generation run."""

    def __init__(self, spec: SceneSpec, seed: int, source: str | Path | None = None):
        self.spec = spec
        self.seed = seed
        self.source = source
        self.fx = frozenset(spec.effects)
        s = spec.sensor
        self.grid = tuple(s.grid)
        self.pitch = s.pitch_mm
        self.fps = s.frame_rate
        self.surface = (self.grid[0] * self.pitch, self.grid[1] * self.pitch)
        self.people = make_people(spec, seed)
        self.params: dict[tuple[str, str | None], GestureParams] = {}
        self._baselines: dict[tuple, np.ndarray] = {}
        groups = list(spec.protocol.groups) if spec.protocol.groups else [None]
        for g in spec.gestures:
            for grp in groups:
                self.params[(g, grp)] = spec.gesture_params(g, grp)
        seg = spec.protocol.segmentation
        self.window_s = seg.frames / self.fps if seg.mode == "fixed" else None
        self.variants = {k: (v.force, v.speed) for k, v in (spec.protocol.variants or {}).items()}

    def baseline(self, row: Row) -> np.ndarray:
        """Resting pattern of one recording set-up (session, substrate,
        cover), drawn once from its own stream."""
        pro = self.spec.protocol
        si = list(pro.substrates).index(row.substrate) if pro.substrates else 0
        ci = list(pro.covers).index(row.cover) if pro.covers else 0
        key = (row.session, si, ci)
        if key not in self._baselines:
            b = self.spec.sensor.baseline
            assert b is not None
            rng = np.random.default_rng([self.seed, BASELINE_STREAM, *key])
            shape = (1, len(CHANNELS)) if self.spec.sensor.kind == "channels" else self.grid
            self._baselines[key] = S.baseline_pattern(shape, b.level, b.spread, rng, lines=b.structure == "lines")  # type: ignore[arg-type]
        return self._baselines[key]

    def curvature(self, row: Row) -> tuple[float, str, float] | None:
        """(radius, axis, tension) if this capture is on a curved surface."""
        if "curvature" not in self.fx:
            return None
        c = self.spec.sensor.curvature
        if c is not None and (c.gestures is None or row.gesture in c.gestures):
            return c.radius_mm, c.axis, c.tension
        if row.substrate is not None:
            sub = self.spec.protocol.substrates[row.substrate]  # type: ignore[index]
            if sub.radius_mm is not None:
                return sub.radius_mm, (c.axis if c is not None else "x"), sub.tension
        return None

    # ------------------------------------------------------------ capture
    def capture(self, index: int, row: Row) -> np.ndarray:
        """Capture ``index`` (its own random stream): the gesture planned, pressed through the cover,
        substrate and curvature, rendered on the sensor and read out through its electronics."""
        spec, fx, pro = self.spec, self.fx, self.spec.protocol
        sen = spec.sensor
        rng = np.random.default_rng([self.seed, index])
        person = self.people[row.person]
        p = self.params[(row.gesture, row.group)]
        f = capture_factors(
            spec,
            person,
            row.gesture,
            session=row.session,
            repetition=row.repetition,
            variant=self.variants.get(row.variant) if row.variant is not None else None,
            rng=rng,
        )
        seg = pro.segmentation
        ev = plan_events(
            p,
            f,
            surface_mm=self.surface,
            rng=rng,
            window_s=self.window_s,
            pad_s=seg.pad_s,
            min_s=seg.min_s,
            max_s=seg.max_s,
        )
        T = seg.frames if seg.frames is not None else max(1, int(round((ev.t_end - ev.t_start) * self.fps)))
        tr = self._covered_tracks(row, ev, p, person, T, rng)
        curve = self.curvature(row)
        if curve is not None:
            tr = S.apply_curvature(tr, curve[0], curve[1])
        leak = None
        if "crosstalk" in fx and sen.kind == "grid":
            c = float(sen.crosstalk)  # type: ignore[arg-type]
            leak = lambda w: S.crosstalk_lines(w, c)  # noqa: E731
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused below, in words
            field = render(tr, self.grid, self.pitch, line_filter=leak)  # type: ignore[arg-type]
            x = self._readout(field, tr)
            x = self._with_rest(x, row, curve, rng)
            if "noise" in fx:
                x = S.add_noise(x, sen.noise_sd, rng)  # type: ignore[arg-type]
        if not np.isfinite(x).all():
            raise DataError(f"capture {index} ({row.subject}, {row.gesture}): the sensor's readings overflowed before the "
                            "ADC (infinite or NaN counts): the scene's forces, sensor.gain, noise_sd, baseline or "
                            "tension are beyond its float32 electronics; make them smaller", self.source)
        return S.adc(x, tuple(sen.value_range), sen.dtype)  # type: ignore[arg-type]

    def _covered_tracks(self, row: Row, ev: Events, p: GestureParams, person: Person, T: int,
                        rng: np.random.Generator) -> Tracks:
        """The contacts of ``ev`` over ``T`` frames, through the capture's cover and substrate (a
        substrate's delay simulated from frames before the first, then cut off)."""
        fx, pro = self.fx, self.spec.protocol
        sub = pro.substrates[row.substrate] if ("substrate" in fx and row.substrate is not None) else None  # type: ignore[index]
        lead = int(np.ceil(4 * sub.delay_s * self.fps)) if (sub is not None and sub.delay_s > 0) else 0
        t = ev.t_start + (np.arange(-lead, T, dtype=np.float64)) / self.fps
        tr = active(tracks(ev, footprint(p.primitive, person.hand_scale * p.size, p.fingers), t, rng))
        if "cover" in fx and row.cover is not None:
            c = pro.covers[row.cover]  # type: ignore[index]
            tr = S.apply_cover(tr, c.transmission, c.blur_mm, c.deadband_n)
        if sub is not None:
            tr = S.apply_substrate(tr, sub.spread_mm, sub.delay_s, sub.gain, self.fps)
        if lead:
            tr = Tracks(tr.cx[:, lead:], tr.cy[:, lead:], tr.force[:, lead:], tr.sdx, tr.sdy, tr.conform)
        return tr

    def _readout(self, field: np.ndarray, tr: Tracks) -> np.ndarray:
        """The sensor's reading of the force ``field``: its channels (fur sensor), or the grid's gain;
        saturated where the scene says so."""
        sen, fx = self.spec.sensor, self.fx
        if sen.kind == "channels":
            r = sen.response
            assert r is not None
            x = S.to_channels(
                field,
                tr,
                frame_rate=self.fps,
                pressure_gain=r.pressure_gain,
                fur_motion_gain=r.fur_motion_gain,
                fur_touch_gain=r.fur_touch_gain,
                contact_n=r.contact_n,
                rest=r.rest,
                value_range=tuple(sen.value_range),  # type: ignore[arg-type]
            )
            if "saturation" in fx:
                rest_p = r.rest["pressure"]
                x[:, 2] = rest_p + S.saturate(x[:, 2] - rest_p, sen.saturation)  # type: ignore[arg-type]
            return x[:, None, :]
        # the electronics in float32: counts up to a few thousand keep
        # ~1e-4 resolution, and the passes over the field cost half
        x = field.astype(np.float32)
        x *= np.float32(sen.gain)
        if "saturation" in fx:
            x = S.saturate(x, sen.saturation)  # type: ignore[arg-type]
        return x

    def _with_rest(self, x: np.ndarray, row: Row, curve: tuple[float, str, float] | None,
                   rng: np.random.Generator) -> np.ndarray:
        """``x`` on the sensor's resting level: the baseline (its drift drawn from ``rng``) and a
        curved sheet's tension."""
        sen, fx = self.spec.sensor, self.fx
        rest = None
        if "baseline" in fx:
            b = sen.baseline
            assert b is not None
            drift = float(np.exp(b.drift * rng.standard_normal() - 0.5 * b.drift**2))
            rest = self.baseline(row) * drift
        if sen.kind == "grid" and curve is not None and curve[2] > 0:
            # the stretched sheet's resting pressure is read through the same
            # line sensitivities as the baseline (if the scene has one)
            if rest is not None and sen.baseline.level > 0:  # type: ignore[union-attr]
                rest = rest * (1.0 + curve[2] / sen.baseline.level)  # type: ignore[union-attr]
            else:
                x = x + S.tension(self.grid, curve[2], curve[1]).astype(x.dtype)[None]  # type: ignore[arg-type]
        if rest is not None:
            x = x + rest.astype(x.dtype)[None]
        return x


def simulate(
    params: GestureParams,
    *,
    grid: tuple[int, int],
    frame_rate: float,
    pitch_mm: float = 25.4,
    frames: int | None = None,
    factors: Factors | None = None,
    hand_scale: float = 1.0,
    seed: int = 0,
) -> tuple[np.ndarray, Events]:
    """One gesture alone on a bare, ideal sensor: the force per cell (T, H,
    W) in newtons and the contact events, on a ``grid`` of cells
    ``pitch_mm`` apart sampled at ``frame_rate``. ``frames`` given: a fixed window
    of the continuous performance; else cut at the touch. For trying a
    gesture's kinematics and for testing each one by itself."""
    rng = np.random.default_rng(seed)
    f = factors or Factors()
    surface = (grid[0] * pitch_mm, grid[1] * pitch_mm)
    ev = plan_events(params, f, surface_mm=surface, rng=rng, window_s=None if frames is None else frames / frame_rate)
    T = frames if frames is not None else max(1, int(round((ev.t_end - ev.t_start) * frame_rate)))
    t = ev.t_start + np.arange(T, dtype=np.float64) / frame_rate
    tr = active(tracks(ev, footprint(params.primitive, hand_scale * params.size, params.fingers), t, rng))
    return render(tr, grid, pitch_mm), ev


def _meta(spec: SceneSpec, rows: list[Row]) -> pd.DataFrame:
    pro = spec.protocol
    multi = pro.sessions > 1 or (pro.groups is not None and any(g.sessions > 1 for g in pro.groups.values()))
    cols: dict[str, Any] = {}
    ids = []
    for r in rows:
        parts = [r.subject]
        if multi:
            parts.append(f"r{r.session}")
        for v in (r.variant, r.substrate, r.cover):
            if v is not None:
                parts.append(v)
        parts.append(r.gesture)
        if pro.repetitions > 1:
            parts.append(f"{r.repetition:02d}")
        ids.append("-".join(parts))
    cols["capture_id"] = ids
    cols["subject"] = [r.subject for r in rows]
    if pro.groups is not None:
        cols["group"] = [r.group for r in rows]
    if multi:
        cols["session"] = np.array([r.session for r in rows], dtype=np.int64)
    if pro.variants is not None:
        cols["variant"] = [r.variant for r in rows]
    if pro.substrates is not None:
        cols["substrate"] = [r.substrate for r in rows]
    if pro.covers is not None:
        cols["cover"] = [r.cover for r in rows]
    cols["gesture"] = [r.gesture for r in rows]
    if pro.repetitions > 1:
        cols["repetition"] = np.array([r.repetition for r in rows], dtype=np.int64)
    if pro.split is not None:
        tr, te = set(pro.split.train), set(pro.split.test)
        ok = set(pro.split.variants) if pro.split.variants is not None else None
        split = []
        for r in rows:
            if ok is not None and r.variant not in ok:
                split.append("none")
            else:
                split.append("train" if r.subject in tr else "test" if r.subject in te else "none")
        cols["split"] = split
    return pd.DataFrame(cols)


def generate(spec: SceneSpec, seed: int | None = None, name: str | None = None,
             source: str | Path | None = None) -> TouchDataset:
    """The dataset of scene ``spec`` for ``seed`` (default: the scene's). A scene whose captures
    would not fit in memory is refused before any is made (:func:`.size.size_problem`), and so is a
    capture whose counts overflow; ``source`` (the scene's file) is named in those errors."""
    seed = spec.seed if seed is None else int(seed)
    if seed < 0:
        raise ValueError(f"seed must be non-negative, got {seed}")
    problem = size_problem(spec)
    if problem is not None:
        raise DataError(f"invalid scene: {problem[0]}: {problem[1]}", source)
    scene = _Scene(spec, seed, source)
    rows = enumerate_rows(spec, scene.people)
    lost = lost_indices(spec, len(rows), seed)
    keep = [i for i in range(len(rows)) if i not in lost]
    captures = [scene.capture(i, rows[i]) for i in keep]
    meta = _meta(spec, [rows[i] for i in keep])
    return TouchDataset(name=name or spec.name, captures=captures, meta=meta, sensor=sensor_spec(spec))
