"""The registry index: what the listing commands print, kept in the user cache, so that a listing
answers without importing the registries' modules (and with them NumPy, pandas, scikit-learn).

A listing (``data list``, ``features list``, ``classifiers list``, ``plugins list``) asks
:func:`cached_rows` for its rows, giving the function that builds them from the registries. The
first time, that function runs (importing the registries) and its rows are written to the index,
one JSON file in the cache folder (:func:`touchbench.core.paths.cache_dir`, a file per Python
environment and touchbench source folder), under a *fingerprint* of everything the answer depends
on (:func:`fingerprint`):

- the index's own format and touchbench's version, the Python version;
- the size and modification time of every Python file of the touchbench package;
- every installed plugin's entry point, its distribution's name and version, and the size and
  modification time of the Python files of the package its module belongs to;
- the modification time of every folder on ``sys.path`` (installing or removing a package -- a
  plugin's dependency, an optional extra such as PyTorch -- changes its folder).

Later, a listing whose fingerprint matches reads its rows from the index; any change rebuilds
them. Rows are built from the registries instead (the index neither read nor written) when the
fingerprint cannot be taken (a plugin whose files cannot be found on ``sys.path``) or the
registries are already imported in this process (their entries are the answer, and may have been
changed since they were imported). Rows are never written when a plugin failed to load, so a
failing plugin is reported, and tried again, every time. An index that cannot be read (damaged,
another format) is ignored and rewritten; one that cannot be written is left as it is.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
from pathlib import Path
from typing import Any, Callable

from .errors import WriteError
from .hashing import canonical_json
from .paths import cache_dir
from .plugins import installed_plugins, plugin_status
from .version import __version__

__all__ = ["cached_rows", "fingerprint", "index_path"]

FORMAT = 1  # the layout of the index file; a new layout changes every fingerprint
PACKAGE_DIR = Path(__file__).resolve().parent.parent  # the touchbench package
log = logging.getLogger("touchbench")


def _python_files(root: Path) -> list[list]:
    """``[path relative to root, size, mtime in ns]`` of every Python file below ``root``, sorted."""
    out = []
    for folder, subfolders, files in os.walk(root):
        subfolders[:] = sorted(d for d in subfolders if d != "__pycache__")
        for name in sorted(files):
            if name.endswith(".py"):
                st = os.stat(os.path.join(folder, name))
                out.append([os.path.relpath(os.path.join(folder, name), root), st.st_size, st.st_mtime_ns])
    return out


def _path_folders() -> list[str]:
    return [p for p in sys.path if p and os.path.isdir(p)]


def _module_files(module: str) -> list[list] | None:
    """The Python files of the top-level package (or module) of ``module``, found on ``sys.path`` without
    importing it; None when it is not there as a plain folder or file."""
    top = module.split(".")[0]
    for folder in _path_folders():
        package, single = Path(folder, top), Path(folder, f"{top}.py")
        if (package / "__init__.py").is_file():
            return _python_files(package)
        if single.is_file():
            st = single.stat()
            return [[single.name, st.st_size, st.st_mtime_ns]]
    return None


def fingerprint() -> str | None:
    """A digest of everything the listings' answer depends on (the module's docstring lists it); None
    when it cannot be taken (a plugin's files not found): the index is then not used."""
    plugins = []
    for info, _ in installed_plugins():
        files = _module_files(info.module)
        if files is None:
            return None
        plugins.append([info.package, info.version, info.entry_point, info.module, files])
    parts = {"format": FORMAT, "touchbench": __version__, "python": sys.version, "plugins": plugins,
             "package": _python_files(PACKAGE_DIR),
             "path": [[p, os.stat(p).st_mtime_ns] for p in _path_folders()]}
    return hashlib.sha256(canonical_json(parts).encode()).hexdigest()


def index_path() -> Path:
    """The index file of this Python environment and touchbench source folder."""
    where = hashlib.sha256(f"{sys.prefix}\n{PACKAGE_DIR}".encode()).hexdigest()[:16]
    return cache_dir() / "registry-index" / f"{where}.json"


def _checksum(listings: Any) -> str:
    return hashlib.sha256(canonical_json(listings).encode()).hexdigest()


def _read(path: Path, digest: str) -> dict[str, Any]:
    """The listings stored under ``digest``; empty when the file is missing, stale or damaged (not
    JSON, or its listings no longer those it was written with)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # missing, unreadable, not JSON, not UTF-8
        return {}
    if not isinstance(data, dict) or data.get("fingerprint") != digest or not isinstance(data.get("listings"), dict):
        return {}
    if data.get("checksum") != _checksum(data["listings"]):
        return {}
    return data["listings"]


def _write(path: Path, digest: str, listings: dict[str, Any]) -> None:
    # here: core.atomic imports pandas and Arrow (its Parquet writer), which a listing read from the
    # index does without; rows are written after the registries have imported them anyway
    from .atomic import atomic_write_bytes

    text = json.dumps({"fingerprint": digest, "checksum": _checksum(listings), "listings": listings}, indent=1)
    try:
        atomic_write_bytes(path, text.encode("utf-8"))
    except WriteError as e:  # a read-only cache: the listing is answered all the same
        log.debug(f"the registry index was not written: {e}")


def _as_json(rows: list[dict]) -> list[dict]:
    return json.loads(json.dumps(rows, default=str))


def cached_rows(name: str, build: Callable[[], list[dict]], packages: tuple[str, ...]) -> list[dict]:
    """The rows of listing ``name``: from the index when it holds them under the current fingerprint,
    else ``build()`` (which imports the registries of ``packages``), then kept in the index.

    The rows are given as the index gives them back (through JSON: a tuple is a list, a key a string),
    wherever they come from, so the output never depends on the index. Imported already
    (any of ``packages`` in ``sys.modules``): ``build()``, the index neither read nor written.
    """
    if any(p in sys.modules for p in packages):
        return _as_json(build())
    digest = fingerprint()
    if digest is None:
        return _as_json(build())
    path = index_path()
    listings = _read(path, digest)
    rows = listings.get(name)
    if isinstance(rows, list) and all(isinstance(r, dict) for r in rows):
        return rows
    rows = _as_json(build())
    if all(error is None for _, error in plugin_status()):
        _write(path, digest, {**listings, name: rows})
    return rows
