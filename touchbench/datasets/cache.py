"""The dataset cache: a dataset converted once is kept as Parquet, keyed by
the reader's version and the SHA-256 of every source file, so a second load
reads one Parquet file and an edited source file is noticed.

Writes are atomic (``TouchDataset.to_parquet`` writes a temporary file and
renames it); a build that fails leaves no cache entry behind. A cache entry
that is damaged (unreadable, cut short, or no longer matching the hash it
was written with) is rebuilt from the source files, with a warning that
says so: the cache is a copy, never new data.
"""

from __future__ import annotations

import hashlib
import logging
from pathlib import Path
from typing import Callable, Sequence

from ..core.errors import DataError
from ..core.paths import cache_dir as default_cache_dir
from .model import FORMAT_VERSION, TouchDataset

log = logging.getLogger("touchbench.datasets")


def source_key(reader_version: str, files: Sequence[Path]) -> str:
    """SHA-256 over the reader version and each file's name and content hash."""
    h = hashlib.sha256(f"{reader_version}\0format{FORMAT_VERSION}".encode())
    for f in sorted(files, key=lambda p: (p.parent.name, p.name)):
        h.update(f"\0{f.parent.name}/{f.name}\0".encode())
        h.update(hashlib.sha256(f.read_bytes()).digest())
    return h.hexdigest()[:24]


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
    path = root / "datasets" / f"{name}-{source_key(reader_version, files)}.parquet"
    if path.is_file() and not refresh:
        try:
            return TouchDataset.from_parquet(path, verify=True)
        except DataError as e:
            log.warning("%s: the cached copy of %s is damaged (%s); rebuilt from its source files", path, name,
                        str(e).removeprefix(f"{path}: "))
    ds = build()
    ds.to_parquet(path)
    return ds
