"""Atomic file writes: a file appears whole, or not at all.

Every writer goes through :func:`atomic_path`: the content is written to a
temporary file in the destination folder and renamed over the destination,
so an interrupted or parallel writer never leaves a half-written file.

The temporary file (:func:`new_temp_file`) is created as ``open(path, "w")``
would create ``path``: mode 0o666 less the process's umask (and the
folder's default ACL, where it has one), applied by the operating system
when the file is created. So a cache or results folder shared between users
or workers is as readable as the user's umask says (``umask 022``: 0644),
never 0600 whatever the umask (:func:`tempfile.mkstemp`'s mode).
"""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path
from typing import Iterator

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .errors import WriteError

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_parquet", "new_temp_file"]

_CREATE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)  # O_EXCL: never through a link


def new_temp_file(path: Path) -> str:
    """Create a new, empty, uniquely named file beside ``path`` (``.NAME.RANDOM.tmp``) and return
    its name; its mode is 0o666 less the umask, as for any file the user creates."""
    for _ in range(100):
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            fd = os.open(tmp, _CREATE, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return str(tmp)
    raise FileExistsError(f"{path.parent}: no free temporary file name beside {path.name}")


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[str]:
    """Yield a temporary file name beside ``path``; rename it to ``path`` on success.

    On any error the temporary file is removed and ``path`` is left as it was.
    An operating-system error (permissions, a read-only or full disk) becomes a
    :class:`touchbench.core.errors.WriteError` naming ``path``.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = new_temp_file(path)
    except OSError as e:
        raise WriteError(path, e) from None
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


def atomic_write_parquet(path: Path, df: pd.DataFrame, metadata: dict[str, str] | None = None) -> None:
    """Write ``df`` as Parquet through a temporary file and a rename; ``metadata`` joins the file's
    key-value metadata."""
    table = pa.Table.from_pandas(df, preserve_index=False)
    if metadata:
        table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                               **{k.encode(): v.encode() for k, v in metadata.items()}})
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
