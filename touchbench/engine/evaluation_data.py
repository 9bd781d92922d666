"""The captures an evaluation runs on: the protocol's dataset, filtered, and what its scheme makes of it.

- :func:`load_spec` loads a dataset entry of a protocol (a registered name,
  a scene, a Parquet file, or a file or folder in a registered ``format``);
  a dataset file changed since it was written adds a note.
- :func:`apply_filters` keeps the captures an entry's ``filters`` keep and
  its ``exclude`` does not drop (unknown columns or values are refused at
  their protocol line).
- :func:`evaluation_dataset` applies the scheme: ``cross-dataset`` loads the
  test data, filters it, brings it to the training sensor with the declared
  adapters (:mod:`touchbench.datasets.adapt`, each recorded in the notes)
  and stacks both with an ``origin`` column and each capture's frame
  checksum (the splitter refuses test captures that are training ones); a
  scheme whose samples are windows (``window-kfold``) gets every capture cut
  into its windows (:func:`touchbench.datasets.windows.window_dataset`).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pandas as pd

from ..catalog import load_dataset, parse_dataset_ref
from ..core.errors import TouchbenchError
from ..core.suggest import did_you_mean
from ..datasets.adapt import AdapterError, adapt
from ..datasets.model import DatasetChangedWarning, TouchDataset, concat, frames_checksum
from ..datasets.windows import seconds_to_frames, window_dataset
from ..protocols.schema import DatasetSpec, Protocol
from ..protocols.splits import FRAMES_SHA, ORIGIN, CrossDataset

__all__ = ["apply_filters", "evaluation_dataset", "load_spec"]


def load_spec(protocol: Protocol, spec: DatasetSpec, loc: tuple, notes: list[str]) -> TouchDataset:
    """The dataset ``spec`` names (relative paths from the protocol's folder); ``loc`` is where the
    protocol gives it, for errors."""
    base = None if protocol.path is None else protocol.path.parent
    ref = str(parse_dataset_ref(spec.name, base))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", DatasetChangedWarning)
            ds = load_dataset(ref, format=spec.format, **spec.options)
        for w in caught:
            if issubclass(w.category, DatasetChangedWarning):
                notes.append(str(w.message))
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
        return ds
    except TouchbenchError:
        raise
    except TypeError as e:
        raise protocol.error_at(loc + ("options",), f"the loader of {ref!r} rejects the options: {e}") from None
    except Exception as e:
        raise protocol.error_at(loc + ("name",), f"cannot load {ref!r}: {type(e).__name__}: {e}") from None


def apply_filters(protocol: Protocol, ds: TouchDataset, spec: DatasetSpec | None = None,
                  loc: tuple = ("dataset",)) -> TouchDataset:
    """Keep the captures ``spec``'s (default: the protocol's dataset's) ``filters`` keep and
    ``exclude`` does not drop."""
    spec = protocol.dataset if spec is None else spec
    meta = ds.meta
    keep = np.ones(len(meta), dtype=bool)
    for field_name, rules, include in (("filters", spec.filters, True), ("exclude", spec.exclude, False)):
        for col, values in rules.items():
            if col not in meta.columns:
                raise protocol.error_at(
                    loc + (field_name, col),
                    f"the dataset has no metadata column {col!r}{did_you_mean(col, list(map(str, meta.columns)))} "
                    f"(columns: {', '.join(map(str, meta.columns))})",
                )
            col_vals = np.array([None if pd.isna(v) else str(v) for v in meta[col].tolist()], dtype=object)
            present = sorted({v for v in col_vals if v is not None})
            for i, v in enumerate(values):
                if v not in present:
                    raise protocol.error_at(
                        loc + (field_name, col, i),
                        f"{col} {v!r} is not in the dataset{did_you_mean(v, present)} (values: {', '.join(present)})",
                    )
            hit = np.isin(col_vals, values)
            keep &= hit if include else ~hit
    if not keep.any():
        raise protocol.error_at(loc, "the filters leave no captures")
    if keep.all():
        return ds
    return ds.subset(np.flatnonzero(keep))


def _with_origin(ds: TouchDataset, origin: str, checksums: list[str], name: str) -> TouchDataset:
    meta = ds.meta.copy()
    meta["capture_id"] = [f"{origin}:{c}" for c in meta["capture_id"].astype(str)]
    meta[ORIGIN] = origin
    meta[FRAMES_SHA] = checksums
    return TouchDataset(name, ds.captures, meta, ds.sensor, provenance=ds.provenance)


def _cross_dataset(protocol: Protocol, splitter: CrossDataset, train: TouchDataset, notes: list[str]) -> TouchDataset:
    params = {"test": splitter.params.test, "adapters": splitter.params.adapters}
    loc = ("scheme", "test")
    try:
        spec = DatasetSpec.model_validate(params["test"])
    except Exception as e:
        raise protocol.error_at(loc, f"not a dataset entry: {e}") from None
    test = apply_filters(protocol, load_spec(protocol, spec, loc, notes), spec, loc)
    test_sha = [frames_checksum(c) for c in test.captures]  # before adapting: the recordings as read
    try:
        test, steps = adapt(test, train.sensor, list(params.get("adapters") or []), "scheme.adapters")
    except AdapterError as e:
        raise protocol.error_at(("scheme", "adapters") if params.get("adapters") else loc, str(e)) from None
    notes += steps
    notes.append(f"trained on {len(train)} captures of {protocol.dataset.name}, tested on {len(test)} of {spec.name}")
    both = [_with_origin(train, "train", [frames_checksum(c) for c in train.captures], train.name),
            _with_origin(test, "test", test_sha, train.name)]
    if {c.dtype for c in both[0].captures} != {c.dtype for c in both[1].captures}:  # one dtype for the stack
        both = [TouchDataset(d.name, [np.asarray(c, dtype=np.float64) for c in d.captures], d.meta, d.sensor,
                             provenance=d.provenance) for d in both]
    out = concat(both, f"{train.name}->{spec.name}")
    out.provenance = {"train": train.provenance, "test": test.provenance}
    return out


def evaluation_dataset(protocol: Protocol, ds: TouchDataset, notes: list[str]) -> TouchDataset:
    """``ds`` (the protocol's filtered dataset) as the protocol's scheme evaluates it (see the module
    docstring)."""
    splitter = protocol.splitter(0)
    if isinstance(splitter, CrossDataset):
        ds = _cross_dataset(protocol, splitter, ds, notes)
    windows: Any = splitter.sample_windows()
    if windows is not None:
        frames, seconds, hop = windows
        if frames is None:
            frames = seconds_to_frames(seconds, ds.sensor.frame_rate, "the window length")
        n = len(ds)
        ds = window_dataset(ds, frames, hop)
        notes.append(f"the samples are windows of {frames} frames every {hop or frames} (from {n} captures: "
                     f"{len(ds)} windows)")
    return ds
