"""Where touchbench finds the shared data and keeps its caches.

- Shared data (real HAART): ``$TOUCHBENCH_DATA_DIR`` if set, else the first
  ``shared/data`` found beside the repository or the working directory
  (``../shared/data`` from a checkout, as in CI).
- Cache: ``$TOUCHBENCH_CACHE_DIR`` if set, else the user's cache directory
  (``~/.cache/touchbench`` on Linux).
- Results: ``results/`` under the current directory (:data:`RESULTS_DIR`) holds
  every results folder the commands write by default; the *results root* of a
  results folder is the nearest folder of that name above it
  (:func:`results_root`).
"""

from __future__ import annotations

import os
from pathlib import Path

import platformdirs

REPO_ROOT = Path(__file__).resolve().parent.parent.parent
#: the folder, under the current directory, that holds the results folders the commands write by default
RESULTS_DIR = "results"


def data_dir() -> Path:
    env = os.environ.get("TOUCHBENCH_DATA_DIR")
    if env:
        return Path(env)
    for base in (REPO_ROOT, Path.cwd()):
        for cand in (base.parent / "shared" / "data", base / "shared" / "data"):
            if cand.is_dir():
                return cand
    return REPO_ROOT.parent / "shared" / "data"


def cache_dir() -> Path:
    env = os.environ.get("TOUCHBENCH_CACHE_DIR")
    return Path(env) if env else Path(platformdirs.user_cache_dir("touchbench"))


def results_root(folder: str | Path) -> Path | None:
    """The results root of results folder ``folder``: the nearest folder named :data:`RESULTS_DIR`
    above it (``folder`` made absolute first); None when there is none."""
    for parent in Path(os.path.abspath(folder)).parents:
        if parent.name == RESULTS_DIR:
            return parent
    return None
