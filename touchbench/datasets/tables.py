"""Reading tabular (one row per frame) files with errors that name the line.

Shared by the challenge CSV, CoST, SocialTouch and table readers. Line
numbers are 1-based file lines: the header is line 1, data row ``i``
(0-based) is line ``i + 2``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv

from ..core.atomic import new_temp_file
from ..core.errors import DataError


def clean_name(name: object) -> str:
    """A header name without surrounding spaces and quotes."""
    return str(name).strip().strip("\"'").strip()


def _text_dtypes(path: Path, text_columns: Sequence[str]) -> dict[str, type]:
    """The CSV header's columns among ``text_columns`` (matched as :func:`find_column` does), read as text."""
    if not text_columns:
        return {}
    header = pd.read_csv(path, skipinitialspace=True, nrows=0).columns
    wanted = {c.lower() for c in text_columns}
    return {c: str for c in header if clean_name(c).lower() in wanted}


def _refuse_repeated_header(df: pd.DataFrame, path: Path) -> None:
    """A data row that repeats the header (two files joined together) is refused at its line."""
    if df.empty or pd.api.types.is_numeric_dtype(df.iloc[:, 0]):
        return
    first = df.iloc[:, 0].astype(str).str.strip().str.strip("\"'")
    for i in np.flatnonzero((first == df.columns[0]).to_numpy()):
        row = [clean_name(v) for v in df.iloc[i].tolist()]
        if row == list(df.columns):
            raise DataError("this line repeats the header row (two files joined into one?)", path, int(i) + 2)


def read_table(path: str | Path, allow_empty: bool = False, text_columns: Sequence[str] = ()) -> pd.DataFrame:
    """Read a CSV (plain or gzipped) or Parquet file; header names cleaned.

    A CSV row with more fields than the header is refused with its line, and
    so is a row that repeats the header; a file with a header and no rows is
    refused unless ``allow_empty``. The columns named in ``text_columns``
    (identifiers: any case) are read as text, as written (``007`` stays
    ``007``).
    """
    path = Path(path)
    if not path.is_file():
        raise DataError("no such file", path)
    try:
        if path.suffix == ".parquet":
            df = pd.read_parquet(path)
        else:
            # blank lines are kept as empty rows, so that row i is line i + 2 of the file
            df = pd.read_csv(path, skipinitialspace=True, low_memory=False, skip_blank_lines=False,
                             dtype=_text_dtypes(path, text_columns))
            filled = np.flatnonzero(df.notna().any(axis=1).to_numpy())
            df = df.iloc[: filled[-1] + 1 if len(filled) else 0]  # blank lines at the end are no rows
    except pd.errors.ParserError as e:
        m = re.search(r"line (\d+)", str(e))
        raise DataError(f"malformed row ({e})", path, int(m.group(1)) if m else None) from None
    except pd.errors.EmptyDataError:
        raise DataError("empty file", path) from None
    except Exception as e:  # unreadable Parquet, bad encoding...
        raise DataError(f"cannot read ({e})", path) from None
    df.columns = [clean_name(c) for c in df.columns]
    if df.empty and not allow_empty:
        raise DataError("no data rows", path)
    _refuse_repeated_header(df, path)
    return df


def find_column(df: pd.DataFrame, names: Sequence[str], path: Path, what: str) -> str:
    """The first column whose name matches one of ``names`` (case-insensitive)."""
    lower = {c.lower(): c for c in df.columns}
    for n in names:
        if n.lower() in lower:
            return lower[n.lower()]
    raise DataError(f"no {what} column (expected one of {list(names)}; found {list(df.columns)[:8]}...)", path, 1)


def numeric(
    df: pd.DataFrame,
    cols: Sequence[str],
    path: Path,
    *,
    lo: float | None = None,
    hi: float | None = None,
    integer: bool = False,
    lines: np.ndarray | None = None,
) -> np.ndarray:
    """The columns as a float64 array; refuses the first bad cell by line (row ``i`` is line
    ``lines[i]``, by default ``i + 2``).

    Bad: empty (a row with fewer values than the header), non-numeric (text
    that is not a plain number, such as ``1_0``), NaN or infinite, outside
    ``[lo, hi]``, or not a whole number when ``integer``.
    """
    sub = df[list(cols)]
    raw = None
    if all(pd.api.types.is_numeric_dtype(t) for t in sub.dtypes):
        arr = sub.to_numpy(dtype=np.float64)
    else:  # text cells: read as numbers by pandas' parser, never Python's float() (which takes 1_0 as 10)
        raw = sub.astype(str).to_numpy()
        arr = pd.DataFrame(raw).apply(pd.to_numeric, errors="coerce").to_numpy(dtype=np.float64)
    bad = ~np.isfinite(arr)
    problem = "missing, non-numeric, NaN or infinite value"
    if not bad.any() and lo is not None:
        bad, problem = arr < lo, f"value below {lo:g}"
    if not bad.any() and hi is not None:
        bad, problem = arr > hi, f"value above {hi:g}"
    if not bad.any() and integer:
        bad, problem = arr != np.round(arr), "not a whole number"
    if bad.any():
        r, c = np.argwhere(bad)[0]
        shown = raw[r, c] if raw is not None else arr[r, c]
        raise DataError(f"column {cols[c]!r}: {problem} ({shown!r})", path,
                        int(lines[r]) if lines is not None else int(r) + 2)
    return arr


def runs(keys: pd.DataFrame, counter: np.ndarray | None, path: Path, counter_name: str = "frame",
         origin: int = 1) -> list[tuple[int, int]]:
    """Split rows into captures: ``[(start, stop), ...]``.

    A new capture starts where any key column changes, or where the frame
    counter restarts at ``origin`` (0 or 1). Inside a capture the counter must
    climb by one. Errors quote the counter as the file has it, at the line of
    the row at fault.
    """
    n = len(keys)
    change = np.zeros(n, dtype=bool)
    change[0] = True
    if n > 1:
        k = keys.astype(str).to_numpy()
        change[1:] |= (k[1:] != k[:-1]).any(axis=1)
    if counter is not None:
        change |= counter == origin
        starts_bad = change & (counter != origin)
        if starts_bad.any():
            i = int(np.flatnonzero(starts_bad)[0])
            raise DataError(f"a capture starts with {counter_name} {counter[i]:g}, not {origin}", path, i + 2)
        step_bad = ~change[1:] & (np.diff(counter) != 1)
        if step_bad.any():
            i = int(np.flatnonzero(step_bad)[0]) + 1
            raise DataError(f"{counter_name} jumps from {counter[i - 1]:g} to {counter[i]:g}", path, i + 2)
    starts = np.flatnonzero(change)
    stops = np.append(starts[1:], n)
    return list(zip(starts.tolist(), stops.tolist()))


def write_csv_atomic(frames: Iterable[tuple[Path, "pa.Table"]]) -> None:
    """Write several CSV files; all appear, or none (temporary + rename).

    Strings and header names are quoted, numbers are not (as R's
    ``write.table`` writes them).
    """
    tmps: list[tuple[str, Path]] = []
    try:
        for path, df in frames:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = new_temp_file(path)
            tmps.append((tmp, path))
            pacsv.write_csv(df, tmp, pacsv.WriteOptions(quoting_style="needed"))
        for tmp, path in tmps:
            os.replace(tmp, path)
    finally:
        for tmp, _ in tmps:
            Path(tmp).unlink(missing_ok=True)
