"""The touch dataset model: :class:`SensorSpec` and :class:`TouchDataset`.

A capture is one gesture performance: a ``(T, H, W)`` array of frames, frames
first, in the sensor's native dtype. Sensors that are not grids (Flagg's fur
sensor: channels x, y, pressure, fur) are stored as ``H = 1`` and
``W = len(channels)`` with the channel names in the spec, so every capture in
touchbench is three-dimensional and feature code has one shape to handle.

A dataset is stored as one Parquet file: one row per capture with the
metadata columns, ``n_frames`` and the flattened frames as a list column in
the native dtype; the sensor, name and dtype live in the schema metadata.
Saving and loading keeps the same arrays, dtypes and content hash.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from ..core.atomic import atomic_path
from ..core.errors import DataError, TouchbenchError
from .formats import register_format

FORMAT_VERSION = 2


class DatasetChangedWarning(UserWarning):
    """A dataset file's content no longer matches the hash it was written with (edited in place)."""

REQUIRED_META = ("capture_id", "subject", "gesture")
#: optional metadata column: each capture's frame times in ms (one increasing value per frame)
TIME_COLUMN = "time_ms"
#: optional metadata column: the frame times as recorded, where the frames were resampled
RECORDED_TIME_COLUMN = "recorded_time_ms"


@dataclass(frozen=True)
class SensorSpec:
    """What a sensor is: grid, frame rate, value range and polarity.

    ``grid`` is ``(H, W)``; for a channel sensor it is ``(1, C)`` and
    ``channels`` names the C channels. ``value_range`` is the inclusive range
    of valid values (the ADC range); ``higher_is_more_pressure`` says the
    polarity of the stored values (touchbench readers convert to True).
    """

    name: str
    grid: tuple[int, int]
    frame_rate: float
    value_range: tuple[float, float] = (0.0, 1023.0)
    higher_is_more_pressure: bool = True
    channels: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "grid", tuple(int(g) for g in self.grid))
        object.__setattr__(self, "value_range", tuple(float(v) for v in self.value_range))
        if self.channels is not None:
            object.__setattr__(self, "channels", tuple(self.channels))
        h, w = self.grid
        if h < 1 or w < 1:
            raise ValueError(f"sensor {self.name!r}: grid must be at least 1 x 1, got {self.grid}")
        if not 0 < self.frame_rate < math.inf:
            raise ValueError(f"sensor {self.name!r}: frame_rate must be positive (and finite), got {self.frame_rate!r}")
        lo, hi = self.value_range
        if not (lo < hi and math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(f"sensor {self.name!r}: value_range must have low < high (both finite), got {lo!r}..{hi!r}")
        if self.channels is not None and (h != 1 or w != len(self.channels)):
            raise ValueError(f"sensor {self.name!r}: a channel sensor has grid (1, n_channels)")

    @property
    def n_cells(self) -> int:
        return self.grid[0] * self.grid[1]

    def describe(self) -> str:
        """``'name' (H x W at R Hz)`` (channel sensors: ``1 x C channels``), for messages."""
        h, w = self.grid
        what = f"{h} x {w} channels" if self.channels is not None else f"{h} x {w}"
        return f"{self.name!r} ({what} at {self.frame_rate:g} Hz)"

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["grid"] = list(self.grid)
        d["value_range"] = list(self.value_range)
        d["channels"] = None if self.channels is None else list(self.channels)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "SensorSpec":
        d = dict(d)
        d["grid"] = tuple(d["grid"])
        d["value_range"] = tuple(d["value_range"])
        if d.get("channels") is not None:
            d["channels"] = tuple(d["channels"])
        return cls(**d)


def _hash_meta(h: "hashlib._Hash", meta: pd.DataFrame) -> None:
    """Feed a canonical form of the metadata table into ``h``.

    Numeric and boolean columns are hashed as their float64/int64 bytes,
    everything else as the JSON list of its ``str`` values (missing values
    as null), so the hash does not depend on pandas' choice between object
    and string dtypes. A cell holding a sequence (a per-capture array such
    as ``time_ms``: a list in memory, a numpy array once read from Parquet)
    is hashed as the JSON text of its values, every value, whichever form.
    """
    for col in meta.columns:
        s = meta[col]
        h.update(b"\x00col\x00" + str(col).encode())
        if pd.api.types.is_bool_dtype(s):
            h.update(b"bool" + s.to_numpy(dtype=np.int8).tobytes())
        elif pd.api.types.is_integer_dtype(s) and not s.isna().any():
            h.update(b"int" + s.to_numpy(dtype=np.int64).tobytes())
        elif pd.api.types.is_float_dtype(s):
            h.update(b"float" + s.to_numpy(dtype=np.float64).tobytes())
        else:
            h.update(b"str" + json.dumps([_cell_text(v) for v in s.tolist()]).encode())


def _cell_text(v: Any) -> str | None:
    """A metadata cell as hashed text: None for missing, JSON for a sequence, else ``str``."""
    if isinstance(v, (list, tuple, np.ndarray)):
        return json.dumps(np.asarray(v).tolist())
    if v is None or (isinstance(v, float) and np.isnan(v)):
        return None
    return str(v)


#: frame rates within this relative difference are the same sensor (clock drift, a rate written
#: rounded); beyond it, features measured in frames or seconds no longer mean what was learned
FRAME_RATE_TOLERANCE = 0.01


def sensor_differences(reference: SensorSpec, data: SensorSpec, names: tuple[str, str] = ("model", "data")) -> list[str]:
    """The fields in which ``data`` differs from ``reference`` (the name is not compared; frame
    rates within ``FRAME_RATE_TOLERANCE``, 1 %, are the same), each as ``field: NAME1 a, NAME2 b``."""
    out = []
    for f in ("grid", "channels", "frame_rate", "value_range", "higher_is_more_pressure"):
        a, b = getattr(reference, f), getattr(data, f)
        if f == "frame_rate" and a and b and abs(float(a) - float(b)) <= FRAME_RATE_TOLERANCE * float(a):
            continue
        if a != b:
            out.append(f"{f}: {names[0]} {a!r}, {names[1]} {b!r}")
    return out


def frames_checksum(capture: np.ndarray) -> str:
    """SHA-256 of a capture's frames as float64 values with their shape: the same recording read
    by two readers (uint16 or float) gives the same checksum."""
    a = np.ascontiguousarray(capture, dtype=np.float64)
    return hashlib.sha256(f"{a.shape}".encode() + a.tobytes()).hexdigest()


def labelled_checksum(capture: np.ndarray, label: Any) -> str:
    """SHA-256 of a capture's shape, label (as text) and frames as float64 values: one item of a
    test set's hash (:func:`touchbench.results.ledger.test_set_hash`)."""
    a = np.ascontiguousarray(capture, dtype=np.float64)
    return hashlib.sha256(f"{np.shape(capture)}|{label}".encode() + a.tobytes()).hexdigest()


@dataclass
class TouchDataset:
    """Ragged captures + a metadata table + a sensor spec + a content hash.

    ``captures[i]`` is a ``(T_i, H, W)`` array; ``meta.iloc[i]`` describes it
    and has at least ``capture_id`` (unique), ``subject`` and ``gesture``.
    Any other column (substrate, cover, variant, session, group, split...)
    is kept as given. The content hash covers every value, dtype, shape,
    label and the sensor spec, not the dataset's name.
    """

    name: str
    captures: list[np.ndarray]
    meta: pd.DataFrame
    sensor: SensorSpec
    _hash: str | None = field(default=None, repr=False, compare=False)
    #: where the data came from and what the reader did (placeholders found,
    #: window used...); saved with the dataset, not part of the content hash.
    provenance: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)
    #: metadata column -> :func:`labelled_checksum` of every capture with that column as its label
    #: (computed once per column; the dataset cache keeps them with its entry)
    _labelled: dict[str, list[str]] = field(default_factory=dict, repr=False, compare=False)
    #: called with (column, checksums) when a column's checksums are computed (the dataset cache's store)
    _on_labelled: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.meta = self.meta.reset_index(drop=True)
        if len(self.captures) != len(self.meta):
            raise ValueError(f"dataset {self.name!r}: {len(self.captures)} captures but {len(self.meta)} metadata rows")
        missing = [c for c in REQUIRED_META if c not in self.meta.columns]
        if missing:
            raise ValueError(f"dataset {self.name!r}: metadata lacks column(s) {missing}")
        if self.meta["capture_id"].duplicated().any():
            dup = self.meta["capture_id"][self.meta["capture_id"].duplicated()].iloc[0]
            raise ValueError(f"dataset {self.name!r}: capture_id {dup!r} occurs more than once")
        h, w = self.sensor.grid
        for i, c in enumerate(self.captures):
            if c.ndim != 3 or c.shape[1:] != (h, w):
                raise ValueError(
                    f"dataset {self.name!r}: capture {self.meta['capture_id'].iloc[i]!r} has shape "
                    f"{c.shape}, sensor {self.sensor.name!r} expects (T, {h}, {w})"
                )
        if TIME_COLUMN in self.meta.columns:
            for i, (c, t) in enumerate(zip(self.captures, self.meta[TIME_COLUMN].tolist())):
                t = np.asarray(t, dtype=np.float64)
                if t.shape != (c.shape[0],) or (t.size > 1 and not (np.diff(t) > 0).all()):
                    raise ValueError(
                        f"dataset {self.name!r}: capture {self.meta['capture_id'].iloc[i]!r}: {TIME_COLUMN} must hold one "
                        f"increasing time per frame ({c.shape[0]} frames, got {t.size} values)"
                    )

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        return len(self.captures)

    @property
    def n_frames(self) -> np.ndarray:
        return np.array([c.shape[0] for c in self.captures], dtype=np.int64)

    @property
    def labels(self) -> np.ndarray:
        return self.meta["gesture"].to_numpy()

    @property
    def content_hash(self) -> str:
        if self._hash is None:
            h = hashlib.sha256()
            h.update(json.dumps(self.sensor.to_dict(), sort_keys=True).encode())
            _hash_meta(h, self.meta)
            for c in self.captures:
                a = np.ascontiguousarray(c)
                h.update(f"{a.dtype.str}{a.shape}".encode())
                h.update(a.tobytes())
            self._hash = h.hexdigest()
        return self._hash

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the cache's callback (a closure): a copy elsewhere keeps nothing."""
        return {**self.__dict__, "_on_labelled": None}

    def labelled_checksums(self, column: str) -> list[str]:
        """:func:`labelled_checksum` of every capture, its label the metadata ``column`` as text
        (computed once per column and dataset)."""
        if column not in self._labelled:
            labels = self.meta[column].astype(str).to_numpy()
            self._labelled[column] = [labelled_checksum(c, y) for c, y in zip(self.captures, labels)]
            if self._on_labelled is not None:
                self._on_labelled(column, self._labelled[column])
        return self._labelled[column]

    def subset(self, index: Iterable[int] | np.ndarray, name: str | None = None) -> "TouchDataset":
        """The captures at ``index`` (positions), in that order (the provenance kept)."""
        idx = np.asarray(list(index) if not isinstance(index, np.ndarray) else index)
        if idx.dtype == bool:
            idx = np.flatnonzero(idx)
        return TouchDataset(
            name=name or self.name,
            captures=[self.captures[i] for i in idx],
            meta=self.meta.iloc[idx].reset_index(drop=True),
            sensor=self.sensor,
            provenance=self.provenance,
        )

    def with_name(self, name: str) -> "TouchDataset":
        return TouchDataset(name, self.captures, self.meta, self.sensor, self._hash, self.provenance, self._labelled)

    # ------------------------------------------------------------- parquet io
    def to_parquet(self, path: str | Path) -> Path:
        """Write atomically (temporary file + rename): no half-written file."""
        path = Path(path)
        dtypes = {c.dtype.str for c in self.captures}
        if len(dtypes) > 1:
            raise ValueError(f"dataset {self.name!r}: captures have mixed dtypes {sorted(dtypes)}")
        dtype = np.dtype(dtypes.pop()) if dtypes else np.dtype(np.float64)
        n = np.array([c.shape[0] for c in self.captures], dtype=np.int64)
        # One binary blob per capture in native byte order; dtype and grid are
        # in the schema metadata. Read back with one frombuffer (fast loads).
        frames = pa.array([np.ascontiguousarray(c, dtype=dtype).tobytes() for c in self.captures], type=pa.large_binary())
        table = pa.Table.from_pandas(self.meta, preserve_index=False)
        table = table.append_column("n_frames", pa.array(n)).append_column("frames", frames)
        info = {
            "format_version": FORMAT_VERSION,
            "name": self.name,
            "sensor": self.sensor.to_dict(),
            "dtype": dtype.str,
            "content_hash": self.content_hash,
            "provenance": self.provenance,
        }
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), b"touchbench": json.dumps(info).encode()})
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp, compression="zstd", use_dictionary=[c for c in table.column_names if c != "frames"])
        return path

    @classmethod
    def from_parquet(cls, path: str | Path, verify: bool = False) -> "TouchDataset":
        """Load a dataset written by :meth:`to_parquet`.

        The content hash is recomputed from what the file holds, never taken
        from the file: a file edited in place is new data, with a new hash
        (so runs on it recompute their tasks and features), and a
        :class:`DatasetChangedWarning` says that the file changed since it
        was written. ``verify=True`` refuses such a file instead
        (:class:`touchbench.core.errors.DataError`).
        """
        path = Path(path)
        if not path.exists():
            raise DataError("no such dataset file", path)
        try:
            table = pq.read_table(path)
        except Exception as e:  # pyarrow raises several types for a bad file
            raise DataError(f"not a readable Parquet file ({e})", path) from None
        return cls.from_table(table, path, verify=verify)

    @classmethod
    def from_table(cls, table: pa.Table, path: str | Path, verify: bool = False,
                   content_hash: str | None = None) -> "TouchDataset":
        """The dataset of a table :meth:`to_parquet` wrote, read from ``path`` (see
        :meth:`from_parquet`). ``content_hash``: the hash this table's content was found to have
        (the dataset cache's, for a file it checked is the one it hashed), used instead of hashing
        the content again."""
        path = Path(path)
        info = _table_info(table, path)
        ds = _dataset_of(cls, table, info, path)
        if content_hash is not None and content_hash == info.get("content_hash"):
            ds._hash = content_hash
        if ds.content_hash != info.get("content_hash"):
            if verify:
                raise DataError("content does not match the hash it was saved with (file corrupted or edited)", path)
            warnings.warn(DatasetChangedWarning(
                f"{path}: the content changed since touchbench wrote this file (it no longer matches the hash "
                "saved with it); it is treated as new data: results and cached features of the old content are not reused"),
                stacklevel=3)
        return ds

    # ----------------------------------------------------------------- summary
    def info(self) -> dict[str, Any]:
        """Counts and ranges for ``touchbench data info``."""
        n = self.n_frames
        lo = min((float(c.min()) for c in self.captures if c.size), default=float("nan"))
        hi = max((float(c.max()) for c in self.captures if c.size), default=float("nan"))
        out: dict[str, Any] = {
            "name": self.name,
            "captures": len(self),
            "sensor": self.sensor.to_dict(),
            "dtype": self.captures[0].dtype.name if self.captures else None,
            "subjects": int(self.meta["subject"].nunique()),
            "gestures": int(self.meta["gesture"].nunique()),
            "frames_per_capture": {"min": int(n.min()) if len(n) else 0, "median": float(np.median(n)) if len(n) else 0.0, "max": int(n.max()) if len(n) else 0},
            "value_range": [lo, hi],
            "content_hash": self.content_hash,
            "by_subject": {str(k): int(v) for k, v in self.meta["subject"].value_counts().sort_index().items()},
            "by_gesture": {str(k): int(v) for k, v in self.meta["gesture"].value_counts().sort_index().items()},
        }
        if TIME_COLUMN in self.meta.columns:
            out["time_steps_ms"] = time_step_summary(self.meta[TIME_COLUMN].tolist())
        if RECORDED_TIME_COLUMN in self.meta.columns:
            out["recorded_time_steps_ms"] = time_step_summary(self.meta[RECORDED_TIME_COLUMN].tolist())
        if "split" in self.meta.columns:
            out["by_split"] = {str(k): int(v) for k, v in self.meta["split"].value_counts().sort_index().items()}
        out["streams"] = self._streams_info(n)
        if self.provenance:
            out["provenance"] = self.provenance
        return out

    def _streams_info(self, n: np.ndarray) -> dict[str, Any]:
        """What a stream evaluation replays of this dataset: its recordings labelled frame by frame
        (``recording`` and ``start_frame`` columns), or streams spliced from its cut captures."""
        if {"recording", "start_frame"} <= set(self.meta.columns):
            return {"source": "recorded", "recordings": int(self.meta["recording"].nunique()),
                    "seconds": float(n.sum() / self.sensor.frame_rate)}
        return {"source": "spliced", "note": "cut captures: a stream evaluation splices each subject's captures "
                "between stretches of its idle captures (the splice points are artificial)"}


def time_step_summary(times: Iterable[Sequence[float]]) -> dict[str, float]:
    """Median, 95th percentile (linear), min and max of the steps between consecutive frame times (ms);
    empty when no capture has two frames."""
    steps = np.concatenate([np.diff(np.asarray(t, dtype=np.float64)) for t in times] + [np.zeros(0)])
    if not steps.size:
        return {}
    return {"median": float(np.median(steps)), "p95": float(np.percentile(steps, 95)),
            "min": float(steps.min()), "max": float(steps.max())}


def _table_info(table: pa.Table, path: Path) -> dict[str, Any]:
    """The touchbench metadata of a dataset table (refused: none, damaged, another format version)."""
    raw = (table.schema.metadata or {}).get(b"touchbench")
    if raw is None or "frames" not in table.column_names:
        raise DataError("not a touchbench dataset (no touchbench metadata or frames column)", path)
    try:
        info = json.loads(raw)
        version = info.get("format_version")
    except (ValueError, AttributeError) as e:  # not JSON, or not an object
        raise DataError(f"its touchbench metadata is damaged ({type(e).__name__}); convert the data again",
                        path) from None
    if version != FORMAT_VERSION:
        raise DataError(
            f"written by another touchbench storage format (version {version}, "
            f"this version reads {FORMAT_VERSION}); convert it again", path)
    return info


def _dataset_of(cls: type, table: pa.Table, info: dict[str, Any], path: Path) -> TouchDataset:
    """The captures, metadata and sensor a dataset table holds (its content not yet hashed)."""
    try:
        sensor = SensorSpec.from_dict(info["sensor"])
        dtype = np.dtype(info["dtype"])
        frames = table.column("frames").combine_chunks()
        n = table.column("n_frames").to_numpy()
        h, w = sensor.grid
        captures = []
        if len(frames):
            _, offsets_buf, data_buf = frames.buffers()
            offsets = np.frombuffer(offsets_buf, dtype=np.int64)[frames.offset:frames.offset + len(frames) + 1]
            values = np.frombuffer(data_buf, dtype=np.uint8)
            captures = [
                values[offsets[i]:offsets[i + 1]].view(dtype).reshape(int(n[i]), h, w) for i in range(len(n))
            ]
        meta = table.drop_columns(["frames", "n_frames"]).to_pandas()
        return cls(name=info["name"], captures=captures, meta=meta, sensor=sensor,
                   provenance=info.get("provenance", {}))
    except TouchbenchError as e:
        raise DataError(str(e), path) from None
    except (KeyError, TypeError, ValueError) as e:  # metadata that does not describe the frames
        raise DataError(f"its touchbench metadata does not describe its frames ({type(e).__name__}: {e}); "
                        "convert the data again", path) from None


def concat(datasets: Sequence[TouchDataset], name: str) -> TouchDataset:
    """Stack datasets that share a sensor."""
    if not datasets:
        raise ValueError("nothing to concatenate")
    sensor = datasets[0].sensor
    for d in datasets[1:]:
        if d.sensor != sensor:
            raise ValueError(f"cannot concatenate {d.name!r}: sensor differs from {datasets[0].name!r}")
    return TouchDataset(
        name=name,
        captures=[c for d in datasets for c in d.captures],
        meta=pd.concat([d.meta for d in datasets], ignore_index=True),
        sensor=sensor,
    )


def _read_parquet(path: str | Path, name: str | None = None) -> TouchDataset:
    ds = TouchDataset.from_parquet(path)
    return ds if name is None else ds.with_name(name)


def _write_parquet(ds: TouchDataset, out_dir: Path) -> list[Path]:
    return [ds.to_parquet(Path(out_dir) / f"{ds.name}.parquet")]


register_format("parquet", "touchbench's own dataset file: one row per capture, the sensor in the metadata",
                _read_parquet, writer=_write_parquet)
