"""The ``table`` format's long layout (one row per cell) gathered into frames, and the helpers both
layouts share: capture keys, counting from 0 or 1, the grid the cells give (:mod:`.generic`)."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .tables import find_column, numeric

__all__ = ["agree_grid", "capture_key", "count_mismatch", "from_zero_or_one", "long_to_frames"]


def from_zero_or_one(idx: np.ndarray, what: str, path: Path) -> np.ndarray:
    lo = int(idx.min())
    if lo not in (0, 1):
        raise DataError(f"{what} count from {lo}; they must count from 0 or 1", path, 1)
    return idx - lo


def count_mismatch(grid: tuple[int, int], n_cells: int, what: str, grid_from: str = "--grid") -> str:
    """The message for a grid whose cell count is not the table's: both counts and the grid."""
    h, w = grid
    return f"the grid {h}x{w} ({grid_from}) has {h * w} cells, but the table has {n_cells} {what}"


def agree_grid(given: tuple[int, int] | None, found: tuple[int, int] | None, path: Path,
               grid_from: str = "--grid") -> tuple[int, int] | None:
    """The grid: ``given`` (from ``grid_from``) or ``found`` (the layout the cells' names or positions
    show); both and different is refused: a transposed grid is said to be one, another cell count
    says both counts."""
    if given is not None and found is not None and tuple(given) != tuple(found):
        (gh, gw), (fh, fw) = given, found
        laid = f"laid out as {fh} rows x {fw} columns ({fh}x{fw})"
        if (gh, gw) == (fw, fh):
            raise DataError(f"the grid {gh}x{gw} ({grid_from}) looks transposed: the table's cells are {laid}", path, 1)
        if gh * gw != fh * fw:
            raise DataError(count_mismatch(given, fh * fw, f"cells, {laid}", grid_from), path, 1)
        raise DataError(f"the table's cells are {laid}, not the grid {gh}x{gw} ({grid_from})", path, 1)
    return tuple(found or given) if (found or given) else None


def long_to_frames(df, cap, frame, time, value, cells, grid, path, lo, hi, grid_from="--grid"):
    """A long table's rows gathered into frames: values ``(frames, H*W)``, each frame's first line,
    the frames' rows of ``df`` (for the other columns), the grid (``grid``, from ``grid_from``, must be
    the one the row and column positions give)."""
    names = cells.split(",") if cells else None
    if names is None:
        names = ["row", "col"] if {"row", "col"} <= {c.lower() for c in df.columns} else ["cell"]
    pos_cols = [find_column(df, (n,), path, f"cell position ({n})") for n in names]
    pos = numeric(df, pos_cols, path, integer=True).astype(np.int64)
    if len(pos_cols) == 2:
        r = from_zero_or_one(pos[:, 0], f"the values of {pos_cols[0]!r}", path)
        c = from_zero_or_one(pos[:, 1], f"the values of {pos_cols[1]!r}", path)
        grid = agree_grid(grid, (int(r.max()) + 1, int(c.max()) + 1), path, grid_from)
        k = r * grid[1] + c
    elif len(pos_cols) == 1:
        if grid is None:
            raise DataError(f"the cell index {pos_cols[0]!r} does not say the grid: give --grid HxW", path, 1)
        k = from_zero_or_one(pos[:, 0], f"the values of {pos_cols[0]!r}", path)
        if k.max() >= grid[0] * grid[1]:
            i = int(np.argmax(k >= grid[0] * grid[1]))
            raise DataError(f"cell {pos[i, 0]} beyond a {grid[0]} x {grid[1]} grid", path, i + 2)
    else:
        raise TouchbenchError(f"a long table's cells are one index column or row,col; got {cells!r}")
    v = numeric(df, [value], path, lo=lo, hi=hi)[:, 0]
    n_cells = grid[0] * grid[1]
    fkey = df[frame if frame is not None else time].astype(str).to_numpy()
    ckey = capture_key(df, cap)
    codes = pd.DataFrame({"c": ckey, "f": fkey}).groupby(["c", "f"], sort=False).ngroup().to_numpy()
    order = np.lexsort((k, codes))
    sc, sk = codes[order], k[order]
    starts = np.flatnonzero(np.r_[True, sc[1:] != sc[:-1]])
    counts = np.diff(np.r_[starts, len(sc)])
    within = np.arange(len(sc)) - np.repeat(starts, counts)
    wrong = np.flatnonzero(counts != n_cells)
    if wrong.size:
        i = order[starts[wrong[0]]]
        raise DataError(f"frame {fkey[i]} of capture {str(ckey[i])!r}: {counts[wrong[0]]} cells "
                        f"for a {grid[0]} x {grid[1]} grid", path, int(i) + 2)
    bad = np.flatnonzero(sk != within)  # as many rows as cells, so one cell is there twice and another missing
    if bad.size:
        i = order[bad[0]]
        raise DataError(f"frame {fkey[i]} of capture {str(ckey[i])!r}: cell "
                        f"{pos[i].tolist()} given twice", path, int(i) + 2)
    first_row = np.minimum.reduceat(order, starts)  # a frame's first row in the file (codes: first-seen order)
    rows = df.iloc[first_row].reset_index(drop=True)
    return v[order].reshape(-1, n_cells), first_row + 2, rows, grid


def capture_key(df: pd.DataFrame, cols: Sequence[str]) -> np.ndarray:
    parts = [df[c].astype(str).str.strip().to_numpy(dtype=object) for c in cols]
    key = parts[0]
    for p in parts[1:]:
        key = key + "-" + p
    return key.astype(str)
