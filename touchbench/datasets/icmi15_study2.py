"""The ``icmi15-study2`` dataset: the HAART organisers' second study, read by the ``haart-raw`` reader.

Recordings made on HAART's sensor (10 x 10 raw grid, the inner 8 x 8 used,
54 frames per second) about nine months after HAART, by other people, with
two conditions HAART did not have: the sensor under a ``cover`` or not
(``none``), and its carrier moved while touched (``dynamic``) or not
(``static``); the seven HAART gestures. The folder is ``icmi15-study2/`` of
the shared data (``$TOUCHBENCH_DATA_DIR``, as for ``haart``), its
recordings in ``raw/``, named ``150505-<participant><cover><motion><gesture>``
(``.csv``, plain or gzipped); ``SHA256SUMS`` beside ``raw/`` is checked.

**Participants.** Whatever participants the folder holds are read: nothing
here names or counts them (``data info`` lists those found). The copy
touchbench is developed on holds 224 recordings of the eight participants
2, 4, 6, 8, 10, 12, 14 and 16 (28 each), as the data folder's README says;
the whole study has 16. A subject
is ``150505-s<NN>`` (the study's prefix: never one of HAART's ``sNN``, who
are other people). Metadata columns: ``cover`` (cover / none), ``motion``
(dynamic / static), ``gesture``, ``study``, ``participant``, ``source``.

**Window** (the ``window`` option; no gesture window was ever defined for
this study, so the capture is a stated choice). Most recordings last 20 s,
some 10, 30 or 40 s (``data info`` lists the lengths):

``haart`` (default)
    HAART's: the middle 8 s of the first 10 s of each recording, frames
    55..486 (1-based), 432 frames: every recording, the 10-s ones included,
    gives one capture of the length methods trained on HAART take.
``first:SECONDS``
    the first SECONDS of each recording.
``middle:SECONDS``
    the middle SECONDS of each whole recording.

A recording shorter than the window is left out and reported: counted in a
warning when the dataset is built, and listed under ``left_out`` in its
provenance (``touchbench data info icmi15-study2``). Never silently.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

from ..core.errors import DataError
from ..core.paths import raw_folder
from .cache import cached_dataset
from .haart import GESTURES, HAART_SENSOR
from .haart_raw import RawRecording, compile_pattern, find_raw_recordings, read_haart_raw
from .model import TouchDataset
from .registry import DATASETS

__all__ = ["NAME", "PATTERN", "WINDOWS", "load_icmi15_study2", "parse_window", "window_option_problem"]

NAME = "icmi15-study2"
READER_VERSION = "icmi15-study2-3"  # 2: the checksums' provenance; 3: no fixed note on the README
PATTERN = (r"(?P<study>150505)-(?P<participant>\d+)(?P<cover>cover|none)(?P<motion>dynamic|static)"
           r"(?P<gesture>" + "|".join(GESTURES) + r")")
#: the window option's forms (``parse_window``)
WINDOWS = ("haart", "first:SECONDS", "middle:SECONDS")


def parse_window(text: str) -> dict[str, object]:
    """The ``haart-raw`` reader's options for a window (module docstring): ``recording_window`` and
    ``recording_seconds``; an unknown form is refused naming the forms."""
    kind, _, secs = str(text).strip().lower().partition(":")
    if kind == "haart" and not secs:
        return {"recording_window": "middle:8", "recording_seconds": 10.0}
    try:
        seconds = float(secs)
    except ValueError:
        seconds = -1.0
    if kind in ("first", "middle") and 0 < seconds < float("inf"):
        rate = HAART_SENSOR.frame_rate
        if round(seconds * rate) < 1:
            raise DataError(f"window {text!r}: {seconds:g} s is {round(seconds * rate)} frames at {rate:g} Hz: a "
                            f"window is at least one frame ({1 / rate:.3g} s)")
        return {"recording_window": f"middle:{seconds:g}", "recording_seconds": seconds if kind == "first" else None}
    raise DataError(f"window {text!r}: expected {', '.join(WINDOWS)} (SECONDS a number above 0)")


def window_option_problem(options: dict[str, object]) -> tuple[str, str] | None:
    """The dataset's options as a protocol gives them: ``(option, why)`` for a window that cannot be
    read (:func:`parse_window`: an unknown form, or a window of no frame), else None."""
    if "window" not in options:
        return None
    try:
        parse_window(str(options["window"]))
    except DataError as e:
        return "window", str(e)
    return None




def _recordings(raw: Path) -> list[RawRecording]:
    return find_raw_recordings(raw, compile_pattern(PATTERN))


def _source_files(raw: Path) -> list[Path]:
    files = [r.path for r in _recordings(raw)]
    return files + ([raw.parent / "SHA256SUMS"] if (raw.parent / "SHA256SUMS").is_file() else [])


def conditions_summary(recs: list[RawRecording]) -> dict[str, object]:
    """Participants and recordings per condition of the recordings ``recs`` (what ``data info`` shows)."""
    per = Counter(r.participant for r in recs)
    by_condition = Counter(f"{r.fields['cover']} / {r.fields['motion']}" for r in recs)
    return {
        "participants": f"{len(per)}: " + ", ".join(f"{p} ({per[p]} recordings)" for p in sorted(per, key=int)),
        "conditions": {k: by_condition[k] for k in sorted(by_condition)},
    }


def build_icmi15_study2(raw: Path, window: str = "haart") -> TouchDataset:
    """The study read from ``raw`` with ``window`` (module docstring)."""
    options = parse_window(window)
    ds = read_haart_raw(raw, pattern=PATTERN, short_recordings="leave-out", name=NAME,
                        checksums=raw.parent / "SHA256SUMS", **options)
    prov = {"window option": f"{window} (of {', '.join(WINDOWS)})", **conditions_summary(_recordings(raw)),
            **ds.provenance}
    ds.provenance = prov
    return ds


@DATASETS.register(NAME, description="the HAART organisers' second study: cover x motion, other people; HAART's "
                                     "window by default", real=True, check_options=window_option_problem)
def load_icmi15_study2(cache_dir=None, data_dir=None, refresh: bool = False, window: str = "haart") -> TouchDataset:
    """The study (module docstring); ``window``: ``haart``, ``first:SECONDS`` or ``middle:SECONDS``."""
    parse_window(window)  # refused before anything is read
    raw = raw_folder(NAME, data_dir)
    key = window.strip().lower()
    return cached_dataset(f"{NAME}-{key.replace(':', '-')}" if key != "haart" else NAME, READER_VERSION,
                          _source_files(raw), lambda: build_icmi15_study2(raw, key), cache_dir, refresh)
