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

A capture's row depends on nothing but the capture, the set (name, parameters,
code) and the sensor, so rows are also shared between datasets: an entry
computed with a *family* (:meth:`FeatureCache.family`: the set's name,
parameters, code and the sensor, without the dataset) keeps the SHA-256 of each
of its captures (:func:`capture_digest`: the values in their own type, with
their shape) in ``rows/<family>/<key>.rows``, its checksum in the entry's
JSON. An entry missing for another selection of the same captures (a table
on the training split after one on the whole dataset, a crop that leaves
short captures whole) takes the rows it finds in the family's sound entries
and computes only the captures none of them holds.
"""

from __future__ import annotations

import hashlib
import io
import json
import time
from dataclasses import dataclass
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

__all__ = ["CHUNK", "FeatureCache", "capture_digest", "crop_captures", "matrix_checksum"]

CHUNK = 32  # captures per chunk (fixed: results must not depend on --jobs)


def matrix_checksum(X: np.ndarray) -> str:
    """SHA-256 of a matrix's float64 values in C order, with its shape."""
    a = np.ascontiguousarray(X, dtype=np.float64)
    h = hashlib.sha256(f"{a.shape}".encode())
    h.update(memoryview(a).cast("B") if a.size else b"")
    return h.hexdigest()


def capture_digest(capture: np.ndarray) -> bytes:
    """SHA-256 (32 bytes) of a capture as a feature set reads it: its values in their own type, with
    the type and the shape (a uint16 capture and its float copy are two captures here)."""
    a = np.ascontiguousarray(capture)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(memoryview(a).cast("B") if a.size else b"")
    return h.digest()


@dataclass
class _Found:
    """The rows of one entry found in other entries of its family: the matrix (rows where ``found``),
    and each found row's seconds per capture as its source recorded it."""

    X: np.ndarray | None
    found: np.ndarray
    seconds: np.ndarray
    columns: list[str]

    @classmethod
    def none(cls, n: int) -> "_Found":
        return cls(None, np.zeros(n, dtype=bool), np.zeros(n), [])


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

    @staticmethod
    def family(name: str, params: dict[str, Any], version: str, sensor: dict[str, Any] | None) -> str:
        """What a capture's row depends on besides the capture: the set's name, parameters and code,
        and the sensor (an entry's key adds the dataset and the crop)."""
        blob = json.dumps({"name": name, "params": params, "code": version, "sensor": sensor},
                          sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()[:32]

    def _rows_path(self, family: str, key: str) -> Path:
        return self.root / "rows" / family / f"{key}.rows"

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

    def store(self, key: str, X: np.ndarray, info: dict[str, Any], rows: Sequence[bytes] | None = None) -> None:
        """Write an entry; ``rows`` (one :func:`capture_digest` per row) makes its rows findable by
        other entries of ``info["family"]``."""
        npy, js = self._paths(key)
        X = np.ascontiguousarray(X, dtype=np.float64)
        buf = io.BytesIO()
        np.save(buf, X)
        data = buf.getvalue()
        atomic_write_bytes(npy, data)
        extra: dict[str, Any] = {}
        if rows is not None and info.get("family"):
            blob = b"".join(rows)
            atomic_write_bytes(self._rows_path(info["family"], key), blob)
            extra["rows_sha256"] = hashlib.sha256(blob).hexdigest()
        atomic_write_bytes(js, json.dumps({**info, **extra, "n_rows": int(X.shape[0]), "npy_bytes": len(data),
                                           "sha256": matrix_checksum(X)}, default=str).encode())

    def _source(self, family: str, path: Path) -> tuple[np.ndarray, dict[str, Any], list[bytes]] | None:
        """A sound entry of ``family`` (its rows file at ``path``): matrix, info and row digests;
        None when damaged, of another family or its rows file does not match its checksum."""
        got = self.load(path.name[:-len(".rows")])
        if got is None or got[1].get("family") != family:
            return None
        M, info = got
        try:
            blob = path.read_bytes()
        except OSError:
            return None
        if len(blob) != 32 * M.shape[0] or hashlib.sha256(blob).hexdigest() != info.get("rows_sha256"):
            return None
        return M, info, [blob[i:i + 32] for i in range(0, len(blob), 32)]

    def found_rows(self, family: str, digests: Sequence[bytes], skip: str | None = None) -> _Found:
        """The rows of captures ``digests`` that sound entries of ``family`` (other than ``skip``) hold."""
        n = len(digests)
        out = _Found.none(n)
        where: dict[bytes, list[int]] = {}
        for i, d in enumerate(digests):
            where.setdefault(d, []).append(i)
        folder = self.root / "rows" / family
        for path in sorted(folder.glob("*.rows")) if folder.is_dir() else []:
            if out.found.all():
                break
            src = None if path.name == f"{skip}.rows" else self._source(family, path)
            if src is None or (out.X is not None and src[0].shape[1] != out.X.shape[1]):
                continue
            M, info, rows = src
            dst, take = [], []
            for r, d in enumerate(rows):
                for i in where.get(d, ()):
                    if not out.found[i]:
                        out.found[i] = True
                        dst.append(i)
                        take.append(r)
            if dst:
                if out.X is None:
                    out.X = np.empty((n, M.shape[1]), dtype=np.float64)
                    out.columns = list(info.get("columns") or [])
                out.X[dst] = M[take]
                out.seconds[dst] = float(info.get("seconds_per_capture", 0.0))
        return out

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

        An entry whose ``info`` names its ``family`` takes the rows other entries of the family
        hold (:meth:`found_rows`; ``reused_rows`` in its info counts them, a reused row's seconds
        its source's); only the captures some entry lacks are computed, in chunks of their own.
        """
        n = len(captures)
        digests = ([capture_digest(c) for c in captures]
                   if any((info or {}).get("family") for _, _, info in entries) else None)
        found = [self.found_rows(info["family"], digests, skip=key) if digests is not None and (info or {}).get("family")
                 else _Found.none(n) for key, _, info in entries]
        missing = np.flatnonzero(~np.logical_and.reduce([f.found for f in found])) if entries else np.arange(n)
        todo = [j for j, f in enumerate(found) if not f.found.all()]
        if on_chunk and n > len(missing):
            on_chunk(n - len(missing))
        computed = dict(zip(todo, _transform_all([entries[j][1] for j in todo], [captures[i] for i in missing],
                                                 jobs=jobs, on_chunk=on_chunk, setup=setup)))
        out = []
        for j, (key, _, info) in enumerate(entries):
            X, seconds, cols, reused = _assemble(found[j], computed.get(j), missing, n)
            entry = {
                **(info or {}),
                "columns": cols,
                "seconds_per_capture": seconds / max(1, n),
                "n_columns": int(X.shape[1]) if X.ndim == 2 else 0,
                "reused_rows": reused,
                "created": time.time(),
            }
            self.store(key, X, entry, rows=digests)
            loaded = self.load(key)
            assert loaded is not None
            out.append(loaded)
        return out


def _assemble(found: _Found, computed: tuple[np.ndarray, float, list[str]] | None, missing: np.ndarray,
              n: int) -> tuple[np.ndarray, float, list[str], int]:
    """One entry's matrix from its found rows and the rows computed for the captures ``missing``:
    ``(matrix, seconds, columns, rows reused)``."""
    if computed is None:  # every row found
        assert found.X is not None or n == 0
        return (found.X if found.X is not None else np.zeros((0, 0)), float(found.seconds.sum()),
                found.columns, n)
    Xc, seconds, cols = computed
    if found.X is None:
        if len(missing) == n:
            return Xc, seconds, cols, 0
        found.X = np.empty((n, Xc.shape[1]), dtype=np.float64)
    X = found.X
    X[missing] = Xc
    used = np.ones(n, dtype=bool)
    used[missing] = False
    return X, seconds + float(found.seconds[used].sum()), cols, int(used.sum())


def _transform_all(makes: Sequence[Callable[[], Any]], captures: Sequence[np.ndarray], *, jobs: int,
                   on_chunk: Callable[[int], None] | None,
                   setup: Callable[[], None] | None) -> list[tuple[np.ndarray, float, list[str]]]:
    """Each set's ``(matrix, seconds, columns)`` of ``captures``, computed in chunks of ``CHUNK``
    (``jobs`` in parallel; nothing to compute when there are no sets)."""
    if not makes:
        return []
    chunks = [list(captures[i:i + CHUNK]) for i in range(0, len(captures), CHUNK)]
    if jobs == 1 or len(chunks) <= 1:
        results = []
        for ch in chunks:
            results.append(_transform_chunk(makes, ch, setup))
            if on_chunk:
                on_chunk(len(ch))
    else:
        results = []
        par = parallel(min(jobs, len(chunks)))  # never more workers than chunks
        for ch, res in zip(chunks, par(delayed(_transform_chunk)(makes, ch, setup) for ch in chunks)):
            results.append(res)
            if on_chunk:
                on_chunk(len(ch))
    out = []
    for j in range(len(makes)):
        X = np.vstack([r[j][0] for r in results]) if results else np.zeros((0, 0))
        out.append((X, float(sum(r[j][1] for r in results)), results[0][j][2] if results else []))
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
