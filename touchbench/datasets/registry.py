"""Registered datasets.

An entry is a loader ``f(cache_dir=None, data_dir=None, refresh=False) ->
TouchDataset``. :func:`touchbench.catalog.load_dataset` resolves a
reference (a registered name, ``scene:NAME`` or a Parquet path).
"""

from __future__ import annotations

import importlib

from ..core.registry import Registry

_MODULES = ["touchbench.datasets.haart", "touchbench.datasets.sample"]


def _load() -> None:
    for m in _MODULES:
        importlib.import_module(m)


DATASETS: Registry = Registry("dataset", loader=_load)
