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
challenge's own study (``140729``) keeps the registered ``haart``'s ids
(``s04``, not ``140729-s04``), so that one participant is one subject in
both datasets. The capture id is the subject followed by the other groups'
values. The folder
is searched recursively; ``note.txt``, ``README*``, ``SHA256SUMS`` and
hidden files are not recordings, and any other file the pattern does not
match is refused (a recording left out without a word would bias a
benchmark). Two files giving one capture are refused.

**Windows** (``recording_window``):

``middle``
    HAART's protocol: the middle 8 s of the first 10 s of each recording
    (``recording_seconds``, default 10): for HAART, frames 55..486
    (1-based) of 540, the ``haart`` dataset's corrected window. A longer
    recording is cut to its first 10 s, as the organisers cut HAART's three
    long files; a shorter one is refused as truncated, naming the file and
    line.
``middle:SECONDS``
    the middle SECONDS of each recording, whatever its length (of its first
    ``recording_seconds`` when that is given). A recording shorter than
    SECONDS is refused, naming the file and its length: choose a shorter
    window, or ``short_recordings="leave-out"`` (it is then left out,
    counted in the warning and listed in the provenance's ``left_out``).
``challenge``
    the organisers' window with its bug (README, "window bug"), exactly as
    ``haart-challenge``; at 54 Hz over 10-s recordings only (longer ones cut
    to 10 s, shorter ones refused).
``whole``
    every frame of each recording, whatever its length (of its first
    ``recording_seconds`` when that is given; a last frame of fewer than ten
    lines is refused).

``recording_seconds`` given: each recording is cut to its first SECONDS, and
a shorter one is used whole (so a folder of recordings of different lengths
is read, not refused at its first short file). Every cut and every
recording used whole for being short is counted in a warning at conversion
(with the median length) and in the provenance (``recordings``; ``cut``
lists the files; ``lengths`` counts the recordings of each length as read).
``checksums``: a SHA256SUMS file naming the recordings relative to the
folder (without ``.gz``); a recording whose content differs is refused.

Every frame is cropped to
the inner 8 x 8 (grid rows and columns 2..9, the organisers' crop) and
turned into pressure (1023 - raw). Byte-identical recordings are
placeholders as in HAART: the copies are left out, counted in the same
warning, and listed in the provenance.
"""

from __future__ import annotations

import hashlib
import logging
import re
import statistics
from dataclasses import dataclass, field, replace
from pathlib import Path

import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .checksums import verify_checksums
from .formats import FormatOption, OptionValueError, check_frame_rate, parse_frame_rate, register_format
from .haart import (
    GESTURES, HAART_SENSOR, RAW_SIDE, STUDY, challenge_window, find_placeholders, frame_window, parse_recording,
    read_bytes,
)
from .model import TouchDataset
from .windows import no_frame

log = logging.getLogger("touchbench.datasets")

__all__ = ["DEFAULT_PATTERN", "read_haart_raw"]

DEFAULT_PATTERN = (r"(?P<study>\d+)-(?P<participant>\d+)(?P<substrate>curve|foam|none)(?P<cover>fur|long|none|short)"
                   r"(?P<gesture>" + "|".join(GESTURES) + r")")
RECORDING_SECONDS = 10.0  # HAART's protocol: 10 s per gesture
#: a length of recording that at most this many have is listed with their files (provenance ``lengths``)
NAMED_LENGTHS = 10
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
        study = self.fields.get("study")
        return f"{study}-{s}" if study is not None and study != STUDY else s

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
    explicit: bool = False  # middle:SECONDS given, not HAART's default middle 8 s

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
            if 0 < s < float("inf"):
                return cls(kind, s, bool(secs))
        raise ValueError(f"expected middle, middle:SECONDS, challenge or whole, got {text!r}")

    @property
    def haart_protocol(self) -> bool:
        """Whether recordings are HAART's 10 s unless told otherwise (``middle``, ``challenge``)."""
        return self.kind == "challenge" or (self.kind == "middle" and not self.explicit)

    def describe(self, rate: float, recording_s: float | None, frames: set[int]) -> str:
        """The window in words; ``frames``: the number of frames of the recordings it was taken from."""
        of = f"the first {recording_s:g} s of each recording" if recording_s else "each recording"
        if self.kind == "whole":
            return f"whole: every frame of {of}"
        if self.kind == "challenge":
            return "the organisers' window (bug included): frame i = lines 8i+55..8i+62 of the row-trimmed stream"
        text = f"middle {self.seconds:g} s of {of}"
        if len(frames) == 1:
            first, n = self.frames(next(iter(frames)), rate)
            text += f": frames {first + 1}..{first + n} (1-based)"
        return text

    def frames(self, total: int, rate: float) -> tuple[int, int]:
        """The first frame (0-based) and number of frames of the middle window of ``total`` frames
        (``n > total`` when the recording is shorter than the window)."""
        n = round(self.seconds * rate)
        return max(total - n, 0) // 2, n


@dataclass
class _Trims:
    """What a conversion did to the recordings' lengths: (file, seconds, lines) of each one cut or used whole."""

    seconds: float | None
    cut: list[tuple[str, float, int]]
    short: list[tuple[str, float, int]]
    #: (file, lines of values) of every recording read, before any cut
    lines: list[tuple[str, int]] = field(default_factory=list)

    def lengths(self, rate: float) -> dict[str, str]:
        """How many recordings have each length, shortest first, naming the files of a length that
        at most :data:`NAMED_LENGTHS` have (``"10 s (5400 lines)": "2: a.csv, b.csv"``)."""
        by: dict[int, list[str]] = {}
        for f, n in self.lines:
            by.setdefault(n, []).append(f)
        return {f"{n / RAW_SIDE / rate:.4g} s ({n} lines)": f"{len(fs)}" + (f": {', '.join(fs)}" if len(fs) <= NAMED_LENGTHS else "")
                for n, fs in sorted(by.items())}

    def report(self, n: int, placeholders: list[dict]) -> str:
        """The counts in words (``""`` when every recording was used as it is)."""
        def median(items: list[tuple[str, float, int]]) -> str:
            return f"median length {statistics.median(s for _, s, _ in items):.3g} s"
        parts = []
        if self.cut:
            parts.append(f"{len(self.cut)} of {n} recordings cut to their first {self.seconds:g} s ({median(self.cut)})")
        if self.short:
            parts.append(f"{len(self.short)} of {n} recordings shorter than {self.seconds:g} s, used whole "
                         f"({median(self.short)})")
        if placeholders:
            files = ", ".join(p["file"] for p in placeholders[:5]) + (", ..." if len(placeholders) > 5 else "")
            parts.append(f"{len(placeholders)} dropped as byte-identical copies of another recording: {files}")
        return "; ".join(parts)


def _read_arrays(folder: Path, recs: list[RawRecording], win: Window, rate: float, rec_s: float | None,
                 strict: bool) -> tuple[dict, dict, _Trims]:
    """Every recording parsed and cut to its first ``rec_s`` seconds; ``strict``: one shorter is
    refused as truncated (HAART's protocol), else used whole."""
    lines_used = round(rec_s * rate) * RAW_SIDE if rec_s else None
    arrays, digests, trims = {}, {}, _Trims(rec_s, [], [])
    for r in recs:
        data = read_bytes(r.path)
        digests[r.key] = hashlib.sha256(data).hexdigest()
        arr = parse_recording(data, r.path, min_lines=lines_used if strict else RAW_SIDE)
        rel, length_s = str(r.path.relative_to(folder)), len(arr) / RAW_SIDE / rate
        trims.lines.append((rel, len(arr)))
        if lines_used is not None and len(arr) > lines_used:
            trims.cut.append((rel, length_s, len(arr)))
            arr = arr[:lines_used]
        elif lines_used is not None and len(arr) < lines_used:
            trims.short.append((rel, length_s, len(arr)))
        if win.kind == "whole" and len(arr) % RAW_SIDE:
            raise DataError(f"{len(arr)} lines is not a whole number of {RAW_SIDE}-line frames (the last frame "
                            "is cut short)", r.path, len(arr) - len(arr) % RAW_SIDE + 1)
        arrays[r.key] = arr
    return arrays, digests, trims


def _capture(arr, win: Window, rate: float, path: Path, leave_out: bool = False):
    """The window of one parsed recording; None when it is shorter than the window and
    ``leave_out`` (else refused)."""
    total = len(arr) // RAW_SIDE
    if win.kind == "whole":
        return frame_window(arr, 0, total)
    if win.kind == "challenge":
        return challenge_window(arr)
    first, n = win.frames(total, rate)
    if n > total and leave_out:
        return None
    if n > total:
        raise DataError(f"a {total / rate:g}-s recording ({total} frames) is shorter than the {win.seconds:g}-s "
                        f"window (--recording-window middle:{win.seconds:g} asks for {n} frames): choose a shorter "
                        "window, or --short-recordings leave-out", path)
    return frame_window(arr, first, n)


def _check_frames(win: Window, rec_s: float | None, rate: float) -> None:
    """Refuse a window or a recording cut of no frame at ``rate``, naming the option."""
    for option, seconds in (("recording_window", win.seconds), ("recording_seconds", rec_s)):
        problem = None if seconds is None else no_frame(seconds, rate)
        if problem:
            raise OptionValueError(f"{option}: {problem}")


def read_haart_raw(
    path: str | Path,
    *,
    pattern: str | None = None,
    recording_window: str | Window = "middle",
    recording_seconds: float | None = None,
    frame_rate: float | None = None,
    name: str | None = None,
    short_recordings: str = "refuse",
    checksums: str | Path | None = None,
) -> TouchDataset:
    """Read a folder of raw-format recordings (module docstring). The sensor is HAART's (at
    ``frame_rate``): a model of another sensor refuses the data, naming both. ``short_recordings``:
    ``leave-out`` leaves out a recording shorter than a ``middle:SECONDS`` window (counted in the
    warning, listed in the provenance's ``left_out``) instead of refusing it. ``checksums``: a
    SHA256SUMS file naming the recordings relative to ``path`` (:func:`verify_checksums`)."""
    folder = Path(path)
    rx = compile_pattern(pattern or DEFAULT_PATTERN)
    win = recording_window if isinstance(recording_window, Window) else Window.parse(recording_window)
    rate = HAART_SENSOR.frame_rate if frame_rate is None else check_frame_rate(frame_rate)
    rec_s = None if recording_seconds is None else parse_seconds(recording_seconds)
    leave_out = parse_short(short_recordings) == "leave-out"
    if rec_s is None and win.haart_protocol:
        rec_s = RECORDING_SECONDS
    _check_frames(win, rec_s, rate)
    if win.kind == "challenge" and (rate != HAART_SENSOR.frame_rate or rec_s != RECORDING_SECONDS):
        raise TouchbenchError("--recording-window challenge is the organisers' window of 10-s recordings at 54 Hz only")
    recs = find_raw_recordings(folder, rx)
    strict = win.kind == "challenge" or (recording_seconds is None and win.haart_protocol)
    arrays, digests, trims = _read_arrays(folder, recs, win, rate, rec_s, strict)
    checked = {} if checksums is None else verify_checksums(
        Path(checksums), [(str(r.path.relative_to(folder)).removesuffix(".gz"), r.path, digests[r.key]) for r in recs],
        folder)
    placeholders = find_placeholders(folder, recs, digests)
    dropped = {p["capture_id"] for p in placeholders}
    windows = [(r, _capture(arrays[r.key], win, rate, r.path, leave_out)) for r in recs if r.capture_id not in dropped]
    kept, captures = [r for r, c in windows if c is not None], [c for _, c in windows if c is not None]
    left_out = [f"{r.path.relative_to(folder)}: {len(arrays[r.key]) // RAW_SIDE / rate:.4g} s, shorter than the "
                f"{win.seconds:g}-s window" for r, c in windows if c is None]
    report = "; ".join(x for x in (trims.report(len(recs), placeholders), left_out and
                                   f"{len(left_out)} left out as shorter than the {win.seconds:g}-s window") if x)
    if report:
        more = (" (--recording-seconds SECONDS, --recording-window middle:SECONDS or whole use more of each recording)"
                if trims.cut and recording_seconds is None else "")  # a cut asked for needs no hint
        log.warning("%s: %s%s", folder, report, more)
    ds = TouchDataset(name or folder.name, captures, _meta(folder, kept), replace(HAART_SENSOR, frame_rate=rate))
    ds.provenance = {
        "pattern": rx.pattern,
        "window": win.describe(rate, rec_s, {len(arrays[r.key]) // RAW_SIDE for r in kept}),
        "crop": "inner 8 x 8 of the 10 x 10 grid (rows and columns 2..9), pressure = 1023 - raw",
        "recordings": f"{len(recs)} read" + (f": {report}" if report else ", each used as it is"),
        "lengths": trims.lengths(rate),
        "cut": [f"{f}: {n} lines, the first {round(rec_s * rate) * RAW_SIDE} used" for f, _, n in trims.cut] or "none",
        "left_out": left_out or "none",
        "placeholders": placeholders,
        **checked,
    }
    return ds


def _meta(folder: Path, kept: list[RawRecording]) -> pd.DataFrame:
    """The metadata of the recordings ``kept``: every group of the pattern a column."""
    columns = [k for k, _ in kept[0].groups] if kept else []
    return pd.DataFrame({
        "capture_id": [r.capture_id for r in kept],
        "subject": [r.subject for r in kept],
        **{k: [r.fields.get(k) for r in kept] for k in columns if k != "participant"},
        "participant": [r.participant for r in kept],
        "source": [str(r.path.relative_to(folder)).removesuffix(".gz") for r in kept],
    })


SHORT_CHOICES = ("refuse", "leave-out")


def parse_short(text: str) -> str:
    """What to do with a recording shorter than the window (``--short-recordings``)."""
    v = str(text).strip().lower()
    if v not in SHORT_CHOICES:
        raise OptionValueError(f"--short-recordings must be {' or '.join(SHORT_CHOICES)}, got {text!r}")
    return v


def parse_seconds(text: str | float) -> float:
    """A finite number of seconds above 0 (``--recording-seconds``)."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        v = -1.0
    if not 0 < v < float("inf"):
        raise OptionValueError(f"--recording-seconds must be a finite number of seconds above 0, got {text!r}")
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
        FormatOption("recording_window", "middle (HAART's: the middle 8 s of the first 10 s), middle:SECONDS (the "
                     "middle SECONDS of each recording, whatever its length), challenge or whole",
                     Window.parse, metavar="WINDOW"),
        FormatOption("recording_seconds", "Use the first SECONDS of each recording (a shorter one is used whole); "
                     "default: 10 s, HAART's, for middle and challenge, every frame for middle:SECONDS and whole",
                     parse_seconds, metavar="SECONDS"),
        FormatOption("frame_rate", "Frames per second (default 54, the HAART sensor's)", parse_frame_rate),
        FormatOption("short_recordings", "refuse (default) or leave-out: a recording shorter than a "
                     "middle:SECONDS window is refused, or left out and listed", parse_short, metavar="WHAT"),
    ),
)
