"""Real HAART, read from the organisers' raw recordings.

Source and format: ../shared/data/haart/README.md (Social Touch Gesture
Challenge 2015; Gaus et al. 2015, section 2; Al-mashhadani et al.
2021, section 2.1). Each recording is a 10 x 10 grid at 54 frames
per second for 10 s, ten text lines per frame, raw ADC values 0..1023 where a
higher value means less pressure.

Two registered datasets:

``haart``
    every real recording (placeholder copies removed), the corrected middle
    8 s: frames 55..486 (1-based) of the 540, grid rows and columns 2..9
    (the 8 x 8 the organisers kept), pressure = 1023 - raw, uint16.
``haart-challenge``
    exactly the captures the challenge released (578 train + 251 test), with
    the organisers' window, which offsets by 54 *lines* instead of 54
    *frames* (README, "window bug"): output frame i is lines ``8 i + 55 ..
    8 i + 62`` (1-based) of the row-trimmed stream. Results on it compare
    with published challenge numbers.

Placeholders are found by content: recordings whose decompressed bytes are
identical. Which member of a group of identical recordings is the copy is
read from the organisers' ``note.txt`` in the participant's folder ("X is
Y", "ALL X are Y"); a group no note explains keeps the recording whose
gesture is ``notouch`` (a copy of no-touch data labelled as a gesture is the
placeholder), and otherwise the first in sorted order, and says so.
"""

from __future__ import annotations

import hashlib
import io
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.errors import DataError
from ..core.paths import raw_folder
from .cache import cached_dataset
from .checksums import read_bytes, verify_checksums
from .model import SensorSpec, TouchDataset
from .registry import DATASETS

READER_VERSION = "haart-raw-2"  # 2: the checksums' provenance

HAART_SENSOR = SensorSpec(name="haart", grid=(8, 8), frame_rate=54.0, value_range=(0.0, 1023.0))
GESTURES = ("constant", "notouch", "pat", "rub", "scratch", "stroke", "tickle")
RAW_SIDE = 10  # the recorded grid is 10 x 10
LINES_USED = 5400  # 540 frames of 10 lines; longer files: the first 5400 lines
N_FRAMES = 432  # 8 s at 54 Hz
CORRECTED_FIRST_FRAME = 54  # 0-based: frames 55..486 (1-based) are the middle 8 s
CHALLENGE_FIRST_LINE = 54  # 0-based line of the trimmed stream where the organisers' window starts
STUDY = "140729"  # the study id that opens every HAART file name

_NAME_RE = re.compile(
    r"^" + STUDY + r"-(?P<participant>\d+)(?P<substrate>curve|foam|none)(?P<cover>fur|long|none|short)"
    r"(?P<gesture>" + "|".join(GESTURES) + r")(?:\.csv)?(?:\.gz)?$"
)

# The challenge split as the organisers' R scripts (Challenge/datascript.r and
# testscript.r of lauracang/ICMI15) built it: participants in the order of the
# released files, with their labels, and the recordings each script skipped.
CHALLENGE_TRAIN = (4, 8, 7, 5, 10, 3, 6)
CHALLENGE_TEST = (1, 9, 2)
CHALLENGE_EXCLUDED = frozenset(
    [(5, "foam", "none", g) for g in GESTURES]
    + [(10, "curve", "fur", "constant"), (3, "foam", "none", "rub"), (6, "foam", "none", "rub"),
       (9, "none", "fur", "constant")]
)


@dataclass(frozen=True)
class Recording:
    path: Path
    participant: int
    substrate: str
    cover: str
    gesture: str

    @property
    def subject(self) -> str:
        return f"s{self.participant:02d}"

    @property
    def key(self) -> tuple[int, str, str, str]:
        return (self.participant, self.substrate, self.cover, self.gesture)

    @property
    def stem(self) -> str:
        return f"{self.substrate}{self.cover}{self.gesture}"

    @property
    def capture_id(self) -> str:
        return f"{self.subject}-{self.substrate}-{self.cover}-{self.gesture}"




def find_recordings(raw: Path) -> list[Recording]:
    """Every recording under ``raw`` (participant folders), sorted."""
    recs = []
    for p in sorted(raw.glob("*/*")):
        if p.name == "note.txt" or p.name.startswith("."):
            continue
        m = _NAME_RE.match(p.name)
        if m is None:
            continue
        recs.append(Recording(p, int(m["participant"]), m["substrate"], m["cover"], m["gesture"]))
    if not recs:
        raise DataError(f"no HAART recordings ({STUDY}-N<substrate><cover><gesture>[.csv][.gz]) found", raw)
    seen: dict[tuple, Path] = {}
    for r in recs:
        if r.key in seen:
            raise DataError(f"recording given twice (also {seen[r.key].name})", r.path)
        seen[r.key] = r.path
    return sorted(recs, key=lambda r: r.key)


def parse_recording(data: bytes, path: Path, min_lines: int = LINES_USED) -> np.ndarray:
    """Parse a recording into a ``(lines, 10)`` int array, checking every line.

    Refuses, naming the file and line: an empty recording, a non-numeric or non-integer value, a
    line without exactly ten values, a negative value or one above 1023, and
    a recording shorter than ``min_lines`` lines (truncated; HAART's 5400:
    540 frames of 10 lines).
    """
    text = data.decode("ascii", errors="replace")
    if not text.strip():
        raise DataError("empty recording (no lines of values)", path)
    try:
        arr = np.loadtxt(io.StringIO(text), delimiter=",", dtype=np.int64, ndmin=2)
        ok = arr.shape[1] == RAW_SIDE
    except ValueError:
        ok = False
    if not ok:
        _locate_bad_line(text, path)
    if arr.shape[0] < min_lines:
        raise DataError(
            f"truncated recording: {arr.shape[0]} lines, a recording has {min_lines} "
            f"({min_lines // RAW_SIDE} frames of {RAW_SIDE} lines)",
            path,
            arr.shape[0] + 1,
        )
    bad = np.flatnonzero(((arr < 0) | (arr > 1023)).any(axis=1))
    if bad.size:
        line = int(bad[0]) + 1
        raise DataError(f"value out of the ADC range 0..1023: {text.splitlines()[line - 1]!r}", path, line)
    return arr


def _locate_bad_line(text: str, path: Path) -> None:
    for i, line in enumerate(text.splitlines(), start=1):
        if not line.strip():  # blank lines are skipped, as by the parser
            continue
        fields = line.split(",")
        if len(fields) != RAW_SIDE:
            raise DataError(f"expected {RAW_SIDE} comma-separated values, found {len(fields)}", path, i)
        for f in fields:
            try:
                int(f)
            except ValueError:
                raise DataError(f"not an integer value: {f.strip()!r}", path, i) from None
    raise DataError("unreadable recording", path)


def frame_window(arr: np.ndarray, first: int, n: int) -> np.ndarray:
    """Frames ``first .. first + n - 1`` (0-based) of a parsed recording, the inner 8 x 8 (the
    organisers' crop: grid rows and columns 2..9), as pressure (1023 - raw), uint16."""
    frames = arr[: (first + n) * RAW_SIDE].reshape(-1, RAW_SIDE, RAW_SIDE)
    return (1023 - frames[first:first + n, 1:-1, 1:-1]).astype(np.uint16)


def corrected_window(arr: np.ndarray) -> np.ndarray:
    """The middle 8 s, inner 8 x 8, as pressure (1023 - raw), uint16."""
    return frame_window(arr, CORRECTED_FIRST_FRAME, N_FRAMES)


def challenge_window(arr: np.ndarray) -> np.ndarray:
    """The organisers' window, bug included (README steps 1-4), uint16."""
    lines = arr[:LINES_USED, 1:-1]  # step 1: first 5400 lines, drop grid columns 1 and 10
    keep = np.arange(LINES_USED) % RAW_SIDE
    lines = lines[(keep != 0) & (keep != RAW_SIDE - 1)]  # step 2: drop grid rows 1 and 10
    lines = 1023 - lines  # step 3
    start = CHALLENGE_FIRST_LINE  # step 4: frame i = 8 lines from line 8 i + 55 (1-based)
    out = lines[start:start + 8 * N_FRAMES].reshape(N_FRAMES, 8, 8)
    return out.astype(np.uint16)


def _parse_notes(raw: Path, recs: list[Recording]) -> dict[tuple, str]:
    """Map recording key -> the note that names it a copy."""
    copies: dict[tuple, str] = {}
    for note in sorted(raw.rglob("note.txt")):
        text = note.read_text(errors="replace")
        for sentence in re.split(r"[\n.;]+", text):
            s = sentence.strip()
            m_all = re.match(r"(?i)all\s+(\w+)\s+are\s+(?:a\s+)?(\w+)", s)
            m_one = re.match(r"(?i)(\w+)\s+is\s+(?:a\s+)?(\w+)", s)
            members = [r for r in recs if r.path.parent == note.parent]
            if m_all:
                prefix = m_all.group(1).lower()
                for r in members:
                    if r.stem.startswith(prefix):
                        copies[r.key] = f"{note.parent.name}/note.txt: {s!r}"
            elif m_one:
                stem = m_one.group(1).lower()
                for r in members:
                    if r.stem == stem:
                        copies[r.key] = f"{note.parent.name}/note.txt: {s!r}"
    return copies


def find_placeholders(raw: Path, recs: list[Recording], digests: dict[tuple, str]) -> list[dict]:
    """Recordings byte-identical to another: which is the copy, and why."""
    groups: dict[str, list[Recording]] = {}
    for r in recs:
        groups.setdefault(digests[r.key], []).append(r)
    noted = _parse_notes(raw, recs)
    out = []
    for members in groups.values():
        if len(members) < 2:
            continue
        copies = [r for r in members if r.key in noted]
        originals = [r for r in members if r.key not in noted]
        reason = {r.key: f"identical content; named a copy in {noted[r.key]}" for r in copies}
        if not originals:  # a note called every member a copy: keep the first
            originals, copies = [copies[0]], copies[1:]
        if len(originals) > 1:
            keep = [r for r in originals if r.gesture == "notouch"][:1] or originals[:1]
            for r in originals:
                if r is not keep[0]:
                    copies.append(r)
                    reason[r.key] = (
                        "identical content; no note, kept the notouch recording"
                        if keep[0].gesture == "notouch" else "identical content; no note, kept the first in sorted order"
                    )
            originals = keep
        for r in copies:
            out.append({
                "file": f"{r.path.parent.name}/{r.path.name}",
                "capture_id": r.capture_id,
                "copy_of": originals[0].capture_id,
                "reason": reason[r.key],
            })
    return sorted(out, key=lambda d: d["file"])


def _verify_checksums(raw: Path, recs: list[Recording], digests: dict[tuple, str]) -> dict[str, str]:
    return verify_checksums(raw.parent / "SHA256SUMS", [(f"{r.path.parent.name}/{r.path.name}".removesuffix(".gz"),
                                                         r.path, digests[r.key]) for r in recs], raw)


def _source_files(raw: Path) -> list[Path]:
    files = [r.path for r in find_recordings(raw)]
    files += sorted(raw.glob("*/note.txt"))
    if (raw.parent / "SHA256SUMS").is_file():
        files.append(raw.parent / "SHA256SUMS")
    return files


def _read_all(raw: Path) -> tuple[list[Recording], dict[tuple, np.ndarray], list[dict], dict[str, str]]:
    """The recordings under ``raw``, their arrays, the placeholder copies and the checksums' provenance."""
    recs = find_recordings(raw)
    arrays, digests = {}, {}
    for r in recs:
        data = read_bytes(r.path)
        digests[r.key] = hashlib.sha256(data).hexdigest()
        arrays[r.key] = parse_recording(data, r.path)
    checked = _verify_checksums(raw, recs, digests)
    return recs, arrays, find_placeholders(raw, recs, digests), checked


def build_haart(raw: Path) -> TouchDataset:
    recs, arrays, placeholders, checked = _read_all(raw)
    dropped = {p["capture_id"] for p in placeholders}
    train, test = set(CHALLENGE_TRAIN), set(CHALLENGE_TEST)
    kept = [r for r in recs if r.capture_id not in dropped]
    meta = pd.DataFrame({
        "capture_id": [r.capture_id for r in kept],
        "subject": [r.subject for r in kept],
        "substrate": [r.substrate for r in kept],
        "cover": [r.cover for r in kept],
        "gesture": [r.gesture for r in kept],
        "split": [
            "none" if r.key in CHALLENGE_EXCLUDED else "train" if r.participant in train
            else "test" if r.participant in test else "none"
            for r in kept
        ],
        "source": [f"{r.path.parent.name}/{r.path.name.removesuffix('.gz')}" for r in kept],
    })
    ds = TouchDataset("haart", [corrected_window(arrays[r.key]) for r in kept], meta, HAART_SENSOR)
    ds.provenance = {
        "placeholders": placeholders,
        "note": f"the {len(placeholders)} placeholder copies are left out",
        "window": "corrected: frames 55..486 (1-based), rows/cols 2..9",
        **checked,
    }
    return ds


def challenge_meta(recs: list[Recording]) -> pd.DataFrame:
    """Metadata columns of ``haart-challenge`` (what the released CSV holds)."""
    return pd.DataFrame({
        "capture_id": [r.capture_id for r in recs],
        "subject": [r.subject for r in recs],
        "substrate": [r.substrate for r in recs],
        "cover": [r.cover for r in recs],
        "gesture": [r.gesture for r in recs],
        "split": ["train" if r.participant in CHALLENGE_TRAIN else "test" for r in recs],
        "challenge_label": [("P" if r.participant in CHALLENGE_TRAIN else "T") + str(r.participant) for r in recs],
    })


def build_haart_challenge(raw: Path) -> TouchDataset:
    recs, arrays, placeholders, checked = _read_all(raw)
    order = {p: i for i, p in enumerate(CHALLENGE_TRAIN + CHALLENGE_TEST)}
    chosen = sorted(
        (r for r in recs if r.participant in order and r.key not in CHALLENGE_EXCLUDED),
        key=lambda r: (order[r.participant], r.substrate, r.cover, r.gesture),
    )
    ds = TouchDataset("haart-challenge", [challenge_window(arrays[r.key]) for r in chosen], challenge_meta(chosen), HAART_SENSOR)
    ds.provenance = {
        "placeholders": placeholders,
        "window": "organisers' (bug included): frame i = lines 8i+55..8i+62 of the row-trimmed stream",
        "note": "includes s02 none-fur-constant (a copy of s02 none-fur-notouch) and lacks s09's, as released",
        **checked,
    }
    return ds


@DATASETS.register("haart", description="real HAART: 830 captures, corrected middle 8 s, 8x8 at 54 Hz", real=True)
def load_haart(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    raw = raw_folder("haart", data_dir, "HAART")
    return cached_dataset("haart", READER_VERSION, _source_files(raw), lambda: build_haart(raw), cache_dir, refresh)


@DATASETS.register(
    "haart-challenge",
    description="the 578 + 251 captures the 2015 challenge released, organisers' window",
    real=True,
)
def load_haart_challenge(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    raw = raw_folder("haart", data_dir, "HAART")
    return cached_dataset(
        "haart-challenge", READER_VERSION, _source_files(raw), lambda: build_haart_challenge(raw), cache_dir, refresh
    )
