"""The ``haart-raw`` format: recordings of any study in the HAART organisers' raw format.

The format (../shared/data/haart/README.md; Gaus et al. 2015, section 2):
one text file per recording, plain or gzipped, ten comma-separated lines of
ten raw ADC values per frame of the 10 x 10 fabric sensor (0..1023, higher =
less pressure), 54 frames per second. The registered ``haart`` dataset is
the challenge's study read this way; this reader takes a folder of another
study's recordings (other participants, sessions, robots) from the command
line.

**Names.** Participant, conditions and gesture are parsed from each file's
name (``.gz`` and then ``.csv`` taken off) by a regular expression with
named groups (``pattern``), which must match the whole name and have the
groups ``participant`` and ``gesture``. The default is the organisers'
naming, ``<study>-<participant><substrate><cover><gesture>`` as in
``140729-3foamfurpat``::

    (?P<study>\\d+)-(?P<participant>\\d+)(?P<substrate>curve|foam|none)
    (?P<cover>fur|long|none|short)(?P<gesture>constant|notouch|pat|rub|scratch|stroke|tickle)

Every group is a metadata column. The subject is ``s<participant>`` (two
digits for a number), prefixed by ``<study>-`` when the pattern has a
``study`` group, so that participant 1 of two studies are two people; the
capture id is the subject followed by the other groups' values. The folder
is searched recursively; ``note.txt``, ``README*``, ``SHA256SUMS`` and
hidden files are not recordings, and any other file the pattern does not
match is refused (a recording left out without a word would bias a
benchmark). Two files giving one capture are refused.

**Windows** (``recording_window``), on the first ``recording_seconds`` (10 s, HAART's
protocol) of each recording:

``middle`` or ``middle:SECONDS``
    the middle 8 s (or SECONDS) of the recording: for HAART, frames 55..486
    (1-based) of 540, the ``haart`` dataset's corrected window.
``challenge``
    the organisers' window with its bug (README, "window bug"), exactly as
    ``haart-challenge``; at 54 Hz over 10 s only.
``whole``
    every frame of the recording, whatever its length (a last frame of
    fewer than ten lines is refused).

A recording longer than ``recording_seconds`` is cut to its first
``recording_seconds``, as the organisers cut HAART's three long files (the
provenance lists each file cut); a shorter one is refused as truncated,
naming the file and line, except with ``whole``. Every frame is cropped to
the inner 8 x 8 (grid rows and columns 2..9, the organisers' crop) and
turned into pressure (1023 - raw). Byte-identical recordings are
placeholders as in HAART: the copies are left out, with a warning, and
listed in the provenance.
"""

from __future__ import annotations

import hashlib
import logging
import re
from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .formats import FormatOption, parse_frame_rate, register_format
from .haart import (
    GESTURES, HAART_SENSOR, RAW_SIDE, challenge_window, find_placeholders, frame_window, parse_recording, read_bytes,
)
from .model import TouchDataset

log = logging.getLogger("touchbench.datasets")

__all__ = ["DEFAULT_PATTERN", "read_haart_raw"]

DEFAULT_PATTERN = (r"(?P<study>\d+)-(?P<participant>\d+)(?P<substrate>curve|foam|none)(?P<cover>fur|long|none|short)"
                   r"(?P<gesture>" + "|".join(GESTURES) + r")")
RECORDING_SECONDS = 10.0  # HAART's protocol: 10 s per gesture
NOT_RECORDINGS = re.compile(r"(?i)^(note\.txt|readme.*|sha256sums|\..*)$")


@dataclass(frozen=True)
class RawRecording:
    """A recording and the groups its name gave (what :func:`find_placeholders` reads)."""

    path: Path
    groups: tuple[tuple[str, str], ...]

    @property
    def fields(self) -> dict[str, str]:
        return dict(self.groups)

    @property
    def participant(self) -> str:
        return self.fields["participant"]

    @property
    def gesture(self) -> str:
        return self.fields["gesture"]

    @property
    def subject(self) -> str:
        p = self.participant
        s = f"s{int(p):02d}" if p.isdigit() else f"s{p}"
        return f"{self.fields['study']}-{s}" if "study" in self.fields else s

    @property
    def stem(self) -> str:
        """The conditions and gesture, as a note names a recording (``foamnonerub``)."""
        return "".join(v for k, v in self.groups if k not in ("study", "participant"))

    @property
    def key(self) -> tuple[str, ...]:
        return tuple(v for _, v in self.groups)

    @property
    def capture_id(self) -> str:
        return "-".join([self.subject, *(v for k, v in self.groups if k not in ("study", "participant"))])


def compile_pattern(pattern: str) -> re.Pattern:
    """The file-name pattern, checked: it compiles and names ``participant`` and ``gesture``."""
    try:
        rx = re.compile(pattern)
    except re.error as e:
        raise TouchbenchError(f"--pattern is not a regular expression ({e}): {pattern!r}") from None
    missing = [g for g in ("participant", "gesture") if g not in rx.groupindex]
    if missing:
        raise TouchbenchError(f"--pattern needs the named group(s) {', '.join(f'(?P<{g}>...)' for g in missing)}: "
                              f"{pattern!r}")
    return rx


def find_raw_recordings(folder: Path, rx: re.Pattern) -> list[RawRecording]:
    """Every recording below ``folder`` whose name ``rx`` matches, sorted; anything else refused."""
    if not folder.is_dir():
        raise DataError("no such folder (the haart-raw format reads a folder of recordings)", folder)
    recs, seen = [], {}
    for p in sorted(q for q in folder.rglob("*") if q.is_file()):
        if NOT_RECORDINGS.match(p.name) or any(part.startswith(".") for part in p.relative_to(folder).parts):
            continue
        stem = p.name.removesuffix(".gz").removesuffix(".csv")
        m = rx.fullmatch(stem)
        if m is None:
            raise DataError(f"the file name {stem!r} does not match the recording pattern {rx.pattern!r} "
                            "(give --pattern, a regular expression with (?P<participant>...) and "
                            "(?P<gesture>...))", p)
        rec = RawRecording(p, tuple((k, v) for k, v in m.groupdict().items() if v is not None))
        if rec.key in seen:
            raise DataError(f"recording given twice (also {seen[rec.key].relative_to(folder)})", p)
        seen[rec.key] = p
        recs.append(rec)
    if not recs:
        raise DataError("no recordings in this folder", folder)
    return recs


@dataclass(frozen=True)
class Window:
    """Which frames of a recording make the capture (module docstring)."""

    kind: str  # middle, challenge or whole
    seconds: float | None = None

    @classmethod
    def parse(cls, text: str) -> "Window":
        kind, _, secs = str(text).strip().lower().partition(":")
        if kind in ("whole", "challenge") and not secs:
            return cls(kind)
        if kind == "middle":
            try:
                s = float(secs) if secs else 8.0
            except ValueError:
                s = -1.0
            if s > 0:
                return cls(kind, s)
        raise ValueError(f"expected middle, middle:SECONDS, challenge or whole, got {text!r}")

    def describe(self, rate: float, recording_s: float) -> str:
        if self.kind == "whole":
            return "whole: every frame of each recording"
        if self.kind == "challenge":
            return "the organisers' window (bug included): frame i = lines 8i+55..8i+62 of the row-trimmed stream"
        first, n = self.frames(rate, recording_s)
        return f"middle {self.seconds:g} s of the first {recording_s:g} s: frames {first + 1}..{first + n} (1-based)"

    def frames(self, rate: float, recording_s: float) -> tuple[int, int]:
        total = round(recording_s * rate)
        n = round(self.seconds * rate)
        if not 1 <= n <= total:
            raise TouchbenchError(f"--recording-window middle:{self.seconds:g} asks for {n} frames of a {recording_s:g}-s "
                                  f"recording of {total} frames")
        return (total - n) // 2, n


def read_haart_raw(
    path: str | Path,
    *,
    pattern: str | None = None,
    recording_window: str | Window = "middle",
    recording_seconds: float | None = None,
    frame_rate: float | None = None,
    name: str | None = None,
) -> TouchDataset:
    """Read a folder of raw-format recordings (module docstring). The sensor is HAART's (at
    ``frame_rate``): a model of another sensor refuses the data, naming both."""
    folder = Path(path)
    rx = compile_pattern(pattern or DEFAULT_PATTERN)
    win = recording_window if isinstance(recording_window, Window) else Window.parse(recording_window)
    rate = float(frame_rate or HAART_SENSOR.frame_rate)
    rec_s = float(recording_seconds or RECORDING_SECONDS)
    if win.kind == "challenge" and (rate != HAART_SENSOR.frame_rate or rec_s != RECORDING_SECONDS):
        raise TouchbenchError("--recording-window challenge is the organisers' window of 10-s recordings at 54 Hz only")
    lines_used = round(rec_s * rate) * RAW_SIDE
    recs = find_raw_recordings(folder, rx)
    arrays, digests, cut = {}, {}, []
    for r in recs:
        data = read_bytes(r.path)
        digests[r.key] = hashlib.sha256(data).hexdigest()
        arr = parse_recording(data, r.path, min_lines=RAW_SIDE if win.kind == "whole" else lines_used)
        if win.kind == "whole":
            if len(arr) % RAW_SIDE:
                raise DataError(f"{len(arr)} lines is not a whole number of {RAW_SIDE}-line frames (the last frame "
                                "is cut short)", r.path, len(arr) - len(arr) % RAW_SIDE + 1)
        elif len(arr) > lines_used:
            cut.append(f"{r.path.relative_to(folder)}: {len(arr)} lines, the first {lines_used} used")
            arr = arr[:lines_used]
        arrays[r.key] = arr
    placeholders = find_placeholders(folder, recs, digests)
    dropped = {p["capture_id"] for p in placeholders}
    for p in placeholders:
        log.warning("%s: left out, %s of %s (%s)", p["file"], p["capture_id"], p["copy_of"], p["reason"])
    kept = [r for r in recs if r.capture_id not in dropped]
    if win.kind == "whole":
        captures = [frame_window(arrays[r.key], 0, len(arrays[r.key]) // RAW_SIDE) for r in kept]
    elif win.kind == "challenge":
        captures = [challenge_window(arrays[r.key]) for r in kept]
    else:
        first, n = win.frames(rate, rec_s)
        captures = [frame_window(arrays[r.key], first, n) for r in kept]
    columns = [k for k, _ in kept[0].groups] if kept else []
    meta = pd.DataFrame({
        "capture_id": [r.capture_id for r in kept],
        "subject": [r.subject for r in kept],
        **{k: [r.fields.get(k) for r in kept] for k in columns if k != "participant"},
        "participant": [r.participant for r in kept],
        "source": [str(r.path.relative_to(folder)).removesuffix(".gz") for r in kept],
    })
    ds = TouchDataset(name or folder.name, captures, meta, replace(HAART_SENSOR, frame_rate=rate))
    ds.provenance = {
        "pattern": rx.pattern,
        "window": win.describe(rate, rec_s),
        "crop": "inner 8 x 8 of the 10 x 10 grid (rows and columns 2..9), pressure = 1023 - raw",
        "cut": cut or "none",
        "placeholders": placeholders,
    }
    return ds


def parse_seconds(text: str) -> float:
    """A positive number of seconds."""
    try:
        v = float(text)
    except ValueError:
        v = -1.0
    if not v > 0:
        raise ValueError(f"expected a positive number of seconds, got {text!r}")
    return v


register_format(
    "haart-raw",
    "recordings of any study in the HAART organisers' raw format (10 lines of 10 values a frame), a folder",
    read_haart_raw,
    reads="folder",
    options=(
        FormatOption("pattern", "Regular expression for the file names, with (?P<participant>...) and "
                     "(?P<gesture>...) (default: the organisers' <study>-<participant><substrate><cover><gesture>)",
                     metavar="REGEX"),
        FormatOption("recording_window", "middle, middle:SECONDS (default middle: the middle 8 s), challenge or whole",
                     Window.parse, metavar="WINDOW"),
        FormatOption("recording_seconds", "Length of a recording in seconds; longer ones are cut to it "
                     "(default 10, HAART's)", parse_seconds, metavar="SECONDS"),
        FormatOption("frame_rate", "Frames per second (default 54, the HAART sensor's)", parse_frame_rate),
    ),
)
