"""SocialTouch: 32 social gestures on a 19 x 24 capacitive grid.

Source and format: ../shared/data/socialtouch/README.md (the public
repository ``yliess86/SocialTouch``, folder ``data/``). One gzipped CSV per
participant and gesture, ``raw/touch_p<P>_g<G>-<date>_<time>.csv.gz``, one row
per frame: ``participantID, gesture, repetition, frameID, time,
pixel0..pixel455`` (the 19 rows of 24 cells, row-major, values 0..255,
higher = stronger contact; ``time`` in ms since the capture's first frame).
A capture is one (participant, gesture, repetition): 2493 captures of 3 to
227 frames by 3 participants. Gesture names come from ``GesturesRated.csv``
(``id, gesture_name, ...``).

The frames are irregular: the median step is 83 ms (12 Hz) but 8 % of the
steps are about 165 ms (one frame dropped) and some 250 to 420 ms. The rule
(stated once, here and in each dataset's provenance, which the run manifest
records):

``socialtouch-recorded``
    the frames as recorded, with their time stamps: meta ``time_ms`` holds
    each capture's per-frame ``time`` (ms, as many values as frames). For
    methods that take time stamps. Its sensor states 12 Hz, the median
    step, only because a sensor needs a rate: the steps are not equal, so
    a method that assumes a fixed rate belongs on ``socialtouch``.
``socialtouch``
    the same captures resampled to a fixed 12 Hz (a step of 1000/12 ms,
    the median recorded step), for the methods that need a fixed frame rate
    (every feature set and classifier of touchbench: spectra in Hz, frame
    skips, windows). Frame ``k`` is at ``k * 1000 / 12`` ms from the
    capture's first frame, for every ``k`` with that time at most the last
    recorded time (a tail shorter than one step is dropped; a capture of
    ``D`` ms gets ``floor(12 D / 1000) + 1`` frames). Each cell's value is
    the linear interpolation between the two recorded frames around that
    time, rounded to the nearest integer (halves up, computed exactly in
    integers), so values stay whole numbers in 0..255 (uint8, the sensor's
    own quantisation). Meta
    ``time_ms`` holds the resampled times and ``recorded_time_ms`` the
    recorded ones.

Why linear interpolation rather than holding the previous frame: 92 % of
the recorded steps lie within 8 ms of 83.3 ms, where either rule moves a
frame by less than a tenth of a step; they differ at the dropped frames. A
held frame repeats the last reading, so a stroke that kept moving reads as
stop-and-go (zero change, then a double step): motion and rhythm features
(``smmhh`` runs of motion, total variation per step, spectra) would see
pauses that did not happen. Linear interpolation fills the gap with the
straight line between the frames around it, the smallest assumption about a
contact that changes continuously. It invents no values outside the two
recorded frames, so the value range is kept.

Checks (each refusal names the file and line): the header, whole numbers,
``participantID`` and ``gesture`` as the file name says, gesture ids known
to ``GesturesRated.csv``, ``frameID`` counting 0, 1, 2... within each
repetition, ``time`` strictly increasing within a capture, values 0..255,
and the SHA-256 of every file against ``SHA256SUMS`` when present.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.errors import DataError
from ..core.paths import data_dir as default_data_dir, data_dir_help
from .cache import cached_dataset
from .checksums import read_bytes, verify_checksums
from .model import RECORDED_TIME_COLUMN, SensorSpec, TouchDataset, time_step_summary
from .registry import DATASETS
from .tables import numeric, read_table, runs

READER_VERSION = "socialtouch-2"

GRID = (19, 24)
VALUE_RANGE = (0.0, 255.0)
#: the fixed rate of ``socialtouch`` (Hz): the median recorded step is 83 ms
RATE_HZ = 12.0
SOCIALTOUCH_SENSOR = SensorSpec(name="socialtouch", grid=GRID, frame_rate=RATE_HZ, value_range=VALUE_RANGE)

KEYS = ("participantID", "gesture", "repetition")
COLUMNS = (*KEYS, "frameID", "time") + tuple(f"pixel{i}" for i in range(GRID[0] * GRID[1]))

_NAME_RE = re.compile(r"^touch_p(?P<participant>\d+)_g(?P<gesture>\d+)-[^/]*\.csv(?:\.gz)?$")

SOURCE = "github.com/yliess86/SocialTouch at 79ce611 (2022-05-04), folder data/ (MIT licence badge)"


@dataclass(frozen=True)
class Recording:
    path: Path
    participant: int
    gesture: int

    @property
    def original_name(self) -> str:
        return self.path.name.removesuffix(".gz")


@dataclass(frozen=True)
class Capture:
    """One (participant, gesture, repetition) as recorded."""

    participant: int
    gesture: int
    repetition: int
    time_ms: np.ndarray  # (T,) int64
    frames: np.ndarray  # (T, 19, 24) uint8
    source: str


def _base_dir(data_dir: str | Path | None) -> Path:
    base = Path(data_dir) if data_dir is not None else default_data_dir() / "socialtouch"
    if (base / "socialtouch" / "raw").is_dir():  # the shared data folder itself was given
        base = base / "socialtouch"
    if not (base / "raw").is_dir():
        where = data_dir_help("socialtouch") if data_dir is None else "the data_dir given has no raw folder"
        raise DataError(f"SocialTouch raw folder not found: {where}", base / "raw")
    return base


def find_recordings(raw: Path) -> list[Recording]:
    """Every ``touch_p<P>_g<G>-....csv[.gz]`` under ``raw``, by participant and gesture."""
    recs = []
    for p in sorted(raw.iterdir()):
        m = _NAME_RE.match(p.name)
        if m is not None:
            recs.append(Recording(p, int(m["participant"]), int(m["gesture"])))
    if not recs:
        raise DataError("no SocialTouch recordings (touch_p<P>_g<G>-<date>_<time>.csv[.gz]) found", raw)
    seen: dict[tuple[int, int], Path] = {}
    for r in recs:
        key = (r.participant, r.gesture)
        if key in seen:
            raise DataError(f"participant {r.participant}, gesture {r.gesture} given twice (also {seen[key].name})", r.path)
        seen[key] = r.path
    return sorted(recs, key=lambda r: (r.participant, r.gesture))


def gesture_names(base: Path) -> dict[int, str]:
    """Gesture id -> name from ``GesturesRated.csv`` (columns ``id``, ``gesture_name``)."""
    path = base / "GesturesRated.csv"
    df = read_table(path)
    for col in ("id", "gesture_name"):
        if col not in df.columns:
            raise DataError(f"no {col!r} column (found {list(df.columns)[:4]}...)", path, 1)
    ids = numeric(df, ["id"], path, lo=0, integer=True)[:, 0].astype(int)
    names = [str(v).strip() for v in df["gesture_name"].tolist()]
    out: dict[int, str] = {}
    for row, (i, name) in enumerate(zip(ids.tolist(), names)):
        if i in out or name in out.values() or not name or name == "nan":
            raise DataError(f"gesture id {i} or name {name!r} given twice, or empty", path, row + 2)
        out[i] = name
    return out


def _check_header(columns: list[str], path: Path) -> list[str]:
    """The data columns in file order; a trailing comma's empty column is allowed."""
    named = [c for c in columns if c and not c.startswith("Unnamed:")]
    if named != list(COLUMNS):
        wrong = next((i for i, (a, b) in enumerate(zip(named, COLUMNS)) if a != b), min(len(named), len(COLUMNS)))
        found = named[wrong] if wrong < len(named) else "(end of header)"
        expected = COLUMNS[wrong] if wrong < len(COLUMNS) else "(end of header)"
        raise DataError(f"header column {wrong + 1} is {found!r}, expected {expected!r} "
                        f"(participantID,gesture,repetition,frameID,time,pixel0..pixel{len(COLUMNS) - 6})", path, 1)
    return named


def read_recording(rec: Recording) -> list[Capture]:
    """The captures of one file, checked row by row."""
    path = rec.path
    df = read_table(path)
    _check_header(list(df.columns), path)
    extra = [c for c in df.columns if c not in COLUMNS]
    if extra and df[extra].notna().any().any():
        r = int(np.flatnonzero(df[extra].notna().any(axis=1).to_numpy())[0])
        raise DataError(f"more values than the {len(COLUMNS)} header columns", path, r + 2)
    keys = numeric(df, list(KEYS), path, lo=0, integer=True).astype(np.int64)
    for j, (name, want) in enumerate((("participantID", rec.participant), ("gesture", rec.gesture))):
        bad = np.flatnonzero(keys[:, j] != want)
        if bad.size:
            raise DataError(f"{name} {keys[bad[0], j]} in a file named for {name} {want}", path, int(bad[0]) + 2)
    frame_id = numeric(df, ["frameID"], path, lo=0, integer=True)[:, 0]
    time_ms = numeric(df, ["time"], path, lo=0, integer=True)[:, 0].astype(np.int64)
    pixels = numeric(df, list(COLUMNS[5:]), path, lo=VALUE_RANGE[0], hi=VALUE_RANGE[1], integer=True)
    spans = runs(pd.DataFrame(keys, columns=list(KEYS)), frame_id, path, counter_name="frameID", origin=0)
    out, seen = [], {}
    for start, stop in spans:
        rep = int(keys[start, 2])
        if rep in seen:
            raise DataError(f"repetition {rep} starts again (it began at line {seen[rep]})", path, start + 2)
        seen[rep] = start + 2
        t = time_ms[start:stop]
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            i = start + int(back[0]) + 1
            raise DataError(f"time {time_ms[i]} ms does not follow {time_ms[i - 1]} ms (time must increase within a capture)",
                            path, i + 2)
        frames = pixels[start:stop].astype(np.uint8).reshape(stop - start, *GRID)
        out.append(Capture(rec.participant, rec.gesture, rep, t.copy(), frames, rec.original_name))
    return out


def resample(time_ms: np.ndarray, frames: np.ndarray, rate_hz: float = RATE_HZ) -> tuple[np.ndarray, np.ndarray]:
    """Frames at ``k * 1000 / rate_hz`` ms from the first (module docstring): times (ms) and frames.

    Linear interpolation between the recorded frames around each time,
    rounded to the nearest integer, halves up, in the input dtype (integer
    frames). Computed exactly in integers (times in units of ``1 / q`` ms,
    the step being ``p / q`` ms), so a value exactly half-way between two
    integers -- common: the grid time often falls midway between two
    recorded frames -- is never decided by floating-point error.
    """
    step = Fraction(1000) / Fraction(rate_hz).limit_denominator(1000)
    p, q = step.numerator, step.denominator
    tu = (np.asarray(time_ms, dtype=np.int64) - int(time_ms[0])) * q
    n = len(tu)
    k = int(tu[-1] // p) + 1
    gu = np.arange(k, dtype=np.int64) * p
    if n == 1:
        return gu / q, frames[:1].copy()
    left = np.clip(np.searchsorted(tu, gu, side="right") - 1, 0, n - 2)
    span = (tu[left + 1] - tu[left])[:, None, None]
    into = (gu - tu[left])[:, None, None]
    x = frames.astype(np.int64)
    num = x[left] * (span - into) + x[left + 1] * into
    return gu / q, ((2 * num + span) // (2 * span)).astype(frames.dtype)


def read_all(base: Path) -> tuple[list[Capture], dict[int, str], str]:
    """Every capture as recorded, sorted by participant, gesture, repetition; the gesture names; what
    ``SHA256SUMS`` checked (:func:`touchbench.datasets.checksums.verify_checksums`)."""
    names = gesture_names(base)
    recs = find_recordings(base / "raw")
    files = []
    captures: list[Capture] = []
    for r in recs:
        if r.gesture not in names:
            raise DataError(f"gesture id {r.gesture} is not in GesturesRated.csv (ids {min(names)}..{max(names)})", r.path)
        files.append((r.original_name, r.path, hashlib.sha256(read_bytes(r.path)).hexdigest()))
        captures += read_recording(r)
    checked = verify_checksums(base / "SHA256SUMS", files, base / "raw")["checksums"]
    return sorted(captures, key=lambda c: (c.participant, c.gesture, c.repetition)), names, checked


def _meta(captures: list[Capture], names: dict[int, str]) -> pd.DataFrame:
    return pd.DataFrame({
        "capture_id": [f"p{c.participant}-{names[c.gesture]}-r{c.repetition:02d}" for c in captures],
        "subject": [f"p{c.participant}" for c in captures],
        "gesture": [names[c.gesture] for c in captures],
        "gesture_id": np.array([c.gesture for c in captures], dtype=np.int64),
        "repetition": np.array([c.repetition for c in captures], dtype=np.int64),
        "source": [c.source for c in captures],
    })


def _recorded_note(captures: list[Capture]) -> str:
    n = np.array([len(c.time_ms) for c in captures])
    s = time_step_summary([c.time_ms for c in captures])
    return (f"{int(n.sum())} frames, {n.min()}..{n.max()} per capture (median {np.median(n):g}); time steps median "
            f"{s['median']:g} ms, 95th percentile {s['p95']:g} ms, {s['min']:g}..{s['max']:g} ms")


def build_recorded(base: Path) -> TouchDataset:
    captures, names, checked = read_all(base)
    meta = _meta(captures, names)
    meta["time_ms"] = [c.time_ms.tolist() for c in captures]
    ds = TouchDataset("socialtouch-recorded", [c.frames for c in captures], meta, SOCIALTOUCH_SENSOR)
    ds.provenance = {
        "source": SOURCE,
        "frame rule": (f"as recorded, irregular; time_ms holds each frame's time. The sensor's {RATE_HZ:g} Hz is the "
                   "median step only: fixed-rate methods belong on socialtouch (resampled to that rate)"),
        "recorded": _recorded_note(captures),
        "checksums": checked,
    }
    return ds


def build_resampled(base: Path) -> TouchDataset:
    captures, names, checked = read_all(base)
    meta = _meta(captures, names)
    times, frames = zip(*(resample(c.time_ms, c.frames) for c in captures))
    meta["recorded_frames"] = np.array([len(c.time_ms) for c in captures], dtype=np.int64)
    meta["time_ms"] = [t.tolist() for t in times]
    meta[RECORDED_TIME_COLUMN] = [c.time_ms.tolist() for c in captures]
    ds = TouchDataset("socialtouch", list(frames), meta, SOCIALTOUCH_SENSOR)
    ds.provenance = {
        "source": SOURCE,
        "frame rule": (f"resampled to a fixed {RATE_HZ:g} Hz (frame k at k * {1000 / RATE_HZ:.2f} ms up to the last recorded "
                   "frame), each cell linearly interpolated between the recorded frames around that time, rounded to "
                   "the nearest integer (halves up); the recorded times are in recorded_time_ms (socialtouch-recorded: the frames "
                   "as recorded)"),
        "recorded": _recorded_note(captures),
        "checksums": checked,
    }
    return ds


def _source_files(base: Path) -> list[Path]:
    files = [r.path for r in find_recordings(base / "raw")] + [base / "GesturesRated.csv"]
    if (base / "SHA256SUMS").is_file():
        files.append(base / "SHA256SUMS")
    return files


@DATASETS.register(
    "socialtouch",
    description="SocialTouch capacitive grid: 2493 captures, 32 gestures, 3 people, 19x24, resampled to 12 Hz",
    real=True,
)
def load_socialtouch(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    base = _base_dir(data_dir)
    return cached_dataset("socialtouch", READER_VERSION, _source_files(base), lambda: build_resampled(base),
                          cache_dir, refresh)


@DATASETS.register(
    "socialtouch-recorded",
    description="the SocialTouch captures as recorded: irregular frames, per-frame times in time_ms",
    real=True,
)
def load_socialtouch_recorded(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    base = _base_dir(data_dir)
    return cached_dataset("socialtouch-recorded", READER_VERSION, _source_files(base), lambda: build_recorded(base),
                          cache_dir, refresh)
