"""Registered datasets, and :func:`load_dataset` which resolves a name.

An entry is a loader ``f(cache_dir=None, data_dir=None, refresh=False) ->
TouchDataset``. :func:`load_dataset` accepts a registered dataset name, a
registered scene name written ``scene:NAME``, or the path of a dataset
Parquet file.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from ..registry import Registry
from .model import TouchDataset

_MODULES = ["touchbench.datasets.haart", "touchbench.datasets.sample"]


def _load() -> None:
    for m in _MODULES:
        importlib.import_module(m)


DATASETS: Registry = Registry("dataset", loader=_load)


def load_dataset(ref: str | Path, **kwargs: Any) -> TouchDataset:
    """Load a registered dataset, a ``scene:NAME`` or a Parquet file."""
    ref_s = str(ref)
    if ref_s.startswith("scene:"):
        from ..scenes import generate_scene  # scenes are optional at import time

        return generate_scene(ref_s[len("scene:"):], **kwargs)
    if ref_s.endswith(".parquet") or Path(ref_s).is_file():
        return TouchDataset.from_parquet(ref_s)
    return DATASETS.create(ref_s, **kwargs)
