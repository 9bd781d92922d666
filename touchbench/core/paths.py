"""Where touchbench finds the shared data and keeps its caches.

- Shared data (real HAART): ``$TOUCHBENCH_DATA_DIR`` if set, else the first
  ``shared/data`` found beside the repository of a source checkout
  (``../shared/data``, as in CI) or beside the working directory. An
  installed package never looks beside its install location.
- Cache: ``$TOUCHBENCH_CACHE_DIR`` if set, else the user's cache directory
  (``~/.cache/touchbench`` on Linux).
- The user's references (``touchbench reference save``): ``$TOUCHBENCH_REFERENCE_DIR``
  if set, else ``reference/`` in the user's data directory
  (``~/.local/share/touchbench/reference`` on Linux, ``$XDG_DATA_HOME`` when set).
  Never the package's own folder: the shipped references there are read-only.
- Results: ``results/`` under the current directory (:data:`RESULTS_DIR`) holds
  every results folder the commands write by default; the *results root* of a
  results folder is the nearest folder of that name above it
  (:func:`results_root`).
"""

from __future__ import annotations

import os
from pathlib import Path

import platformdirs

from .errors import DataError

REPO_ROOT = Path(__file__).resolve().parent.parent.parent
#: the folder, under the current directory, that holds the results folders the commands write by default
RESULTS_DIR = "results"


def data_dir_candidates() -> list[Path]:
    """The folders touchbench looks in for the shared data when ``$TOUCHBENCH_DATA_DIR`` is not set, in
    order: ``shared/data`` beside the repository of a source checkout, then beside the working directory."""
    bases = [REPO_ROOT] if (REPO_ROOT / "pyproject.toml").is_file() else []  # a checkout, not an installed package
    if Path.cwd() not in bases:
        bases.append(Path.cwd())
    return [cand for base in bases for cand in (base.parent / "shared" / "data", base / "shared" / "data")]


def data_dir() -> Path:
    env = os.environ.get("TOUCHBENCH_DATA_DIR")
    if env:
        return Path(env)
    candidates = data_dir_candidates()
    return next((c for c in candidates if c.is_dir()), candidates[0])


def data_dir_help(dataset: str) -> str:
    """Where touchbench looked for the folder ``dataset`` of the shared data, and how to point it there."""
    env = os.environ.get("TOUCHBENCH_DATA_DIR")
    if env:
        looked = f"in {Path(env) / dataset} (TOUCHBENCH_DATA_DIR={env})"
    else:
        looked = ("in " + ", ".join(str(c / dataset) for c in data_dir_candidates())
                  + " (TOUCHBENCH_DATA_DIR is not set)")
    return (f"touchbench looked for the {dataset} data {looked}; set TOUCHBENCH_DATA_DIR to the folder that "
            f"holds {dataset}/, or give the {dataset} folder itself (data_dir, --data-dir)")


def raw_folder(dataset: str, given: str | Path | None, label: str | None = None) -> Path:
    """The folder of a shared dataset's recordings: ``given`` (a data_dir, --data-dir) or the data folder's
    ``dataset``, its ``raw/`` when it has one; a missing one is a DataError saying where touchbench looked
    (``label``: how the message names the dataset, default ``dataset``)."""
    base = Path(given) if given is not None else data_dir() / dataset
    raw = base / "raw" if (base / "raw").is_dir() else base
    if not raw.is_dir():
        name = label or dataset
        where = data_dir_help(dataset) if given is None else f"the data_dir given holds no {name} recordings"
        raise DataError(f"{name} raw folder not found: {where}", raw)
    return raw


def cache_dir() -> Path:
    env = os.environ.get("TOUCHBENCH_CACHE_DIR")
    return Path(env) if env else Path(platformdirs.user_cache_dir("touchbench"))


def user_reference_dir() -> Path:
    """The folder of the user's own references: ``$TOUCHBENCH_REFERENCE_DIR`` if set, else
    ``reference/`` in the user's data directory."""
    env = os.environ.get("TOUCHBENCH_REFERENCE_DIR")
    return Path(env) if env else Path(platformdirs.user_data_dir("touchbench")) / "reference"


def results_root(folder: str | Path) -> Path | None:
    """The results root of results folder ``folder``: the nearest folder named :data:`RESULTS_DIR`
    above it (``folder`` made absolute first); None when there is none."""
    for parent in Path(os.path.abspath(folder)).parents:
        if parent.name == RESULTS_DIR:
            return parent
    return None
