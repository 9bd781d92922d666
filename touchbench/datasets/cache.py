"""The dataset cache: a dataset converted once is kept as Parquet, keyed by
the reader's version and the SHA-256 of every source file, so a second load
reads one Parquet file and an edited source file is noticed.

Writes are atomic (``TouchDataset.to_parquet`` writes a temporary file and
renames it); a build that fails leaves no cache entry behind. A cache entry
that is damaged (unreadable, cut short, or no longer matching the hash it
was written with) is rebuilt from the source files, with a warning that
says so: the cache is a copy, never new data.

Beside each entry, ``<entry>.json`` records what was computed from its content
once: the content hash and the per-capture checksums of test sets
(:meth:`TouchDataset.labelled_checksums`, per label column, added as runs ask
for them), with the entry's size, modification time and SHA-256 when they
were computed. A load reads the entry's bytes once, hashes them, and takes
these values only when size, time and SHA-256 all match; otherwise the
content is hashed again (and verified against the hash the entry was
written with) and the record is written anew.
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path
from typing import Any, Callable, Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from ..core.atomic import atomic_write_bytes
from ..core.errors import DataError, WriteError
from ..core.hashing import file_state, settled
from ..core.paths import cache_dir as default_cache_dir
from .model import FORMAT_VERSION, TouchDataset

log = logging.getLogger("touchbench.datasets")


#: the SHA-256 of each source file hashed so far, with the file's state then (``datasets/sources.json``)
SOURCES_NAME = "sources.json"
def _digest(f: Path, known: dict[str, Any]) -> bytes:
    """The SHA-256 of ``f``: from ``known`` (absolute path -> [state, hex digest]) while the file's
    state is the one it was hashed in, else read and hashed (and kept in ``known`` unless the file
    changed within :data:`touchbench.core.hashing.RECENT_SECONDS`)."""
    key, state = str(f.absolute()), file_state(f)
    entry = known.get(key)
    if isinstance(entry, list) and len(entry) == 2 and entry[0] == state:
        return bytes.fromhex(entry[1])
    digest = hashlib.sha256(f.read_bytes()).digest()
    if settled(state[4]):
        known[key] = [state, digest.hex()]
    else:
        known.pop(key, None)
    return digest


def source_key(reader_version: str, files: Sequence[Path], known: Path | None = None) -> str:
    """SHA-256 over the reader version and each file's name and content hash. ``known``: a file
    keeping each file's digest with its state (:func:`_digest`): a file not written since is not
    read again."""
    memo = _read_json(known) if known is not None else {}
    before = dict(memo)
    h = hashlib.sha256(f"{reader_version}\0format{FORMAT_VERSION}".encode())
    for f in sorted(files, key=lambda p: (p.parent.name, p.name)):
        h.update(f"\0{f.parent.name}/{f.name}\0".encode())
        h.update(_digest(f, memo))
    if known is not None and memo != before:
        _write_json(known, memo)
    return h.hexdigest()[:24]


def _read_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _write_json(path: Path, data: dict[str, Any]) -> None:
    """``data`` written atomically; a cache folder that cannot take it only costs a later load the
    hashing (a debug message)."""
    try:
        atomic_write_bytes(path, json.dumps(data).encode())
    except WriteError as e:
        log.debug("%s: not written (%s)", path, e)


def cached_dataset(
    name: str,
    reader_version: str,
    files: Sequence[Path],
    build: Callable[[], TouchDataset],
    cache_dir: str | Path | None = None,
    refresh: bool = False,
) -> TouchDataset:
    """Load ``name`` from the cache, or build it and cache it."""
    root = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = root / "datasets" / f"{name}-{source_key(reader_version, files, root / 'datasets' / SOURCES_NAME)}.parquet"
    if path.is_file() and not refresh:
        try:
            return load_entry(path)
        except DataError as e:
            log.warning("%s: the cached copy of %s is damaged (%s); rebuilt from its source files", path, name,
                        str(e).removeprefix(f"{path}: "))
    ds = build()
    ds.to_parquet(path)
    _keep_record(path, ds, _entry_state(path, hashlib.sha256(path.read_bytes()).hexdigest()))
    return ds


def record_path(entry: Path) -> Path:
    """The record of what was computed from cache entry ``entry``'s content (``<entry>.json``)."""
    return entry.with_name(entry.name + ".json")


def _entry_state(path: Path, sha256: str) -> dict[str, Any]:
    st = path.stat()
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": sha256}


def _read_record(entry: Path, state: dict[str, Any]) -> dict[str, Any] | None:
    """The entry's record when it was made from exactly these bytes (``state``), else None."""
    try:
        record = json.loads(record_path(entry).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("file") != state or not isinstance(record.get("labelled"), dict):
        return None
    return record


def load_entry(path: Path) -> TouchDataset:
    """The cache entry ``path`` (refused when damaged: :class:`DataError`), with what its record
    holds for exactly these bytes; a missing or outdated record is written anew."""
    try:
        data = path.read_bytes()
        table = pq.read_table(pa.BufferReader(data), use_threads=False)  # one column chunk: no faster with threads
    except OSError as e:
        raise DataError(f"not readable ({e})", path) from None
    except Exception as e:  # pyarrow raises several types for a bad file
        raise DataError(f"not a readable Parquet file ({e})", path) from None
    state = _entry_state(path, hashlib.sha256(data).hexdigest())
    record = _read_record(path, state)
    known = record.get("content_hash") if record is not None else None
    ds = TouchDataset.from_table(table, path, verify=True, content_hash=known)
    if record is None or known != ds.content_hash:
        record = _keep_record(path, ds, state)
    else:
        _follow(path, ds, record)
    ds._labelled.update({k: v for k, v in record["labelled"].items() if isinstance(v, list) and len(v) == len(ds)})
    return ds


def _keep_record(path: Path, ds: TouchDataset, state: dict[str, Any]) -> dict[str, Any]:
    """Write the record of entry ``path`` (its bytes' ``state``, ``ds``'s content hash) and keep
    the checksums ``ds`` computes later in it."""
    record = {"file": state, "content_hash": ds.content_hash, "labelled": {}}
    _write_record(path, record)
    _follow(path, ds, record)
    return record


def _follow(path: Path, ds: TouchDataset, record: dict[str, Any]) -> None:
    """Add each column's checksums ``ds`` computes to the record of entry ``path``."""
    def keep(column: str, checksums: list[str]) -> None:
        record["labelled"][column] = checksums
        _write_record(path, record)
    ds._on_labelled = keep


def _write_record(path: Path, record: dict[str, Any]) -> None:
    _write_json(record_path(path), record)
