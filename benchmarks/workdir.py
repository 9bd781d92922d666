"""Where a benchmark keeps the files it writes: ``cache_dir() / "benchmarks" / <name>``.

``<name>`` is the script's file name without ``bench_`` and ``.py``
(``bench_engine.py`` -> ``engine``); ``cache_dir()`` is touchbench's cache
(``$TOUCHBENCH_CACHE_DIR``, else the user's cache directory), so nothing is
written to a fixed system folder and the user's own results are not touched.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from touchbench.core.paths import cache_dir


def bench_dir(script: str) -> Path:
    """The folder of the benchmark ``script`` (pass ``__file__``), created if missing."""
    path = cache_dir() / "benchmarks" / Path(script).stem.removeprefix("bench_")
    path.mkdir(parents=True, exist_ok=True)
    return path


@contextmanager
def fresh_dir(script: str) -> Iterator[Path]:
    """A new, empty folder inside :func:`bench_dir` for one run, removed on exit."""
    path = Path(tempfile.mkdtemp(prefix="run-", dir=bench_dir(script)))
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)
