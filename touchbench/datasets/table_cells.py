"""The ``table`` format's cell columns in a row-per-frame table (:mod:`.generic`): named by a pattern
(``pixel{i}``, ``r{row}c{col}``) or found by their names, in row-major order, with the grid their
names lay out; a grid given that does not fit them is refused (both counts, or that it looks
transposed: :func:`.table_long.agree_grid`)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.errors import DataError, TouchbenchError
from .table_long import count_mismatch, from_zero_or_one

__all__ = ["cell_columns", "numbered_groups", "pattern_regex"]


def pattern_regex(pattern: str) -> tuple[re.Pattern, tuple[str, ...]]:
    fields = tuple(re.findall(r"\{(i|row|col)\}", pattern))
    if sorted(fields) not in (["i"], ["col", "row"]):
        raise TouchbenchError(f"cell pattern {pattern!r}: use {{i}} (one index) or {{row}} and {{col}}, "
                              "such as pixel{i} or r{row}c{col}")
    parts = re.split(r"\{(?:i|row|col)\}", pattern)
    rx = "".join(re.escape(p) + (r"(\d+)" if k < len(fields) else "") for k, p in enumerate(parts))
    return re.compile(rx), fields


def numbered_groups(df: pd.DataFrame) -> dict[str, list[tuple[int, str]]]:
    """Columns named by a common prefix and a number: prefix -> ``[(number, column), ...]``."""
    groups: dict[str, list[tuple[int, str]]] = {}
    for c in df.columns:
        m = re.fullmatch(r"(.*?)(\d+)", c)
        if m:
            groups.setdefault(m.group(1), []).append((int(m.group(2)), c))
    return groups


def _laid_out(pos: np.ndarray) -> tuple[np.ndarray, tuple[int, int]] | None:
    """``(row, col)`` positions, each counting from 0 or 1, that fill a grid exactly once: their
    row-major order and the grid; else None."""
    r, c = pos[:, 0] - pos[:, 0].min(), pos[:, 1] - pos[:, 1].min()
    if pos[:, 0].min() not in (0, 1) or pos[:, 1].min() not in (0, 1):
        return None
    shape = (int(r.max()) + 1, int(c.max()) + 1)
    flat = r * shape[1] + c
    if len(set(flat.tolist())) != len(pos) or len(pos) != shape[0] * shape[1]:
        return None
    return np.argsort(flat), shape


def _candidate_groups(df: pd.DataFrame) -> dict[str, tuple[list[str], tuple[int, int] | None]]:
    """The groups of columns that may be the cells, by the pattern naming them: ``r{row}c{col}``-like
    groups (a prefix, a row number, a separator, a column number) that fill a grid, with the grid
    they lay out, and ``<prefix>{i}`` groups of more than one column (row-major order unknown)."""
    two: dict[tuple[str, str], list[tuple[tuple[int, int], str]]] = {}
    for col in df.columns:
        m = re.fullmatch(r"(\D*?)(\d+)(\D+)(\d+)", str(col))
        if m:
            two.setdefault((m.group(1), m.group(3)), []).append(((int(m.group(2)), int(m.group(4))), col))
    out: dict[str, tuple[list[str], tuple[int, int] | None]] = {}
    for (prefix, sep), found in two.items():
        laid = _laid_out(np.array([k for k, _ in found])) if len(found) > 1 else None
        if laid is not None:
            out[f"{prefix}{{row}}{sep}{{col}}"] = ([found[i][1] for i in laid[0]], laid[1])
    named = {c for cols, _ in out.values() for c in cols}
    for prefix, found in numbered_groups(df).items():
        if len(found) > 1 and not {c for _, c in found} <= named:
            out[f"{prefix}{{i}}"] = ([c for _, c in sorted(found)], None)
    return out


def _default_cell_columns(df: pd.DataFrame, grid: tuple[int, int] | None, path: Path,
                          grid_from: str) -> tuple[list[str], tuple[int, int] | None]:
    """:func:`cell_columns` without a pattern: the one candidate group with the grid's cell count."""
    groups = _candidate_groups(df)
    n_cells = grid[0] * grid[1] if grid is not None else None
    fits = {k: v for k, v in groups.items() if n_cells is None or len(v[0]) == n_cells}
    if not fits and len(groups) == 1:
        (name, (cols, shape)), = groups.items()
        laid = f", laid out as {shape[0]} rows x {shape[1]} columns" if shape is not None else ""
        raise DataError(count_mismatch(grid, len(cols), f"cell columns ({cols[0]}..{cols[-1]}{laid})", grid_from),
                        path, 1)
    if len(fits) != 1:
        want = f"the {n_cells} cell columns" if n_cells else "the cell columns"
        raise DataError(
            f"cannot tell {want} apart (name them with a pattern such as --cells 'pixel{{i}}'); groups of numbered "
            f"columns: { {k: len(v[0]) for k, v in groups.items()} }", path, 1)
    (name, (cols, shape)), = fits.items()
    if shape is None:
        idx = from_zero_or_one(np.array([int(re.fullmatch(r".*?(\d+)", c).group(1)) for c in cols]),
                               "the cell columns", path)
        if not np.array_equal(idx, np.arange(len(idx))):
            raise DataError(f"cell columns {cols[0]}..{cols[-1]} skip a number", path, 1)
    return cols, shape


def cell_columns(df: pd.DataFrame, grid: tuple[int, int] | None, path: Path, pattern: str | None = None,
                 grid_from: str = "--grid") -> tuple[list[str], tuple[int, int] | None]:
    """The cell columns in row-major order, and the grid their names give (``None`` for one index).

    Without ``pattern``: the one group of columns named by a common prefix and a number, or by a
    prefix, a row, a separator and a column (``r{row}c{col}``), whose size is the cell count of
    ``grid`` (from ``grid_from``; or the only such group when the grid is not known). One group of
    another size is refused with both counts and the grid."""
    if pattern is None:
        return _default_cell_columns(df, grid, path, grid_from)
    rx, fields = pattern_regex(pattern)
    found = [(tuple(int(g) for g in m.groups()), c) for c in df.columns if (m := rx.fullmatch(c))]
    if not found:
        raise DataError(f"no column matches the cell pattern {pattern!r} (columns: {list(df.columns)[:8]}...)", path, 1)
    if fields == ("i",):
        idx = from_zero_or_one(np.array([k[0] for k, _ in found]), "the cell columns", path)
        order = np.argsort(idx, kind="stable")
        if not np.array_equal(idx[order], np.arange(len(found))):
            raise DataError(f"the columns matching {pattern!r} skip a number or give one twice", path, 1)
        return [found[i][1] for i in order], None
    pos = np.array([k for k, _ in found])
    if fields == ("col", "row"):
        pos = pos[:, ::-1]
    from_zero_or_one(pos[:, 0], "the rows of the cell columns", path)
    from_zero_or_one(pos[:, 1], "the columns of the cell columns", path)
    laid = _laid_out(pos)
    if laid is None:
        shape = (int(np.ptp(pos[:, 0])) + 1, int(np.ptp(pos[:, 1])) + 1)
        raise DataError(f"the columns matching {pattern!r} do not fill a {shape[0]} x {shape[1]} grid "
                        f"({len(found)} columns)", path, 1)
    return [found[i][1] for i in laid[0]], laid[1]
