"""The ``table`` format: a user's own sensor as a table, one file or a folder of files.

Two layouts, told apart by the columns (``layout``: ``auto``, ``wide`` or
``long``):

``wide`` (one row per frame)
    capture, subject and gesture columns, optionally a frame counter and a
    time column, other metadata columns, and one column per cell, H x W of
    them. Cell columns are named by a pattern (``cells``): ``pixel{i}`` or
    ``cell{i}`` (one index, row-major, counting from 0 or 1 as the
    smallest index says), or ``r{row}c{col}`` (row and column indices,
    each counting from 0 or 1; the grid is then read from the names). By
    default the one group of columns named by a common prefix and a
    number (``cell1``.., ``ch1``.., ``pixel0``..) or by a prefix, a row
    number, a separator and a column number (``r0c0``.., ``cell_1_1``..:
    the grid is read from the names) whose size is the grid's cell count
    is taken.
``long`` (one row per cell, a true long table)
    the same capture, subject, gesture, frame and time columns, a value
    column (``value_column``, default ``value``) and the cell's position:
    ``row`` and ``col`` columns (the grid is their number of distinct
    values, each counting from 0 or 1), or one ``cell`` index column
    (row-major; the grid must then be given). Every cell of every frame
    must be there exactly once. ``auto`` takes ``long`` when the table has
    a value column and no numbered cell columns.

Rows may come in any order: a capture is every row with its capture key
(``capture_columns``: one column, default ``capture_id``, or several, such
as ``participantID,gesture,repetition``, joined with ``-`` into the capture
id), its frames ordered by the frame counter, or by time when there is
none. The frame counter must then count up by one from 0 or 1 (a gap or a
frame given twice is refused, naming the line); times must increase
strictly. Metadata columns must be constant within a capture.

Continuous recordings labelled frame by frame (``frame_labels``: the column
holding each frame's label, read as the gesture): the capture key then
names a recording, and each run of one label in it, in frame order, becomes
a capture of its own (id ``<recording>#<k>``, ``k`` from 1) with the
metadata columns ``recording`` and ``start_frame`` (its first frame within
the recording, from 0), so a stream evaluation can put the recording back
together (:mod:`touchbench.streams.timeline`) and any other scheme sees its
segments as captures.

A folder is every ``.csv``, ``.csv.gz`` and ``.parquet`` file below it, in
sorted order, each read as above with its own line numbers; the file each
capture came from is kept in the metadata column ``source``, and a capture
key found in two files is refused.

What the file cannot say, the user gives or touchbench works out, saying so:

- the grid (``grid``, ``HxW``): needed unless the cell names or the row and
  column indices give it; a grid given whose cell count is not the table's
  is refused with both counts, and one that is the transpose of the layout
  the names or indices show is refused as transposed (one index per cell
  cannot show a layout);
- the frame rate (``frame_rate``): given, or estimated from the time
  column as 1 / the median step between consecutive frames over all
  captures (robust to dropped frames), with a warning that shows the
  estimate and the steps it came from. Frames are kept as recorded: the
  time column's values (in ms) go into the metadata column ``time_ms``.
  A numeric time column's unit is its name's suffix (``_ms``, ``_s``,
  ``_us``) or ``time_unit``; a text column is read as date-times;
- the value range (``value_range``, ``LO..HI``): given (a value outside it
  is refused at its line), or inferred with a warning that shows it: for
  whole numbers from 0, ``0..2^k - 1`` for the smallest k in 1, 8, 10, 12,
  14, 16, 24, 32 that holds the largest value (the ADC ranges of common
  converters: 12-bit data is 0..4095); for values within 0..1, ``0..1``
  (normalised data); otherwise the smallest and largest values seen.

Whole-number values are stored in the smallest unsigned integer type that
holds the range (uint8, uint16, uint32), others as float64.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .formats import (
    FormatOption, check_frame_rate, check_range_used, check_value_range, parse_frame_rate, parse_grid, parse_value_range, register_format,
)
from .model import TIME_COLUMN, SensorSpec, TouchDataset, time_step_summary
from .table_cells import cell_columns, numbered_groups, pattern_regex
from .table_long import agree_grid, capture_key, count_mismatch, long_to_frames
from .tables import find_column, numeric, read_table

log = logging.getLogger("touchbench.datasets")

__all__ = ["TableLayout", "read_table_dataset", "parse_value_range"]

TIME_NAMES = ("time_ms", "timestamp_ms", "time", "timestamp", "time_s", "t")
FRAME_NAMES = ("frame", "frame_id", "frameid", "frame_index", "sequence")
TIME_UNITS = {"s": 1000.0, "ms": 1.0, "us": 1e-3}
ADC_BITS = (1, 8, 10, 12, 14, 16, 24, 32)
SUFFIXES = (".csv", ".csv.gz", ".parquet")


@dataclass(frozen=True)
class TableLayout:
    """The columns of a table (the names the user gives; ``None``: found by the rules of the module)."""

    capture: tuple[str, ...] = ("capture_id",)
    subject: str = "subject"
    gesture: str = "gesture"
    frame: str | None = None
    time: str | None = None
    time_unit: str | None = None
    cells: str | None = None
    value: str | None = None
    layout: str = "auto"
    frame_labels: bool = False  # the gesture column labels each frame (module docstring)

    def __post_init__(self) -> None:
        if self.layout not in ("auto", "wide", "long"):
            raise TouchbenchError(f"layout must be auto, wide or long, got {self.layout!r}")
        if self.time_unit is not None and self.time_unit not in TIME_UNITS:
            raise TouchbenchError(f"time unit must be one of {', '.join(TIME_UNITS)}, got {self.time_unit!r}")
        if self.cells is not None and "{" in self.cells:
            pattern_regex(self.cells)  # a bad pattern is refused before any file is read


# ---------------------------------------------------------------- one file
@dataclass
class _Frames:
    """A file's frames, one row each, in file order: what both layouts reduce to."""

    key: np.ndarray  # (n,) capture key, str
    order: np.ndarray  # (n,) frame counter or time, float64
    values: np.ndarray  # (n, H*W) float64
    lines: np.ndarray  # (n,) file line of the row (of the frame's first row in a long table)
    meta: pd.DataFrame  # (n, k) metadata columns
    time_ms: np.ndarray | None  # (n,) ms, or None without a time column


def _time_ms(df: pd.DataFrame, col: str, unit: str | None, path: Path, lines: np.ndarray) -> np.ndarray:
    """The time column in ms (row ``i`` is file line ``lines[i]``): numbers in a unit, or date-times."""
    s = df[col]
    if not pd.api.types.is_numeric_dtype(s):
        as_numbers = pd.to_numeric(s, errors="coerce")
        if as_numbers.notna().any():  # numbers with a cell that is not one: that cell is at fault
            i = int(np.flatnonzero(as_numbers.isna().to_numpy())[0])
            raise DataError(f"column {col!r}: not a number ({s.iloc[i]!r}) among numbers", path, int(lines[i]))
        parsed = pd.to_datetime(s, errors="coerce", utc=True, format="mixed")
        if parsed.isna().any():
            i = int(np.flatnonzero(parsed.isna().to_numpy())[0])
            raise DataError(f"column {col!r}: neither a number nor a date-time ({s.iloc[i]!r})", path, int(lines[i]))
        return (parsed - parsed.min()).dt.total_seconds().to_numpy() * 1000.0
    if unit is None:
        m = re.search(r"_(ms|s|us)$", col.lower())
        if m is None:
            raise DataError(f"the time column {col!r} does not say its unit: give --time-unit "
                            f"{' or '.join(TIME_UNITS)} (its values run {s.min():g}..{s.max():g})", path, 1)
        unit = m.group(1)
    return numeric(df, [col], path, lines=lines)[:, 0] * TIME_UNITS[unit]


def _refuse_empty_labels(df: pd.DataFrame, columns: dict[str, str], path: Path) -> None:
    """A row with an empty capture, subject or gesture (``columns``: column -> what it names) is refused
    at its line: a capture of nobody or of no gesture cannot be evaluated."""
    for col, what in columns.items():
        empty = df[col].isna().to_numpy() | (df[col].astype(str).str.strip() == "").to_numpy()
        if empty.any():
            raise DataError(f"empty {what} (column {col!r})", path, int(np.flatnonzero(empty)[0]) + 2)


def _optional_column(df: pd.DataFrame, given: str | None, names: Sequence[str], path: Path, what: str) -> str | None:
    if given is not None:
        return find_column(df, (given,), path, what)
    lower = {c.lower(): c for c in df.columns}
    return next((lower[n] for n in names if n in lower), None)


def _read_file(path: Path, lay: TableLayout, grid: tuple[int, int] | None, value_range, allow_empty: bool,
               grid_from: str = "--grid"):
    """One file's frames and the grid its columns give (or ``grid``, from ``grid_from``)."""
    df = read_table(path, allow_empty=allow_empty, text_columns=(*lay.capture, lay.subject, lay.gesture))
    cap = [find_column(df, (c,), path, "capture") for c in lay.capture]
    subj = find_column(df, (lay.subject,), path, "subject")
    gest = find_column(df, (lay.gesture,), path, "gesture")
    _refuse_empty_labels(df, {**{c: "capture" for c in cap}, subj: "subject", gest: "gesture"}, path)
    frame = _optional_column(df, lay.frame, FRAME_NAMES, path, "frame")
    time = _optional_column(df, lay.time, TIME_NAMES, path, "time")
    value = _optional_column(df, lay.value, ("value",), path, "value")
    layout = lay.layout
    if layout == "auto":
        numbered = any(len(g) > 1 for g in numbered_groups(df).values())
        layout = "long" if value is not None and lay.cells is None and not numbered else "wide"
    if layout == "long" and value is None:
        raise DataError("a long table needs a value column (--value-column; found none named 'value')", path, 1)
    lo, hi = value_range if value_range is not None else (None, None)
    taken = {*cap, frame, time}
    if layout == "wide":
        cells, named_grid = cell_columns(df, grid, path, lay.cells, grid_from)
        grid = agree_grid(grid, named_grid, path, grid_from)
        if grid is None:
            raise DataError(f"{len(cells)} cell columns: give the grid (--grid HxW), their names do not say it", path, 1)
        if len(cells) != grid[0] * grid[1]:
            raise DataError(count_mismatch(grid, len(cells), f"cell columns ({cells[0]}..{cells[-1]})", grid_from),
                            path, 1)
        values = numeric(df, cells, path, lo=lo, hi=hi)
        lines = np.arange(len(df)) + 2
        taken |= set(cells)
    else:
        values, lines, df, grid = long_to_frames(df, cap, frame, time, value, lay.cells, grid, path, lo, hi,
                                                  grid_from)
        taken |= {value, *(lay.cells.split(",") if lay.cells else ()), "row", "col", "cell"}
    meta_cols = [c for c in df.columns if c not in taken or c in (subj, gest)]
    if frame is not None:
        order = numeric(df, [frame], path, integer=True, lines=lines)[:, 0]
    elif time is not None:
        order = None
    else:
        raise DataError("no frame counter or time column to order the frames by (name one with --frame-column "
                        "or --time-column)", path, 1)
    t_ms = _time_ms(df, time, lay.time_unit, path, lines) if time is not None else None
    fr = _Frames(capture_key(df, cap), order if order is not None else t_ms, values, lines,
                 df[meta_cols].rename(columns={subj: "subject", gest: "gesture"}).reset_index(drop=True), t_ms)
    return fr, grid, frame, time


# ---------------------------------------------------------------- captures
def _captures(fr: _Frames, path: Path, frame_col: str | None, time_col: str | None, per_frame: tuple[str, ...] = ()):
    """Group a file's frames into captures (rows in any order): ``[(key, rows in frame order)]``, the
    captures in the order the file first gives them."""
    codes, uniq = pd.factorize(fr.key)
    uniq = [str(u) for u in uniq]
    order = np.lexsort((fr.order, codes))
    sc = codes[order]
    starts = np.flatnonzero(np.r_[True, sc[1:] != sc[:-1]])
    out = []
    for a, b in zip(starts, np.r_[starts[1:], len(order)]):
        rows = order[a:b]
        o = fr.order[rows]
        if frame_col is not None:
            if o[0] not in (0, 1):
                raise DataError(f"capture {uniq[sc[a]]!r} starts at {frame_col} {o[0]:g}; frames count from 0 or 1",
                                path, int(fr.lines[rows[0]]))
            gap = np.flatnonzero(np.diff(o) != 1)
            if gap.size:
                j = rows[gap[0] + 1]
                what = "given twice" if o[gap[0] + 1] == o[gap[0]] else f"follows {o[gap[0]]:g} (a frame is missing)"
                raise DataError(f"capture {uniq[sc[a]]!r}: {frame_col} {o[gap[0] + 1]:g} {what}", path, int(fr.lines[j]))
        if fr.time_ms is not None:
            t = fr.time_ms[rows]
            same = np.flatnonzero(np.diff(t) <= 0)
            if same.size:
                raise DataError(f"capture {uniq[sc[a]]!r}: {time_col} does not increase (two frames at the same "
                                "time, or times out of order against the frame counter)", path,
                                int(fr.lines[rows[same[0] + 1]]))
        meta = fr.meta.iloc[rows]
        varying = [c for c in meta.columns if c not in per_frame and meta[c].nunique(dropna=False) > 1]
        if varying:
            col = meta[varying[0]].to_numpy()
            j = rows[int(np.flatnonzero(col != col[0])[0])]
            raise DataError(f"metadata column {varying[0]!r} changes inside capture {uniq[sc[a]]!r}", path,
                            int(fr.lines[j]))
        out.append((uniq[sc[a]], rows))
    return out


def infer_value_range(lo: float, hi: float, whole: bool) -> tuple[tuple[float, float], str]:
    """The inferred range of values seen in ``[lo, hi]`` and the rule that gave it (module docstring)."""
    if whole and lo >= 0:
        bits = next((b for b in ADC_BITS if hi <= 2 ** b - 1), None)
        if bits is not None:
            return (0.0, float(2 ** bits - 1)), f"the smallest 2^k - 1 that holds the largest value, {hi:g} ({bits}-bit)"
    if lo >= 0 and hi <= 1:
        return (0.0, 1.0), f"values within 0..1 (largest {hi:g}): normalised data"
    if lo == hi:
        return (lo, lo + 1.0), "one value throughout: that value to one above it"
    return (lo, hi), "the smallest and largest values seen"


def _dtype(values_whole: bool, rng: tuple[float, float]) -> np.dtype:
    if values_whole and rng[0] >= 0:
        for t in (np.uint8, np.uint16, np.uint32):
            if rng[1] <= np.iinfo(t).max:
                return np.dtype(t)
    return np.dtype(np.float64)


def _files(path: Path) -> list[Path]:
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise DataError("no such file or folder", path)
    files = sorted(p for p in path.rglob("*") if p.is_file() and p.name.lower().endswith(SUFFIXES)
                   and not p.name.startswith("."))
    if not files:
        raise DataError(f"no {', '.join(SUFFIXES)} file in this folder", path)
    return files


def _read_files(files: list[Path], columns: TableLayout, grid: tuple[int, int] | None,
                value_range: tuple[float, float] | None, grid_from: str = "--grid") -> tuple[list, tuple[int, int] | None]:
    """Each file's frames and frame and time columns, and the grid they agree on (``--grid``, or the
    first file's whose cells give one)."""
    per_file, found_grid = [], grid
    for f in files:
        fr, g, frame_col, time_col = _read_file(f, columns, found_grid, value_range, len(files) > 1, grid_from)
        if found_grid is None and g is not None:
            grid_from = f"{f.name}'s cells"
        found_grid = agree_grid(found_grid, g, f, grid_from)
        per_file.append((f, fr, frame_col, time_col))
    return per_file, found_grid


def _gather_captures(path: Path, per_file: list, frame_labels: bool = False) -> tuple[list, list, list, bool]:
    """The captures of every file, their metadata rows, their frame times (ms from the first frame)
    and whether every value is whole; a capture split across two files is refused. With
    ``frame_labels``, each capture key is a recording cut into its runs of one gesture."""
    caps, meta_rows, times, seen = [], [], [], {}
    whole = True
    for f, fr, frame_col, time_col in per_file:
        if len(fr.key) == 0:
            continue
        whole &= bool(np.all(fr.values == np.round(fr.values)))
        for key, rows in _captures(fr, f, frame_col, time_col, ("gesture",) if frame_labels else ()):
            if key in seen:
                raise DataError(f"capture {key!r} is also in {seen[key].name}: a capture's rows belong in one file",
                                f, int(fr.lines[rows[0]]))
            seen[key] = f
            for cid, part, extra in _segments(key, rows, fr, frame_labels):
                caps.append(fr.values[part])
                row = {"capture_id": cid, **fr.meta.iloc[part[0]].to_dict(), **extra}
                if len(per_file) > 1:
                    row["source"] = str(f.relative_to(path))
                meta_rows.append(row)
                times.append(None if fr.time_ms is None else fr.time_ms[part] - fr.time_ms[part[0]])
    return caps, meta_rows, times, whole


def _segments(key: str, rows: np.ndarray, fr: _Frames, frame_labels: bool):
    """A capture's rows as ``(capture id, rows, extra metadata)``: itself, or with ``frame_labels`` each
    run of one gesture of the recording ``key`` (module docstring)."""
    if not frame_labels:
        return [(key, rows, {})]
    g = fr.meta["gesture"].astype(str).to_numpy()[rows]
    starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    ends = np.r_[starts[1:], len(rows)]
    return [(f"{key}#{k + 1}", rows[a:b], {"recording": key, "start_frame": int(a)})
            for k, (a, b) in enumerate(zip(starts, ends))]


def _inferred_value_range(path: Path, caps: list, whole: bool) -> tuple[float, float]:
    """The value range inferred from the values seen, with a warning that says how."""
    lo = min(float(c.min()) for c in caps)
    hi = max(float(c.max()) for c in caps)
    value_range, why = infer_value_range(lo, hi, whole)
    log.warning("%s: value range not given: inferred %g..%g (%s); give --value-range LO..HI to state it",
                path, *value_range, why)
    return value_range


def _estimated_frame_rate(path: Path, times: list) -> float:
    """The frame rate estimated from the time column (1 / the median step), with a warning that says how."""
    if times[0] is None:
        raise TouchbenchError(f"{path}: the table does not say its frame rate: give --frame-rate, or a time "
                              "column (--time-column)")
    steps = time_step_summary(times)
    if not steps or steps["median"] <= 0:
        raise DataError("no capture has two frames to estimate the frame rate from: give --frame-rate", path)
    frame_rate = 1000.0 / steps["median"]
    log.warning("%s: frame rate estimated from the time column: %.4g Hz (1 / the median step, %.4g ms; steps "
                "%.4g..%.4g ms, 95th percentile %.4g ms); frames kept as recorded, their times in %r; give "
                "--frame-rate to state it", path, frame_rate, steps["median"], steps["min"], steps["max"],
                steps["p95"], TIME_COLUMN)
    return frame_rate


def read_table_dataset(
    path: str | Path,
    grid: tuple[int, int] | None = None,
    frame_rate: float | None = None,
    *,
    name: str | None = None,
    columns: TableLayout = TableLayout(),
    value_range: tuple[float, float] | None = None,
    sensor_name: str = "custom",
    grid_from: str = "--grid",
) -> TouchDataset:
    """Read a table file or a folder of them (module docstring) into a dataset; ``grid_from`` says
    where ``grid`` came from, in messages."""
    path = Path(path)
    frame_rate = None if frame_rate is None else check_frame_rate(frame_rate)
    value_range = None if value_range is None else check_value_range(*value_range)
    per_file, found_grid = _read_files(_files(path), columns, grid, value_range, grid_from)
    caps, meta_rows, times, whole = _gather_captures(path, per_file, columns.frame_labels)
    if not caps:
        raise DataError("no data rows", path)
    if any(t is None for t in times) and not all(t is None for t in times):
        raise DataError("some files have a time column and others not", path)
    if value_range is None:
        value_range = _inferred_value_range(path, caps, whole)
    else:
        check_range_used(min(float(c.min()) for c in caps), max(float(c.max()) for c in caps), value_range)
    if frame_rate is None:
        frame_rate = _estimated_frame_rate(path, times)
    if found_grid is None:
        raise DataError("the grid is not known: give --grid HxW", path)
    dtype = _dtype(whole, value_range)
    meta = pd.DataFrame(meta_rows)
    for c in ("capture_id", "subject", "gesture"):
        meta[c] = meta[c].astype(str)
    if times[0] is not None:
        meta[TIME_COLUMN] = [t.tolist() for t in times]
    sensor = SensorSpec(name=sensor_name, grid=found_grid, frame_rate=float(frame_rate), value_range=value_range)
    return TouchDataset(name or path.name.split(".")[0], [c.reshape(len(c), *found_grid).astype(dtype) for c in caps],
                        meta, sensor)


def read_table_format(
    path: str | Path,
    *,
    grid: tuple[int, int] | None = None,
    frame_rate: float | None = None,
    value_range: tuple[float, float] | None = None,
    capture_columns: Sequence[str] | None = None,
    subject_column: str | None = None,
    gesture_column: str | None = None,
    frame_column: str | None = None,
    time_column: str | None = None,
    time_unit: str | None = None,
    cells: str | None = None,
    value_column: str | None = None,
    layout: str | None = None,
    frame_labels: str | None = None,
    name: str | None = None,
    like: SensorSpec | None = None,
) -> TouchDataset:
    """The ``table`` file format (module docstring). ``like`` (the sensor of the model that is to
    label the data) fills the grid and value range, never the frame rate: a recording at another
    rate must be refused, not read as if it had the model's."""
    if frame_labels is not None and gesture_column is not None:
        raise TouchbenchError("give --frame-labels (each frame's label) or --gesture-column (each capture's), "
                              "not both")
    gesture_column = frame_labels if frame_labels is not None else gesture_column
    kw = {k: v for k, v in (("capture", tuple(capture_columns) if capture_columns else None),
                            ("subject", subject_column), ("gesture", gesture_column), ("frame", frame_column),
                            ("time", time_column), ("time_unit", time_unit), ("cells", cells),
                            ("value", value_column), ("layout", layout),
                            ("frame_labels", frame_labels is not None or None)) if v is not None}
    sensor_name, grid_from = "custom", "--grid"
    if like is not None:
        grid_from = "--grid" if grid else f"the model's sensor {like.name!r}"
        grid = grid or like.grid
        value_range = value_range or like.value_range
        sensor_name = like.name
    try:
        return read_table_dataset(path, grid, frame_rate, name=name, columns=TableLayout(**kw),
                                  value_range=value_range, sensor_name=sensor_name, grid_from=grid_from)
    except TouchbenchError as e:
        if like is not None and frame_rate is None and "frame rate" in str(e):
            raise TouchbenchError(f"{e} (the model was trained at {like.frame_rate:g})") from None
        raise


def _columns(text: str) -> tuple[str, ...]:
    cols = tuple(c.strip() for c in str(text).split(",") if c.strip())
    if not cols:
        raise ValueError("expected one or more column names separated by commas")
    return cols


register_format(
    "table",
    "your own sensor: a table or a folder of tables, one row per frame (a column per cell) or per cell "
    "(a true long table); CSV, CSV.gz or Parquet",
    read_table_format,
    reads="file or folder",
    options=(
        FormatOption("grid", "Rows x columns of the grid, e.g. 19x24 (when the cell names do not say it)",
                     parse_grid, metavar="HxW"),
        FormatOption("frame_rate", "Frames per second (default: estimated from the time column, with a warning)",
                     parse_frame_rate),
        FormatOption("value_range", "The sensor's value range (default: inferred, with a warning)",
                     parse_value_range, metavar="LO..HI"),
        FormatOption("capture_columns", "Column(s) naming a capture, comma-separated (default capture_id)",
                     _columns, metavar="COLS"),
        FormatOption("subject_column", "The subject column (default subject)", metavar="COL"),
        FormatOption("gesture_column", "The gesture column (default gesture)", metavar="COL"),
        FormatOption("frame_column", "The frame counter (default: frame, frame_id... if present)", metavar="COL"),
        FormatOption("time_column", "The time column (default: time, time_ms, timestamp... if present)",
                     metavar="COL"),
        FormatOption("time_unit", "Unit of a numeric time column whose name does not say it: s, ms or us",
                     metavar="UNIT"),
        FormatOption("cells", "Cell columns: a pattern such as pixel{i} or r{row}c{col}; in a long table the "
                     "position column(s), row,col or cell", metavar="PATTERN"),
        FormatOption("value_column", "A long table's value column (default value)", metavar="COL"),
        FormatOption("layout", "wide (a row per frame), long (a row per cell) or auto", metavar="LAYOUT"),
        FormatOption("frame_labels", "Continuous recordings labelled frame by frame: the column of each frame's "
                     "label (the capture columns then name a recording, cut into one capture per run of one label)",
                     metavar="COL"),
    ),
)
