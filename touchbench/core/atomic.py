"""Atomic file writes: a file appears whole, or not at all.

Every writer goes through :func:`atomic_path`: the content is written to a
temporary file in the destination folder and renamed over the destination,
so an interrupted or parallel writer never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .errors import WriteError

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_parquet"]


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[str]:
    """Yield a temporary file name beside ``path``; rename it to ``path`` on success.

    On any error the temporary file is removed and ``path`` is left as it was.
    An operating-system error (permissions, a read-only or full disk) becomes a
    :class:`~touchbench.core.errors.WriteError` naming ``path``.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as e:
        raise WriteError(path, e) from None
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and not isinstance(e, WriteError):
            raise WriteError(path, e) from None
        raise


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file (flushed to disk) and a rename."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())


def atomic_write_parquet(path: Path, df: pd.DataFrame) -> None:
    """Write ``df`` as Parquet through a temporary file and a rename."""
    table = pa.Table.from_pandas(df, preserve_index=False)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
