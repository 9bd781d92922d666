"""The on-disk feature cache.

Features of a feature set whose ``fit`` learns nothing (``fold_dependent =
False``) do not depend on the fold: they are computed once per capture and
kept under ``touchbench.core.paths.cache_dir() / "features"``, keyed by

- the content hash of the (filtered) dataset,
- the feature set's name and parameters (canonical JSON),
- the code version: touchbench's version and a hash of the source files the
  feature set comes from (its module, its bases' modules and the touchbench
  helpers they import; see :func:`code_version`),
- the crop (``early`` scheme: the first N frames).

An entry is ``<key>.npy`` (the float64 matrix, one row per capture in the
dataset's order) and ``<key>.json`` (column names, seconds per capture it
took to compute, shape), both written atomically, the JSON last: an entry
without its JSON is not an entry. Rows are computed in chunks of a fixed
size, so the matrix is the same whatever the number of parallel jobs.
"""

from __future__ import annotations

import hashlib
import inspect
import io
import json
import time
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from .. import __version__
from ..core.atomic import atomic_write_bytes
from ..core.paths import cache_dir
from .backends import run_setup, supports_generator

__all__ = ["CHUNK", "FeatureCache", "code_version", "crop_captures"]

CHUNK = 32  # captures per chunk (fixed: results must not depend on --jobs)


@lru_cache(maxsize=None)
def _file_hash(path: str, mtime_ns: int) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def _touchbench_file(obj: Any) -> str | None:
    try:
        f = inspect.getsourcefile(obj)
    except TypeError:
        return None
    return f if f and "touchbench" in Path(f).parts else None


def source_files(cls: type) -> list[str]:
    """Source files a feature set's output depends on, as far as we can tell.

    The modules of the class and of its bases, and the touchbench modules
    their module-level names come from (helpers imported with ``from .x
    import f`` or ``from . import x``), one level deep.
    """
    files: set[str] = set()
    for klass in getattr(cls, "__mro__", (cls,)):
        f = _touchbench_file(klass)
        if f is None:
            continue
        files.add(f)
        module = inspect.getmodule(klass)
        for value in vars(module).values() if module is not None else ():
            if inspect.ismodule(value) or inspect.isclass(value) or inspect.isfunction(value):
                g = _touchbench_file(value)
                if g is not None:
                    files.add(g)
    return sorted(files)


def code_version(cls: Any) -> str:
    """touchbench's version + a hash of :func:`source_files` of ``cls``.

    Editing a feature set's code (or a helper it imports) changes the code
    version, so its cached features and the tasks that use them are recomputed.
    """
    h = hashlib.sha256()
    for f in source_files(cls):
        h.update(Path(f).name.encode() + b"\0" + _file_hash(f, Path(f).stat().st_mtime_ns).encode())
    return f"{__version__}-{h.hexdigest()[:16]}"


def crop_captures(captures: Sequence[np.ndarray], n_frames: int | None) -> list[np.ndarray]:
    """The first ``n_frames`` frames of every capture (whole if shorter, or if None)."""
    if n_frames is None:
        return list(captures)
    return [c[:n_frames] for c in captures]


class FeatureCache:
    """Matrices of fold-independent features, one entry per (dataset, set, params, code, crop)."""

    def __init__(self, root: str | Path | None = None):
        self.root = Path(root) if root is not None else cache_dir() / "features"

    @staticmethod
    def key(dataset_hash: str, name: str, params: dict[str, Any], version: str, crop: int | None) -> str:
        blob = json.dumps(
            {"dataset": dataset_hash, "name": name, "params": params, "code": version, "crop": crop},
            sort_keys=True, default=str,
        )
        return hashlib.sha256(blob.encode()).hexdigest()[:32]

    def _paths(self, key: str) -> tuple[Path, Path]:
        return self.root / f"{key}.npy", self.root / f"{key}.json"

    def has(self, key: str) -> bool:
        npy, js = self._paths(key)
        return npy.is_file() and js.is_file()

    def load(self, key: str) -> tuple[np.ndarray, dict[str, Any]] | None:
        """``(matrix, info)`` (the matrix memory-mapped, read-only) or None."""
        npy, js = self._paths(key)
        if not (npy.is_file() and js.is_file()):
            return None
        try:
            info = json.loads(js.read_text())
            X = np.load(npy, mmap_mode="r")
        except (OSError, ValueError, json.JSONDecodeError):
            return None
        if X.shape[0] != info.get("n_rows"):
            return None
        return X, info

    def store(self, key: str, X: np.ndarray, info: dict[str, Any]) -> None:
        npy, js = self._paths(key)
        buf = io.BytesIO()
        np.save(buf, np.ascontiguousarray(X, dtype=np.float64))
        atomic_write_bytes(npy, buf.getvalue())
        atomic_write_bytes(js, json.dumps({**info, "n_rows": int(X.shape[0])}, default=str).encode())

    def compute(
        self,
        key: str,
        make: Callable[[], Any],
        captures: Sequence[np.ndarray],
        *,
        jobs: int = 1,
        info: dict[str, Any] | None = None,
        on_chunk: Callable[[int], None] | None = None,
        setup: Callable[[], None] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Compute (chunked, ``jobs`` in parallel), store and return an entry.

        ``make()`` builds an unfitted feature set; each chunk fits it on an
        empty-learning ``fit`` (the set is fold-independent) and transforms.
        ``seconds_per_capture`` is the transform time per capture, summed
        over chunks (CPU time per capture when chunks run in parallel).
        """
        chunks = [list(captures[i:i + CHUNK]) for i in range(0, len(captures), CHUNK)]
        if jobs == 1 or len(chunks) == 1:
            results = []
            for ch in chunks:
                results.append(_transform_chunk(make, ch, setup))
                if on_chunk:
                    on_chunk(len(ch))
        else:

            results = []

            par = Parallel(n_jobs=jobs, return_as="generator" if supports_generator() else "list")
            for ch, res in zip(chunks, par(delayed(_transform_chunk)(make, ch, setup) for ch in chunks)):
                results.append(res)
                if on_chunk:
                    on_chunk(len(ch))
        X = np.vstack([r[0] for r in results]) if results else np.zeros((0, 0))
        seconds = float(sum(r[1] for r in results))
        columns = results[0][2] if results else []
        entry = {
            **(info or {}),
            "columns": columns,
            "seconds_per_capture": seconds / max(1, len(captures)),
            "n_columns": int(X.shape[1]) if X.ndim == 2 else 0,
            "created": time.time(),
        }
        self.store(key, X, entry)
        loaded = self.load(key)
        assert loaded is not None
        return loaded


def _transform_chunk(make: Callable[[], Any], captures: list[np.ndarray],
                     setup: Callable[[], None] | None = None) -> tuple[np.ndarray, float, list[str]]:
    run_setup(setup)

    with threadpool_limits(limits=1):
        fs = make()
        fs.fit(captures)
        t0 = time.perf_counter()
        X = np.asarray(fs.transform(captures), dtype=np.float64)
        dt = time.perf_counter() - t0
    try:
        cols = [str(c) for c in fs.get_feature_names_out()]
    except Exception:
        cols = [f"f{i}" for i in range(X.shape[1])]
    return X, dt, cols
