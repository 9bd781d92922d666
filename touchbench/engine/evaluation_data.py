"""The captures an evaluation runs on: the protocol's dataset, filtered, and what its scheme makes of it.

- :func:`load_spec` loads a dataset entry of a protocol (a registered name,
  a scene, a Parquet file, or a file or folder in a registered ``format``);
  a dataset file changed since it was written adds a note.
- :func:`apply_filters` keeps the captures an entry's ``filters`` keep and
  its ``exclude`` does not drop (unknown columns or values are refused at
  their protocol line).
- :func:`evaluation_dataset` is what the scheme makes of the dataset: its
  :meth:`touchbench.protocols.schemes.Splitter.prepare` (``cross-dataset``
  loads, filters and adapts its test data and stacks both; ``window-kfold``
  cuts the captures into windows), given the protocol's services as a
  :class:`touchbench.protocols.schemes.DataContext`.
"""

from __future__ import annotations

import warnings
from functools import partial
from typing import Any

import numpy as np
import pandas as pd

from ..catalog import load_dataset, parse_dataset_ref
from ..core.errors import TouchbenchError
from ..core.suggest import did_you_mean
from ..datasets.model import DatasetChangedWarning, TouchDataset
from ..protocols.schema import Protocol
from ..protocols.specs import DatasetSpec
from ..protocols.schemes import DataContext

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


def _load_entry(protocol: Protocol, notes: list[str], entry: Any, loc: tuple) -> TouchDataset:
    """The dataset entry ``entry`` (a mapping given at ``loc``), loaded and filtered."""
    try:
        spec = DatasetSpec.model_validate(entry)
    except Exception as e:
        raise protocol.error_at(loc, f"not a dataset entry: {e}") from None
    return apply_filters(protocol, load_spec(protocol, spec, loc, notes), spec, loc)


def evaluation_dataset(protocol: Protocol, ds: TouchDataset, notes: list[str]) -> TouchDataset:
    """``ds`` (the protocol's filtered dataset) as the protocol's scheme evaluates it (see the module
    docstring)."""
    context = DataContext(dataset_name=protocol.dataset.name, notes=notes,
                          load=partial(_load_entry, protocol, notes), error_at=protocol.error_at)
    return protocol.splitter(0).prepare(ds, context)
