"""The on-disk feature cache.

Features of a feature set whose ``fit`` learns nothing (``fold_dependent =
False``) do not depend on the fold: they are computed once per capture and
kept under ``touchbench.core.paths.cache_dir() / "features"``, keyed by

- the content hash of the (filtered) dataset,
- the feature set's name and parameters (canonical JSON),
- the feature set's identity: its source, the source of the helper modules
  it imports and the versions of the packages they import
  (:func:`touchbench.engine.identity.feature_set_identity`),
- the crop (``early`` scheme: the first N frames).

An entry is ``<key>.npy`` (the float64 matrix, one row per capture in the
dataset's order) and ``<key>.json`` (column names, seconds per capture it
took to compute, shape, size of the ``.npy`` file and a SHA-256 checksum of
the matrix), both written atomically, the JSON last: an entry without its
JSON is not an entry. An entry whose file is truncated or whose matrix does
not match its checksum is never loaded (:meth:`FeatureCache.problem` says
why; the run computes it again and says so in its notes). The checksum is
verified once per process and file. Rows are computed in chunks of a fixed
size, so the matrix is the same whatever the number of parallel jobs; the
sets of one pass (:meth:`FeatureCache.compute`) share a chunk's preprocessing and
each gets the rows it gives alone.
"""

from __future__ import annotations

import hashlib
import io
import json
import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from joblib import delayed
from threadpoolctl import threadpool_limits

from ..core.atomic import atomic_write_bytes
from ..core.hashing import file_state
from ..core.paths import cache_dir
from ..features.base import FeatureStack
from .backends import parallel, run_setup

__all__ = ["CHUNK", "FeatureCache", "crop_captures", "matrix_checksum"]

CHUNK = 32  # captures per chunk (fixed: results must not depend on --jobs)


def matrix_checksum(X: np.ndarray) -> str:
    """SHA-256 of a matrix's float64 values in C order, with its shape."""
    a = np.ascontiguousarray(X, dtype=np.float64)
    h = hashlib.sha256(f"{a.shape}".encode())
    h.update(memoryview(a).cast("B") if a.size else b"")
    return h.hexdigest()


def crop_captures(captures: Sequence[np.ndarray], n_frames: int | None) -> list[np.ndarray]:
    """The first ``n_frames`` frames of every capture (whole if shorter, or if None)."""
    if n_frames is None:
        return list(captures)
    return [c[:n_frames] for c in captures]


class FeatureCache:
    """Matrices of fold-independent features, one entry per (dataset, set, params, code, crop)."""

    #: entries whose checksum this process verified, with the files' signatures then
    _verified: dict[Path, tuple] = {}

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
        """Whether a complete entry exists (its files; :meth:`problem` checks their content)."""
        npy, js = self._paths(key)
        return npy.is_file() and js.is_file()

    def problem(self, key: str) -> str | None:
        """None for a sound entry, ``"missing"``, or what is wrong with it (truncated file, checksum...)."""
        npy, js = self._paths(key)
        if not (npy.is_file() and js.is_file()):
            return "missing"
        return self._check(npy, js)[0]

    def _check(self, npy: Path, js: Path) -> tuple[str | None, np.ndarray | None, dict[str, Any]]:
        try:
            sig = (file_state(npy), file_state(js))
            info = json.loads(js.read_text())
        except (OSError, ValueError):
            return "its description is unreadable", None, {}
        if not isinstance(info, dict) or "sha256" not in info or "npy_bytes" not in info:
            return "it has no checksum (written by an older touchbench)", None, info
        if sig[0][2] != info["npy_bytes"]:
            return f"its matrix file has {sig[0][2]} bytes instead of {info['npy_bytes']} (truncated or overwritten)", None, info
        try:
            X = np.load(npy, mmap_mode="r")
        except (OSError, ValueError) as e:
            return f"its matrix file is unreadable ({e})", None, info
        if X.ndim != 2 or X.shape[0] != info.get("n_rows") or X.dtype != np.float64:
            return f"its matrix has shape {X.shape} and type {X.dtype}, not {info.get('n_rows')} float64 rows", None, info
        if FeatureCache._verified.get(npy) != sig:
            if matrix_checksum(X) != info["sha256"]:
                return "its matrix does not match its checksum", None, info
            FeatureCache._verified[npy] = sig
        return None, X, info

    def load(self, key: str) -> tuple[np.ndarray, dict[str, Any]] | None:
        """``(matrix, info)`` (the matrix memory-mapped, read-only), or None when missing or damaged."""
        npy, js = self._paths(key)
        if not (npy.is_file() and js.is_file()):
            return None
        problem, X, info = self._check(npy, js)
        return None if problem is not None else (X, info)

    def store(self, key: str, X: np.ndarray, info: dict[str, Any]) -> None:
        npy, js = self._paths(key)
        X = np.ascontiguousarray(X, dtype=np.float64)
        buf = io.BytesIO()
        np.save(buf, X)
        data = buf.getvalue()
        atomic_write_bytes(npy, data)
        atomic_write_bytes(js, json.dumps({**info, "n_rows": int(X.shape[0]), "npy_bytes": len(data),
                                           "sha256": matrix_checksum(X)}, default=str).encode())

    def compute(
        self,
        entries: Sequence[tuple[str, Callable[[], Any], dict[str, Any]]],
        captures: Sequence[np.ndarray],
        *,
        jobs: int = 1,
        on_chunk: Callable[[int], None] | None = None,
        setup: Callable[[], None] | None = None,
    ) -> list[tuple[np.ndarray, dict[str, Any]]]:
        """Compute (chunked, ``jobs`` in parallel), store and return entries of the same captures.

        ``entries``: ``(key, make, info)``, ``make()`` building an unfitted feature set; each
        chunk fits every set on an empty-learning ``fit`` (the sets are fold-independent) and
        transforms the chunk through one :class:`touchbench.features.base.FeatureStack`, so a
        preprocessing the sets share (the Zhou sets' frame descriptors) is computed once per
        chunk; each set's matrix is the one it gives alone. ``seconds_per_capture`` is a set's
        transform time per capture, summed over chunks (CPU time per capture when chunks run in
        parallel), a shared preprocessing counted in every set that reads it.
        """
        chunks = [list(captures[i:i + CHUNK]) for i in range(0, len(captures), CHUNK)]
        makes = [make for _, make, _ in entries]
        if jobs == 1 or len(chunks) == 1:
            results = []
            for ch in chunks:
                results.append(_transform_chunk(makes, ch, setup))
                if on_chunk:
                    on_chunk(len(ch))
        else:

            results = []

            # never more workers than chunks
            par = parallel(min(jobs, len(chunks)))
            for ch, res in zip(chunks, par(delayed(_transform_chunk)(makes, ch, setup) for ch in chunks)):
                results.append(res)
                if on_chunk:
                    on_chunk(len(ch))
        out = []
        for j, (key, _, info) in enumerate(entries):
            X = np.vstack([r[j][0] for r in results]) if results else np.zeros((0, 0))
            seconds = float(sum(r[j][1] for r in results))
            entry = {
                **(info or {}),
                "columns": results[0][j][2] if results else [],
                "seconds_per_capture": seconds / max(1, len(captures)),
                "n_columns": int(X.shape[1]) if X.ndim == 2 else 0,
                "created": time.time(),
            }
            self.store(key, X, entry)
            loaded = self.load(key)
            assert loaded is not None
            out.append(loaded)
        return out


def _transform_chunk(makes: Sequence[Callable[[], Any]], captures: list[np.ndarray],
                     setup: Callable[[], None] | None = None) -> list[tuple[np.ndarray, float, list[str]]]:
    """Each set's ``(matrix, transform seconds, column names)`` of one chunk of captures."""
    run_setup(setup)

    with threadpool_limits(limits=1):
        sets = [make() for make in makes]
        for fs in sets:
            fs.fit(captures)
        seconds = [0.0] * len(sets)
        parts = FeatureStack(sets).transform_each(captures, seconds=seconds)
    out = []
    for fs, X, dt in zip(sets, parts, seconds):
        X = np.asarray(X, dtype=np.float64)
        try:
            cols = [str(c) for c in fs.get_feature_names_out()]
        except Exception:
            cols = [f"f{i}" for i in range(X.shape[1])]
        out.append((X, dt, cols))
    return out
