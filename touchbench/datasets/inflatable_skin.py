"""The ``inflatable-skin`` dataset: continuous recordings of an inflatable robot skin, labelled frame by frame.

Source: the public GitHub repository ``mdethmers/Social-Touch-Research``,
commit 0ea7cf5, folder ``Annotated-dataset/``; its paper is "A gesture and
touch recognising inflatable soft social robot". A soft, inflatable social
robot whose skin carries a grid of pressure cells (19 x 27) was touched
repeatedly with one gesture per recording, with rests in between, and every
frame was labelled by hand. The repository states no licence: touchbench
reads the files from the shared data folder (``inflatable-skin/`` of
``$TOUCHBENCH_DATA_DIR``, else ``shared/data`` beside the checkout) and
never ships them.

**Files.** ``raw/<label>_<YYYYMMDDhhmmss>_annotated.json``, plain or gzipped
(``.gz`` appended): a JSON object with the recording's own ``label``
(``Unknown`` for a recording of taps) and ``frames``, a list of
``{frame_index, label, data}`` in order (``frame_index`` 0, 1, ...), ``data``
a grid as a list of rows of numbers in 0..255, higher = more pressure.
``SHA256SUMS`` beside ``raw/`` lists the SHA-256 of every original
(uncompressed) file: a file whose content differs, a listed file that is
absent and a recording it does not list are each refused, naming the file.
The grid is read from the data: a frame whose shape differs from its
recording's first frame, a value outside 0..255 and a frame out of order
are refused, naming the file and the frame.

**Captures are segments**: one capture per run of one frame label within a
recording (frames in order), ``(T, H, W)`` float32. The values are kept
exactly as the files give them: they are not all whole numbers (the source
stores halves, such as 7.5), so they are not rounded into integers.
Metadata columns: ``capture_id`` (``<recording>@<start_frame>``, e.g.
``Grab_20250521150749@0``), ``subject``, ``session``, ``recording`` (the file
name without ``_annotated.json[.gz]``), ``recording_gesture`` (the
recording's own ``label``), ``start_frame`` (the segment's first frame within
its recording, from 0) and ``gesture`` (the frame label; the source's
``None``, no touch, becomes ``idle``; the others as the source spells them:
``Grab``, ``Stroke``, ``Squeez``, ``Tickle``, ``Tap``, ``hug``, ``Punch``).
``recording`` and ``start_frame`` let a stream evaluation put each recording
back together (:func:`touchbench.streams.timeline.recorded_streams`).

**Sessions and subjects.** The files carry no session field: recordings are
sorted by the timestamp in their names, and a new sitting starts when the
day changes or more than 60 minutes passed since the previous recording; a
session is named ``YYYY-MM-DD-N`` (N: the sitting within that day, from 1).
The people are not identified in the source, so the subject is the
session: leave-one-subject-out on this dataset is leave one session out.

**Frame rate: an assumption.** The files carry no frame times; the source's
scripts treat the frames as a sequence at about 10 frames per second. The
sensor says 10 Hz, and every time in seconds computed on this dataset (a
stream's length, a window in seconds) depends on that assumption:
``touchbench data info inflatable-skin`` says so.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections import Counter
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.errors import DataError
from ..core.paths import raw_folder
from .cache import cached_dataset
from .checksums import read_bytes, verify_checksums
from .model import SensorSpec, TouchDataset
from .registry import DATASETS

__all__ = ["FRAME_RATE", "NAME", "Recording", "find_recordings", "load_inflatable_skin", "read_recording",
           "runs", "sessions"]

NAME = "inflatable-skin"
READER_VERSION = "inflatable-skin-1"
#: frames per second: an ASSUMPTION (module docstring), the files carry no frame times
FRAME_RATE = 10.0
VALUE_RANGE = (0.0, 255.0)
#: more than this long since the previous recording starts a new sitting
SITTING_GAP = timedelta(minutes=60)
SOURCE_IDLE, IDLE = "None", "idle"
SUFFIX = "_annotated.json"
SOURCE = ('the GitHub repository mdethmers/Social-Touch-Research, commit 0ea7cf5, folder Annotated-dataset/ '
          '("A gesture and touch recognising inflatable soft social robot"); no licence stated: read from the '
          'data folder, never shipped with touchbench')
FRAME_RATE_NOTE = (f"{FRAME_RATE:g} Hz is an ASSUMPTION: the files carry no frame times (the source's scripts treat "
                   "the frames as a sequence at about 10 per second); every time in seconds shown for this dataset "
                   "(the streams line) depends on it")
SUBJECT_NOTE = ("the people are not identified in the source: the subject is the session, so leave-one-subject-out "
                "on this dataset is leave one session out")
_NAME_RE = re.compile(r"^(?P<label>.+)_(?P<stamp>\d{14})" + re.escape(SUFFIX) + r"(?:\.gz)?$")


@dataclass(frozen=True)
class Recording:
    """One recording file: its path, name (the file name without ``_annotated.json[.gz]``) and time."""

    path: Path
    name: str
    time: datetime

    @property
    def listed_as(self) -> str:
        """The name SHA256SUMS gives it: the original, uncompressed file."""
        return self.path.name.removesuffix(".gz")




def find_recordings(raw: Path) -> list[Recording]:
    """Every recording in ``raw``, sorted by time (then name); a ``.json`` file not named
    ``<label>_<YYYYMMDDhhmmss>_annotated.json[.gz]``, a timestamp that is no date and a recording
    given twice (plain and gzipped) are refused, naming the file."""
    recs: dict[str, Recording] = {}
    for p in sorted(raw.iterdir()):
        if p.name.startswith(".") or not p.is_file() or not p.name.removesuffix(".gz").endswith(".json"):
            continue
        m = _NAME_RE.match(p.name)
        if m is None:
            raise DataError(f"not a recording's name: expected <label>_<YYYYMMDDhhmmss>{SUFFIX}[.gz]", p)
        try:
            time = datetime.strptime(m["stamp"], "%Y%m%d%H%M%S")
        except ValueError:
            raise DataError(f"the timestamp {m['stamp']} in the name is no date and time (YYYYMMDDhhmmss)", p) from None
        name = p.name.removesuffix(".gz").removesuffix(SUFFIX)
        if name in recs:
            raise DataError(f"recording given twice (also {recs[name].path.name})", p)
        recs[name] = Recording(p, name, time)
    if not recs:
        raise DataError(f"no {NAME} recordings (<label>_<YYYYMMDDhhmmss>{SUFFIX}[.gz]) found", raw)
    return sorted(recs.values(), key=lambda r: (r.time, r.name))


def sessions(recs: list[Recording]) -> dict[str, str]:
    """Recording name -> session (module docstring): sorted by time, a new sitting when the day
    changes or more than :data:`SITTING_GAP` passed since the previous recording; ``YYYY-MM-DD-N``."""
    out: dict[str, str] = {}
    prev: datetime | None = None
    sitting = 0
    for r in sorted(recs, key=lambda r: (r.time, r.name)):
        if prev is None or r.time.date() != prev.date():
            sitting = 1
        elif r.time - prev > SITTING_GAP:
            sitting += 1
        out[r.name] = f"{r.time:%Y-%m-%d}-{sitting}"
        prev = r.time
    return out


def runs(labels: list[str]) -> list[tuple[int, int]]:
    """The runs of one label in ``labels``: ``(start, stop)`` pairs, in order."""
    starts = [i for i in range(len(labels)) if i == 0 or labels[i] != labels[i - 1]]
    return list(zip(starts, starts[1:] + [len(labels)]))


def _frame(fr: object, k: int, path: Path, shape: tuple[int, ...] | None) -> tuple[str, np.ndarray]:
    """Frame ``k`` of the file ``path``: its label and grid, checked (module docstring)."""
    where = f"frame {k}"
    if not isinstance(fr, dict) or not {"frame_index", "label", "data"} <= set(fr):
        raise DataError(f"{where}: expected an object with frame_index, label and data", path)
    if fr["frame_index"] != k:
        raise DataError(f"{where}: frame_index {fr['frame_index']!r}; the frames must be in order, from 0", path)
    label = fr["label"]
    if not isinstance(label, str) or not label.strip():
        raise DataError(f"{where}: the label {label!r} is not a name", path)
    try:
        grid = np.asarray(fr["data"], dtype=np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{where}: data is not a grid of numbers (a list of rows of equal length)", path) from None
    if grid.ndim != 2 or (shape is not None and grid.shape != shape):
        want = f"the {shape[0]} x {shape[1]} of the recording's first frame" if shape else "a grid (a list of rows)"
        raise DataError(f"{where}: data of shape {' x '.join(map(str, grid.shape)) or 'scalar'}, not {want}", path)
    bad = ~((grid >= VALUE_RANGE[0]) & (grid <= VALUE_RANGE[1]))  # NaN is outside too
    if bad.any():
        r, c = (int(i[0]) for i in np.nonzero(bad))
        raise DataError(f"{where}: value {float(grid[r, c]):g} at row {r}, column {c} is outside "
                        f"{VALUE_RANGE[0]:g}..{VALUE_RANGE[1]:g}", path)
    return label, grid


def read_recording(data: bytes, path: Path) -> tuple[str, list[str], np.ndarray]:
    """A recording's own label, each frame's label (as the source spells it) and its frames
    ``(T, H, W)`` float32, checked (module docstring); errors name ``path`` and the frame."""
    try:
        doc = json.loads(data)
    except ValueError as e:
        raise DataError(f"not a JSON file ({e})", path) from None
    if not isinstance(doc, dict) or not isinstance(doc.get("frames"), list) or not isinstance(doc.get("label"), str):
        raise DataError("expected a JSON object with a label and a list of frames", path)
    if not doc["frames"]:
        raise DataError("a recording without frames", path)
    labels, grids = [], []
    for k, fr in enumerate(doc["frames"]):
        label, grid = _frame(fr, k, path, grids[0].shape if grids else None)
        labels.append(label)
        grids.append(grid)
    return doc["label"], labels, np.stack(grids).astype(np.float32)


def _checked(raw: Path, recs: list[Recording]) -> tuple[dict[str, bytes], str]:
    """Each recording's original bytes, checked against SHA256SUMS beside ``raw``
    (:func:`touchbench.datasets.checksums.verify_checksums`: a mismatch or a listed recording that is
    absent is refused; an unlisted one, or no list, is said), and what was checked (the provenance)."""
    contents = {r.name: read_bytes(r.path) for r in recs}
    said = verify_checksums(raw.parent / "SHA256SUMS",
                            [(r.listed_as, r.path, hashlib.sha256(contents[r.name]).hexdigest()) for r in recs], raw)
    return contents, said["checksums"]


def _provenance(recs: list[Recording], session_of: dict[str, str], frames: dict[str, list[str]],
                arrays: dict[str, np.ndarray], checked: str) -> dict[str, object]:
    per_label = Counter(IDLE if g == SOURCE_IDLE else g for labels in frames.values() for g in labels)
    n_runs = {r.name: len(runs(frames[r.name])) for r in recs}
    lengths = [len(frames[r.name]) for r in recs]
    by_session: dict[str, list[str]] = {}
    for r in recs:
        by_session.setdefault(session_of[r.name], []).append(r.name)
    values = np.concatenate([a.ravel() for a in arrays.values()])
    whole = bool(np.all(values == np.round(values)))
    return {
        "source": SOURCE,
        "frame rate": FRAME_RATE_NOTE,
        "subjects": SUBJECT_NOTE,
        "recordings": f"{len(recs)}, {sum(lengths)} frames",
        "sessions": {s: f"{len(v)} recordings: {', '.join(v)}" for s, v in by_session.items()},
        "frames per label": {g: per_label[g] for g in sorted(per_label, key=lambda g: (-per_label[g], g))},
        "segments": (f"{sum(n_runs.values())} (runs of one label; {min(n_runs.values())}..{max(n_runs.values())} "
                     "per recording)"),
        "recording lengths": {r.name: f"{len(frames[r.name])} frames, {n_runs[r.name]} segments" for r in recs},
        "values": (f"{values.min():g}..{values.max():g}, {len(np.unique(values))} distinct; "
                   + ("whole numbers" if whole else "not all whole numbers (the source stores halves): kept exactly, "
                      "float32")),
        "checksums": checked,
    }


def build_inflatable_skin(raw: Path) -> TouchDataset:
    """The dataset read from ``raw`` (module docstring)."""
    recs = find_recordings(raw)
    contents, checked = _checked(raw, recs)
    session_of = sessions(recs)
    captures, rows, frames, arrays, grid = [], [], {}, {}, None
    for r in recs:
        own, labels, arr = read_recording(contents[r.name], r.path)
        if grid is not None and arr.shape[1:] != grid:
            raise DataError(f"frames of {arr.shape[1]} x {arr.shape[2]}, not the {grid[0]} x {grid[1]} of "
                            f"{recs[0].path.name}: one sensor's recordings share one grid", r.path)
        grid = arr.shape[1:]
        frames[r.name], arrays[r.name] = labels, arr
        for a, b in runs(labels):
            captures.append(arr[a:b])
            rows.append({"capture_id": f"{r.name}@{a}", "subject": session_of[r.name], "session": session_of[r.name],
                         "recording": r.name, "recording_gesture": own, "start_frame": a,
                         "gesture": IDLE if labels[a] == SOURCE_IDLE else labels[a]})
    sensor = SensorSpec(name=NAME, grid=grid, frame_rate=FRAME_RATE, value_range=VALUE_RANGE,
                        higher_is_more_pressure=True)
    ds = TouchDataset(NAME, captures, pd.DataFrame(rows), sensor)
    ds.provenance = _provenance(recs, session_of, frames, arrays, checked)
    return ds


def _source_files(raw: Path) -> list[Path]:
    files = [r.path for r in find_recordings(raw)]
    return files + ([raw.parent / "SHA256SUMS"] if (raw.parent / "SHA256SUMS").is_file() else [])


@DATASETS.register(NAME, description="an inflatable robot skin (19x27), recordings labelled frame by frame, cut "
                                     "into runs of one label; 10 Hz assumed", real=True)
def load_inflatable_skin(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    """The recordings (module docstring) as segments, from ``inflatable-skin/`` of the shared data."""
    raw = raw_folder(NAME, data_dir)
    return cached_dataset(NAME, READER_VERSION, _source_files(raw), lambda: build_inflatable_skin(raw), cache_dir,
                          refresh)
