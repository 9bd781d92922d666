"""``touchbench stream``: continuous recognition over sliding windows.

Flagg (2012, section 4.5) asks for "continuous gesture
recognition that works with ongoing sequences of data, rather than
fixed-length windows", "buffering in 2-second periods", "a few buffers of
different length simultaneously", and "confidence estimates, so that the
model is not forced to classify everything it sees in terms of its known
gesture types". Here:

- frames arrive one at a time (:func:`replay` of a recorded file at its
  frame rate, or the model's when the file does not say it, or
  :func:`text_frames` from standard input, one frame per line of ``H*W``
  comma-separated decimal numbers, row-major; ``1_0`` is no number here);
- a malformed line of a live stream (standard input) is reported with its
  line number and skipped, and the stream goes on (a sensor's glitch
  should not end a session); the summary counts the skipped lines. A
  recorded file is read whole before its replay and refused at its first
  malformed line (nothing is replayed);
- the recogniser keeps twice its longest window of frames: a window whose
  frames would take more than :func:`buffer_limit` bytes (512 MiB, or a
  quarter of the available memory when that is less) is refused up front,
  naming ``--window`` and the longest window allowed;
- :class:`SlidingRecognizer` keeps the last frames; once the shortest
  window is full, and then every ``hop`` frames, it classifies the last
  ``L`` frames for every window length ``L`` already full, in one batch,
  and combines them (:func:`.windows.combine_windows`);
- the decision is the best class and its probability, or ``none`` ("none
  of the above") when that probability is under ``threshold``;
- a decision's latency is the time from the arrival of the frame that
  completed the hop (after it was read and parsed) to the decision being
  ready: features of every window + classifier + combination. It does not
  include writing the decision out. With a real-time replay, frames that
  reached the recogniser more than one frame period after their scheduled
  time are counted as ``late`` (the recogniser did not keep up).

Rules (:func:`choose_rule`): a model trained on a stream protocol holds
every rule the protocol declares, fitted on its training captures
(``stream_rules``: the gate's and onset's ``level: auto`` written in as
``level``), and the default one (``stream_rule``, with
``stream_rule_source``). Without ``--rule`` the default decides (or ``max``
with ``--threshold`` for a model that records none); ``--rule NAME`` or a
mapping takes the first stored rule with that name and the mapping's fields,
else the rule as given, refused when it still needs a fitted level. The
start-up note says which rule decides and where it came from.

A recorded dataset's recording (``--recording``, :func:`replay_recording`)
is its segments put back in order by the functions a stream evaluation uses
(:mod:`touchbench.streams.timeline`), so the same frames are replayed.

A model that adapts to each session from its unlabelled captures
(``touch-et-adapt``, :attr:`.model.TrainedModel.adapts_to_session`) is
refused: a stream's frames arrive one at a time, with no session to adapt
to beforehand.

Defaults (interpretations): the window lengths are the model's training
windows, or, for a model trained on whole captures, its median training
capture length; hop 0.5 s; threshold 0.5 (the best class is more likely than
all others together); ``combine="max"``.
"""

from __future__ import annotations

import gzip
import math
import re
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Callable, Iterable, Iterator

import numpy as np
import pyarrow.parquet as pq

from ..core.errors import DataError, TouchbenchError
from ..core.memory import memory_limit
from ..core.suggest import did_you_mean
from ..core.threads import single_thread
from ..datasets.formats import FORMATS
from ..datasets.model import TouchDataset
from ..datasets.table_cells import cell_columns
from ..datasets.table_long import agree_grid
from ..datasets.tables import numeric, read_table
from ..streams.recognizer import Decision, WindowRecognizer, decide_all
from ..streams.timeline import recorded_streams, rest_value, stream_frames
from ..streams.rules import RULES, DecisionRule, make_rule, needs_fitting
from .model import TrainedModel
from .predict import read_data

__all__ = [
    "Decision",
    "SlidingRecognizer",
    "StreamSummary",
    "buffer_limit",
    "choose_rule",
    "load_replay",
    "replay",
    "replay_dataset",
    "replay_recording",
    "run_stream",
    "text_frames",
]


#: the most bytes of frames a recogniser keeps, whatever the memory
MAX_BUFFER_BYTES = 512 * 2 ** 20
#: a decimal number as a frame line writes it (no ``_`` digit groups, no hexadecimal): float() accepts more
_NUMBER = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*|\s*[+-]?(nan|inf|infinity)\s*", re.IGNORECASE)


@dataclass
class StreamSummary:
    frames: int = 0
    decisions: int = 0
    none: int = 0
    late_frames: int = 0
    skipped_lines: int = 0  # malformed lines of a live stream, reported and skipped
    labels: dict[str, int] = field(default_factory=dict)
    latency_ms_p50: float = math.nan
    latency_ms_p99: float = math.nan
    latency_ms_max: float = math.nan

    none_label: str = "none"

    def to_text(self) -> str:
        lab = ", ".join(f"{k}: {v}" for k, v in sorted(self.labels.items(), key=lambda kv: -kv[1]))
        return (f"{self.frames} frames, {self.decisions} decisions ({self.none} none); {lab}\n"
                f"latency per decision: p50 {self.latency_ms_p50:.2f} ms, p99 {self.latency_ms_p99:.2f} ms, "
                f"max {self.latency_ms_max:.2f} ms" + (f"; {self.late_frames} frames late" if self.late_frames else "")
                + (f"; {self.skipped_lines} malformed lines skipped" if self.skipped_lines else ""))


class SlidingRecognizer(WindowRecognizer):
    """A model file's recogniser (module docstring): :class:`touchbench.streams.recognizer.WindowRecognizer`
    over the model's probabilities, with the model's windows by default."""

    def __init__(self, model: TrainedModel, windows_s: Iterable[float] | None = None, hop_s: float = 0.5,
                 threshold: float = 0.5, combine: str = "max", none_label: str = "none", fast: bool = True,
                 rule: DecisionRule | None = None, rule_origin: str = "--rule given"):
        if model.adapts_to_session:
            raise TouchbenchError(f"{model.method}: this model adapts to each session from that session's "
                                  "captures (touchbench predict does it on a file); a stream has no session "
                                  "to adapt to: train a method that does not adapt for stream")
        self.model = model
        if windows_s is None:
            windows_s = model.windows or [model.manifest["capture_frames"]["median"] / float(model.sensor.frame_rate)]
        self.rule_origin = rule_origin
        if rule is None:
            rule, self.rule_origin = choose_rule(model, None, threshold)
        super().__init__(lambda caps: model.predict_proba(caps, fast=fast), model.classes, model.sensor, windows_s,
                         dtype=model.manifest.get("capture_dtype", "<f8"), hop_s=hop_s, threshold=threshold,
                         combine=combine, none_label=none_label, rule=rule, buffer_check=_check_buffer)

    def notes(self) -> list[str]:
        out = [f"deciding with the rule {self.rules[0].describe()}: {self.rule_origin}"]
        trained = self.model.windows
        if trained is None:
            med = self.model.manifest["capture_frames"]["median"]
            if any(abs(L - med) > 0.5 for L in self.lengths):
                out.append(f"the model was trained on whole captures ({med:g} frames median); "
                           f"windows of {', '.join(map(str, self.lengths))} frames may behave differently")
        elif sorted(trained) != self.windows_s:
            out.append(f"the model was trained on windows of {', '.join(f'{w:g}' for w in trained)} s, "
                       f"streaming with {', '.join(f'{w:g}' for w in self.windows_s)} s")
        return out


def choose_rule(model: TrainedModel, spec: dict[str, Any] | str | None,
                threshold: float = 0.5) -> tuple[DecisionRule, str]:
    """The decision rule for ``--rule spec`` and where it came from (module docstring, "Rules").

    None: the model file's default rule (``stream_rule``, with its ``stream_rule_source``), or ``max``
    with ``threshold`` for a model that records none. A name or a mapping: the first of the model's
    stored fitted rules (``stream_rules``, then ``stream_rule``) with that name and every field the
    mapping gives, else the rule as given; a rule still needing a level fitted on training captures
    (the gate's and onset's ``level: auto``) is refused, naming ``--rule``."""
    default = model.manifest.get("stream_rule")
    if spec is None:
        if not default:
            return make_rule(None, threshold), "max with --threshold (the model file records no rule)"
        source = model.manifest.get("stream_rule_source", "recorded by touchbench train")
        return make_rule(default), f"the model file's default rule ({source})"
    given = {"name": spec} if isinstance(spec, str) else spec
    if not isinstance(given, dict):
        raise TouchbenchError(f"--rule: a decision rule is a name or a mapping such as {{name: majority, n: 5}}, "
                              f"got {spec!r}")
    stored = [*model.manifest.get("stream_rules", []), *([default] if default else [])]
    wanted = {k: v for k, v in given.items() if not (k == "level" and v == "auto")}  # auto: the fitted level
    match = next((r for r in stored if all(k in r and r[k] == v for k, v in wanted.items())), None)
    if match is not None:
        return make_rule(match), "the model file's fitted rule of that name (--rule)"
    name = given.get("name")
    try:
        rule, problem = make_rule(given, threshold), None
    except TouchbenchError as e:
        rule, problem = None, str(e)
    if rule is not None and not needs_fitting(rule):
        return rule, "--rule given on the command line"
    learns = isinstance(name, str) and name in RULES and RULES.get(name).fit is not DecisionRule.fit
    if rule is None and not learns:
        raise TouchbenchError(f"--rule: {problem}")
    same = [r for r in stored if r.get("name") == name]
    has = (f"its fitted {name} rules: {'; '.join(map(str, same))}" if same
           else f"the model file holds no fitted {name} rule")
    raise TouchbenchError(
        f"--rule {name}: needs a level fitted on training captures and {has}"
        + (f" ({problem})" if problem else "")
        + "; train the model on a stream protocol that declares this rule (touchbench train), or give the "
          "level in --rule, e.g. '{name: gate, idle: IDLE, level: 0.1}'")


def buffer_limit() -> int:
    """The most bytes of frames a recogniser may keep: :data:`MAX_BUFFER_BYTES`, or a quarter of the
    available memory when that is less (:func:`touchbench.core.memory.memory_limit`)."""
    return memory_limit(MAX_BUFFER_BYTES)


def _check_buffer(n_frames: int, grid: tuple[int, int], dtype: np.dtype, frame_rate: float) -> None:
    """Refuse windows whose frames (``n_frames``: twice the longest window) would not fit :func:`buffer_limit`."""
    frame_bytes = int(np.prod(grid)) * np.dtype(dtype).itemsize
    limit = buffer_limit()
    if n_frames * frame_bytes > limit:
        longest = limit // (2 * frame_bytes) / frame_rate
        raise TouchbenchError(
            f"--window {n_frames / 2 / frame_rate:g} s is too long: the recogniser keeps twice the longest window, "
            f"{n_frames} frames of {grid[0]} x {grid[1]} values ({n_frames * frame_bytes / 2 ** 20:.0f} MiB), over "
            f"its limit of {limit / 2 ** 20:.0f} MiB (512 MiB or a quarter of the available memory); "
            f"the longest window allowed is {longest:.0f} s")


# ----------------------------------------------------------------- sources
def _check_values(values: np.ndarray, model: TrainedModel, where: str, line: int | None) -> None:
    lo, hi = model.sensor.value_range
    if not np.isfinite(values).all():
        raise DataError("missing, NaN or infinite value in a frame", where, line)
    if values.min() < lo or values.max() > hi:
        bad = values[(values < lo) | (values > hi)][0]
        raise DataError(f"value {bad:g} outside the model's sensor range [{lo:g}, {hi:g}]", where, line)
    if np.dtype(model.manifest.get("capture_dtype", "<f8")).kind in "iu" and (values != np.round(values)).any():
        bad = values[values != np.round(values)][0]
        raise DataError(f"value {bad!r} is not a whole number (the model was trained on integer frames)", where, line)


def text_frames(fh: IO[str], model: TrainedModel, where: str = "<stdin>",
                on_error: Callable[[DataError], None] | None = None) -> Iterator[tuple[np.ndarray, float]]:
    """Frames from lines of ``H*W`` comma-separated decimal numbers; blank lines are skipped.

    Yields ``(frame, arrival time)`` as each line arrives (a live pipe is
    read line by line). A malformed line is a :class:`DataError` with its
    line number: raised, or, with ``on_error``, handed to it and the line
    skipped (the stream goes on).
    """
    for lineno, line in enumerate(_lines(fh, where), start=1):
        arrived = time.perf_counter()
        if not line.strip():
            continue
        try:
            frame = _parse_frame(line, model, where, lineno)
        except DataError as e:
            if on_error is None:
                raise
            on_error(e)
            continue
        yield frame, arrived


def _parse_frame(line: str, model: TrainedModel, where: str, lineno: int) -> np.ndarray:
    """One frame of the model's grid and dtype from one text line, or the :class:`DataError` it gets."""
    h, w = model.sensor.grid
    parts = line.strip().split(",")
    if len(parts) != h * w:
        raise DataError(f"a frame has {len(parts)} values, the model's {h} x {w} sensor needs {h * w}", where, lineno)
    bad = next((v for v in parts if not _is_number(v)), None)
    if bad is not None:
        raise DataError(f"not a number: {bad.strip()!r}", where, lineno)
    values = np.array([float(v) for v in parts], dtype=np.float64)
    _check_values(values, model, where, lineno)
    return values.reshape(h, w).astype(np.dtype(model.manifest.get("capture_dtype", "<f8")))


def _lines(fh: IO[str], where: str) -> Iterator[str]:
    """The lines of ``fh`` as they arrive; a file that cannot be read to its end (a truncated
    ``.gz``, bytes that are not text) stops with the line it reached."""
    n = 0
    while True:
        try:
            line = fh.readline()
        except (EOFError, OSError, UnicodeDecodeError, zlib.error) as e:
            what = ("the compressed file ends before its end marker (truncated?)" if isinstance(e, EOFError)
                    else f"cannot read on ({type(e).__name__}: {e})")
            raise DataError(what, where, n + 1) from None
        if not line:
            return
        n += 1
        yield line


def _is_number(v: str) -> bool:
    """A decimal number (``1``, ``-2.5``, ``3e2``; ``nan`` and ``inf`` too, refused later by value);
    not ``1_0`` or ``0x1f``, which Python's ``float`` and ``int`` would read."""
    return _NUMBER.fullmatch(v) is not None


def load_replay(path: str | Path, model: TrainedModel, capture: str | None = None,
                fmt: str = "auto", recording: str | None = None, **options) -> tuple[np.ndarray, float, str]:
    """Frames of a recorded file: ``(frames (T, H, W), frame rate, description)``.

    ``fmt`` is a registered file format (:mod:`touchbench.datasets.formats`),
    whose dataset is replayed like a touchbench dataset below (what the file
    does not say, such as the ``table`` format's grid, is the model's sensor's;
    a file that does not say its frame rate, by ``--frame-rate`` or a time
    column, is replayed at the model's, as ``auto`` replays a table), or
    ``auto``:

    - a touchbench dataset (Parquet): the capture ``capture`` (by
      ``capture_id``), or every capture one after another; its sensor must
      match the model's and its frame rate is the replay rate;
    - any other CSV or Parquet table: one frame per row, the ``H*W`` cell
      columns (all columns when there are exactly ``H*W`` of them, else the
      numbered cell columns of the long format), rows of ``capture`` only
      when a ``capture_id`` column exists; a CSV whose first line is numbers
      has no header. Replayed at the model's frame rate.

    ``recording``: the recording of that name of a dataset whose captures are
    segments of recordings (a registered dataset name, a touchbench Parquet,
    or a file read with ``fmt``, such as the ``table`` format's
    ``frame_labels``): :func:`replay_recording`.
    """
    if recording is not None:
        return _replay_recording_of(str(path), model, capture, fmt, recording, options)
    path = Path(path)
    if fmt != "auto":
        return _replay_format(path, model, capture, fmt, options)
    if not path.is_file():
        raise DataError("no such file", path)
    if path.suffix == ".parquet":
        try:
            meta = pq.read_schema(path).metadata or {}
        except Exception as e:
            raise DataError(f"not a readable Parquet file ({e})", path) from None
        if b"touchbench" in meta:
            return replay_dataset(TouchDataset.from_parquet(path), model, capture, path)
    h, w = model.sensor.grid
    n = h * w
    dtype = np.dtype(model.manifest.get("capture_dtype", "<f8"))
    if path.suffix != ".parquet" and _first_line_is_numbers(path):
        with _open_text(path) as fh:
            got = [f for f, _ in text_frames(fh, model, str(path))]
        if not got:
            raise DataError("no frames", path)
        return np.stack(got), model.sensor.frame_rate, f"{path.name}: {len(got)} frames"
    df = read_table(path)
    if capture is not None:
        if "capture_id" not in df.columns:
            raise DataError("--capture needs a capture_id column", path, 1)
        df = df[df["capture_id"].astype(str) == capture]
        if df.empty:
            raise DataError(f"no rows of capture {capture!r}", path)
    if df.shape[1] == n:
        cols = list(df.columns)
    else:
        cols, laid = cell_columns(df, model.sensor.grid, path, grid_from=f"the model's sensor {model.sensor.name!r}")
        agree_grid(model.sensor.grid, laid, path, f"the model's sensor {model.sensor.name!r}")  # a transposed table
    lo, hi = model.sensor.value_range
    values = numeric(df, cols, path, lo=lo, hi=hi, integer=dtype.kind in "iu")
    return values.reshape(len(df), h, w).astype(dtype), model.sensor.frame_rate, f"{path.name}: {len(df)} frames"


def _replay_format(path: Path, model: TrainedModel, capture: str | None, fmt: str,
                   options: dict[str, Any]) -> tuple[np.ndarray, float, str]:
    """:func:`load_replay` of a file in the registered format ``fmt``."""
    ds, note = _read_format(path, model, fmt, options)
    frames, rate, what = replay_dataset(ds, model, capture, path)
    return frames, rate, what + note


def _replay_recording_of(source: str, model: TrainedModel, capture: str | None, fmt: str, recording: str,
                         options: dict[str, Any]) -> tuple[np.ndarray, float, str]:
    """:func:`load_replay` of one recording of ``source`` (a dataset name or file)."""
    if capture is not None:
        raise TouchbenchError("--capture and --recording: give one")
    if fmt != "auto":
        ds, note = _read_format(Path(source), model, fmt, options)
    else:
        ds, note = read_data(source, "auto", model, **options), ""
    frames, rate, what = replay_recording(ds, model, recording, source)
    return frames, rate, what + note


def _read_format(path: Path, model: TrainedModel, fmt: str, options: dict[str, Any]) -> tuple[TouchDataset, str]:
    """The dataset of a file in the registered format ``fmt``, and a note when it was read at the
    model's frame rate (the file does not say its own)."""
    form = FORMATS.get(fmt)
    if not form.replay:
        raise TouchbenchError(f"the {fmt} format cannot be replayed frame by frame")
    takes_rate = any(o.name == "frame_rate" for o in form.options)
    try:
        return form.read(path, like=model.sensor, **options), ""
    except TouchbenchError as e:
        if not takes_rate or options.get("frame_rate") is not None or "give --frame-rate" not in str(e):
            raise
        rate = model.sensor.frame_rate
        ds = form.read(path, like=model.sensor, **{**options, "frame_rate": rate})
        return ds, f" (the file does not say its frame rate: the model's, {rate:g} Hz)"


def replay_recording(ds: TouchDataset, model: TrainedModel, name: str, where: str) -> tuple[np.ndarray, float, str]:
    """The frames of recording ``name`` of ``ds`` (captures that are segments of recordings: metadata
    ``recording`` and ``start_frame``), its segments put back in order as a stream evaluation puts
    them (:func:`touchbench.streams.timeline.recorded_streams`, ``stream_frames``)."""
    model.check_sensor(ds.sensor, where)
    meta = ds.meta
    if "recording" not in meta.columns or "start_frame" not in meta.columns:
        raise DataError("--recording needs captures that are segments of recordings (metadata recording and "
                        "start_frame: a table read with frame labels); this dataset has none", where)
    recs = meta["recording"].astype(str).to_numpy()
    names = sorted(set(recs))
    if name not in names:
        shown = ", ".join(names[:10]) + (f", ... ({len(names)} in all)" if len(names) > 10 else "")
        raise DataError(f"--recording: no recording {name!r}{did_you_mean(name, names)} (recordings: {shown})", where)
    (stream,) = recorded_streams(meta, np.asarray(ds.n_frames, dtype=np.int64), np.flatnonzero(recs == name))
    target = model.manifest.get("target", "gesture")
    labels = meta[target].astype(str).to_numpy() if target in meta.columns else np.full(len(ds), "", dtype=object)
    frames, _ = stream_frames(ds.captures, labels, stream, "", rest_value(ds.sensor))
    return frames, ds.sensor.frame_rate, f"{Path(where).name}: recording {name} ({len(stream.segments)} segments)"


def replay_dataset(ds: TouchDataset, model: TrainedModel, capture: str | None, path: Path) -> tuple[np.ndarray, float, str]:
    """Frames of dataset ``ds`` read from ``path``: the capture ``capture``
    (by ``capture_id``), or every capture one after another, at the dataset's
    frame rate; its sensor must match the model's."""
    model.check_sensor(ds.sensor, str(path))
    if capture is not None:
        ids = ds.meta["capture_id"].astype(str).tolist()
        if capture not in ids:
            raise DataError(f"no capture {capture!r} (e.g. {', '.join(ids[:5])})", path)
        frames = ds.captures[ids.index(capture)]
        return frames, ds.sensor.frame_rate, f"{path.name}: capture {capture}"
    return np.concatenate(ds.captures), ds.sensor.frame_rate, f"{path.name}: {len(ds)} captures"


def _open_text(path: Path) -> IO[str]:
    if path.suffix == ".gz":
        return gzip.open(path, "rt", encoding="utf-8")
    return open(path, encoding="utf-8")


def _first_line_is_numbers(path: Path) -> bool:
    try:
        with _open_text(path) as fh:
            for line in fh:
                if line.strip():
                    return all(_is_number(v) for v in line.strip().split(","))
    except (EOFError, OSError, UnicodeDecodeError, zlib.error):
        return False
    return False


def replay(frames: np.ndarray, frame_rate: float, speed: float = 1.0, realtime: bool = True,
           late: list[int] | None = None) -> Iterator[tuple[np.ndarray, float]]:
    """Yield ``(frame, arrival time)`` at ``frame_rate * speed`` frames per second.

    ``realtime=False`` yields as fast as the consumer takes them. Frames
    handed over more than one period after their scheduled time are counted
    in ``late[0]``.
    """
    if speed <= 0:
        raise TouchbenchError(f"--speed must be positive, got {speed}")
    period = 1.0 / (frame_rate * speed)
    t0 = time.perf_counter()
    for i, f in enumerate(frames):
        if realtime:
            due = t0 + i * period
            now = time.perf_counter()
            if now < due:
                time.sleep(due - now)
            elif late is not None and now - due > period:
                late[0] += 1
        yield f, time.perf_counter()


def run_stream(recognizer: SlidingRecognizer, frames: Iterable[tuple[np.ndarray, float]],
               emit: Callable[[Decision], None] | None = None, late: list[int] | None = None) -> StreamSummary:
    """Feed ``frames`` to ``recognizer``, ``emit`` each decision, and summarise latencies."""
    lat: list[float] = []
    summary = StreamSummary(none_label=recognizer.none_label)
    with single_thread():
        recognizer.warm_up()

        def counted():
            for item in frames:
                summary.frames += 1
                yield item

        for d in decide_all(recognizer, counted()):
            lat.append(d.latency_ms)
            summary.decisions += 1
            summary.labels[d.label] = summary.labels.get(d.label, 0) + 1
            if d.label == recognizer.none_label:
                summary.none += 1
            if emit is not None:
                emit(d)
    if lat:
        a = np.asarray(lat)
        summary.latency_ms_p50 = float(np.percentile(a, 50))
        summary.latency_ms_p99 = float(np.percentile(a, 99))
        summary.latency_ms_max = float(a.max())
    summary.late_frames = int(late[0]) if late else 0
    return summary

