"""What a scene would take in memory, counted from its description before any of it is made.

The captures of a scene take ``people x conditions x repetitions x (frames summed over the
gestures) x H x W x itemsize`` bytes (people: subjects x sessions, or the groups' subjects x
sessions; conditions: variants x substrates x covers; ``H x W`` the sensor's grid, ``1 x 4``
for a channel sensor; the itemsize of its ``dtype``), plus :data:`CAPTURE_OVERHEAD` bytes per
capture for its row, its metadata and its array. With fixed segmentation a capture has
``protocol.segmentation.frames`` frames; with contact segmentation its length is drawn, and the
count takes each gesture's nominal performance, ``duration_s / pace`` plus ``pad_s`` either
side, kept within ``min_s`` .. ``max_s``, at the frame rate (the longest over the groups'
instructions).

:func:`size_problem` refuses a scene above :func:`touchbench.core.memory.memory_limit` (a
quarter of the available memory: generating holds the captures, and writing them out copies
them), naming the field of the largest factor: ``population.subjects``,
``protocol.repetitions``, ``protocol.segmentation.frames`` (with contact segmentation: the
longest gesture's ``duration_s``, or ``pad_s``, ``max_s``, ``min_s`` when they set it, and
``sensor.frame_rate``), ``sensor.grid``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.memory import describe_bytes, memory_limit

__all__ = ["CAPTURE_OVERHEAD", "SceneSize", "scene_size", "size_problem"]

#: bytes a capture costs beyond its values: its row, its metadata (ids, labels) and its array's header
CAPTURE_OVERHEAD = 1024


@dataclass(frozen=True)
class SceneSize:
    """The counts behind a scene's size, and the field of its largest factor."""

    captures: int
    frames: int  # frames summed over one capture of each gesture
    grid: tuple[int, int]
    dtype: str
    bytes: int
    field: str


def _people(spec) -> tuple[int, str]:
    """Subjects x sessions, and the field that sets the larger of the two."""
    pro, pop = spec.protocol, spec.population
    if pro.groups is not None:
        return sum(g.subjects * g.sessions for g in pro.groups.values()), "protocol.groups"
    subjects = pop.subjects or 0
    return subjects * pro.sessions, "population.subjects" if subjects >= pro.sessions else "protocol.sessions"


def _gesture_frames(spec, gesture: str) -> tuple[int, tuple[float, str]]:
    """Frames of one capture of ``gesture`` (nominal, with contact segmentation), and the factor of
    its length that is not the frame rate with the field that sets it."""
    seg, fps = spec.protocol.segmentation, spec.sensor.frame_rate
    if seg.mode == "fixed":
        return int(seg.frames), (seg.frames, "protocol.segmentation.frames")
    groups = list(spec.protocol.groups or {}) or [None]
    performance = max(p.duration_s / p.pace for p in (spec.gesture_params(gesture, g) for g in groups))
    seconds = performance + 2 * seg.pad_s
    field = f"gestures.{gesture}.duration_s" if performance >= 2 * seg.pad_s else "protocol.segmentation.pad_s"
    if seg.max_s is not None and seconds > seg.max_s:
        seconds, field = seg.max_s, "protocol.segmentation.max_s"
    if seg.min_s is not None and seconds < seg.min_s:
        seconds, field = seg.min_s, "protocol.segmentation.min_s"
    return max(1, int(round(seconds * fps))), (seconds, field)


def scene_size(spec) -> SceneSize:
    """The bytes of the captures of ``spec`` (module docstring), in exact integers."""
    pro, sen = spec.protocol, spec.sensor
    people, people_field = _people(spec)
    conditions = len(pro.variants or [0]) * len(pro.substrates or [0]) * len(pro.covers or [0])
    per_gesture = [_gesture_frames(spec, g) for g in spec.gestures]
    frames = sum(f for f, _ in per_gesture)
    grid = (1, 4) if sen.kind == "channels" else (int(sen.grid[0]), int(sen.grid[1]))
    itemsize = np.dtype(sen.dtype).itemsize
    captures = people * conditions * pro.repetitions * len(spec.gestures)
    values = people * conditions * pro.repetitions * frames * grid[0] * grid[1]
    factors = [(people, people_field), (pro.repetitions, "protocol.repetitions"),
               max(f for _, f in per_gesture), (grid[0] * grid[1], "sensor.grid")]
    if pro.segmentation.mode == "contact":
        factors.append((sen.frame_rate, "sensor.frame_rate"))
    field = max(factors, key=lambda f: f[0])[1]
    return SceneSize(captures, frames, grid, sen.dtype, values * itemsize + captures * CAPTURE_OVERHEAD, field)


def size_problem(spec, limit: int | None = None) -> tuple[str, str] | None:
    """``(field, message)`` when the captures of ``spec`` would take more than ``limit`` bytes
    (default :func:`touchbench.core.memory.memory_limit`), else None."""
    size = scene_size(spec)
    limit = memory_limit() if limit is None else limit
    if size.bytes <= limit:
        return None
    n_gestures = len(spec.gestures)
    return size.field, (
        f"the scene would make {size.captures:,} captures ({n_gestures} gesture(s), "
        f"{size.frames / n_gestures:,.0f} frames each on average, {size.grid[0]} x {size.grid[1]} values of "
        f"{size.dtype}): {describe_bytes(size.bytes)}, over the limit of {describe_bytes(limit)} (a quarter of the memory available); "
        f"make {size.field} smaller")
