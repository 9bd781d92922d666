"""A reader for users' own sensors: a long-format CSV or Parquet table.

One row per frame: a capture id column, a frame index column, metadata
columns (``subject`` and ``gesture`` required; any others are kept, and must
be constant within a capture), and one column per cell, H x W of them, in
row-major order. The user gives the grid shape and frame rate. Cell columns
are those named in ``cells``, or else every column whose name is a common
prefix followed by a number (``cell1``.., ``ch1``.., ``c0``..), ordered by
that number.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .formats import FormatOption, parse_frame_rate, parse_grid, register_format
from .model import SensorSpec, TouchDataset
from .tables import find_column, numeric, read_table, runs


def cell_columns(df: pd.DataFrame, n_cells: int, path: Path) -> list[str]:
    """The ``n_cells`` cell columns: the one group of columns named by a common prefix and a number, by number."""
    groups: dict[str, list[tuple[int, str]]] = {}
    for c in df.columns:
        m = re.fullmatch(r"(.*?)(\d+)", c)
        if m:
            groups.setdefault(m.group(1), []).append((int(m.group(2)), c))
    fits = [sorted(v) for v in groups.values() if len(v) == n_cells]
    if len(fits) != 1:
        raise DataError(
            f"cannot tell the {n_cells} cell columns apart (name them with cells=...); "
            f"numbered column groups: { {k: len(v) for k, v in groups.items()} }", path, 1)
    return [c for _, c in fits[0]]


def read_long_table(
    path: str | Path,
    grid: tuple[int, int],
    frame_rate: float,
    *,
    name: str | None = None,
    capture_col: str = "capture_id",
    frame_col: str = "frame",
    cells: Sequence[str] | None = None,
    value_range: tuple[float, float] = (0.0, 1023.0),
    sensor_name: str = "custom",
) -> TouchDataset:
    path = Path(path)
    sensor = SensorSpec(name=sensor_name, grid=grid, frame_rate=frame_rate, value_range=value_range)
    df = read_table(path)
    cap = find_column(df, (capture_col,), path, "capture id")
    fr = find_column(df, (frame_col,), path, "frame index")
    for req in ("subject", "gesture"):
        find_column(df, (req,), path, req)
    cell_cols = list(cells) if cells is not None else cell_columns(df, sensor.n_cells, path)
    missing = [c for c in cell_cols if c not in df.columns]
    if missing:
        raise DataError(f"cell columns not found: {missing[:5]}", path, 1)
    if len(cell_cols) != sensor.n_cells:
        raise DataError(f"{len(cell_cols)} cell columns for a {grid[0]} x {grid[1]} grid ({sensor.n_cells} cells)", path, 1)
    values = numeric(df, cell_cols, path, lo=value_range[0], hi=value_range[1])
    frame = numeric(df, [fr], path, integer=True)[:, 0]
    first = int(frame[0]) if len(frame) else 1
    if first not in (0, 1):  # frames count from 0 or 1, as the file's first row says
        raise DataError(f"the first {frame_col} is {first}; frames are numbered from 0 or 1", path, 2)
    bounds = runs(df[[cap]], frame, path, frame_col, origin=first)
    meta_cols = [c for c in df.columns if c not in set(cell_cols) | {fr}]
    rows, captures = [], []
    for a, b in bounds:
        block = df.iloc[a:b][meta_cols]
        varying = [c for c in meta_cols if block[c].nunique(dropna=False) > 1]
        if varying:
            i = a + int(np.flatnonzero((block[varying[0]] != block[varying[0]].iloc[0]).to_numpy())[0])
            raise DataError(f"metadata column {varying[0]!r} changes inside capture {df[cap].iloc[a]!r}", path, i + 2)
        rows.append(block.iloc[0].to_dict())
        captures.append(values[a:b].reshape(b - a, *grid))
    meta = pd.DataFrame(rows).rename(columns={cap: "capture_id"})
    for c in ("capture_id", "subject", "gesture"):
        meta[c] = meta[c].astype(str)
    if meta["capture_id"].duplicated().any():
        dup = meta["capture_id"][meta["capture_id"].duplicated()].iloc[0]
        raise DataError(f"capture {dup!r} appears in two separate runs of rows", path)
    return TouchDataset(name or path.stem, captures, meta, sensor)


def read_long_format(
    path: str | Path,
    *,
    grid: tuple[int, int] | None = None,
    frame_rate: float | None = None,
    name: str | None = None,
    like: SensorSpec | None = None,
) -> TouchDataset:
    """The ``long`` file format: :func:`read_long_table` with the grid and
    frame rate given. ``like`` (the sensor of the model that is to label the
    data) fills the grid and value range, never the frame rate: the file does
    not say it, and a recording at another rate must be refused, not read as
    if it had the model's."""
    kw = {}
    if like is not None:
        grid = grid or like.grid
        kw = {"value_range": like.value_range, "sensor_name": like.name}
    if frame_rate is None:
        hint = f" (the model was trained at {like.frame_rate:g})" if like is not None else ""
        raise TouchbenchError(f"the long format does not say its frame rate: give --frame-rate, the frames per "
                              f"second of this recording{hint}")
    if grid is None:
        raise TouchbenchError("the long format does not say its grid: give --grid HxW")
    return read_long_table(path, tuple(grid), float(frame_rate), name=name, **kw)


register_format(
    "long", "your own sensor: one row per frame (capture_id, frame, subject, gesture, H x W numbered cell columns)",
    read_long_format,
    options=(
        FormatOption("grid", "Rows x columns of the grid, e.g. 19x24", parse_grid, metavar="HxW", required=True),
        FormatOption("frame_rate", "Frames per second", parse_frame_rate, required=True),
    ),
)
