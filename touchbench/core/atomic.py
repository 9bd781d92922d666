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

A whole folder is replaced the same way (:func:`replace_dir`): written under a
temporary name beside it, then renamed into place.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
from pathlib import Path
from typing import Callable, Iterator

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .errors import WriteError

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_parquet", "new_temp_file", "replace_dir"]

_CREATE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)  # O_EXCL: never through a link


def _new_sibling(path: Path, create: Callable[[Path], None], suffix: str = "tmp") -> Path:
    """Create (``create``) a new, uniquely named entry beside ``path`` (``.NAME.RANDOM.SUFFIX``)."""
    for _ in range(100):
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.{suffix}"
        try:
            create(tmp)
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(f"{path.parent}: no free temporary name beside {path.name}")


def _create_file(path: Path) -> None:
    os.close(os.open(path, _CREATE, 0o666))


def _unused(path: Path) -> None:
    """Only check that ``path`` is free (a name for a later rename)."""
    if os.path.lexists(path):
        raise FileExistsError(path)


def new_temp_file(path: Path) -> str:
    """Create a new, empty, uniquely named file beside ``path`` (``.NAME.RANDOM.tmp``) and return
    its name; its mode is 0o666 less the umask, as for any file the user creates."""
    return str(_new_sibling(path, _create_file))


def replace_dir(path: Path, write: Callable[[Path], None]) -> None:
    """Make the folder ``path`` whole or not at all: ``write`` fills a new folder beside it
    (``.NAME.RANDOM.tmp``, its mode as ``mkdir`` gives it), which is then renamed to ``path``. An
    existing ``path`` is first renamed aside and removed only once the new folder is in place; when
    anything fails, the new folder is removed and ``path`` is left as it was. An operating-system
    error becomes a :class:`WriteError` naming ``path``."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = _new_sibling(path, os.mkdir)
    except OSError as e:
        raise WriteError(path, e) from None
    old = None
    try:
        write(tmp)
        if os.path.lexists(path):
            old = _new_sibling(path, _unused, "old")
            os.rename(path, old)
        try:
            os.rename(tmp, path)
        except BaseException:
            if old is not None:
                os.rename(old, path)
                old = None
            raise
    except BaseException as e:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(e, OSError) and not isinstance(e, WriteError):
            raise WriteError(path, e) from None
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


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
