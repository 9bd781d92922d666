"""Registered datasets.

An entry is a loader ``f(cache_dir=None, data_dir=None, refresh=False) ->
TouchDataset``. :func:`touchbench.catalog.load_dataset` resolves a
reference (a registered name, ``scene:NAME`` or a Parquet path).
"""

from __future__ import annotations

from ..core.registry import Registry

#: the loader parameters that name where it writes (its Parquet cache): a
#: protocol may not set them (the cache folder is the user's choice,
#: ``TOUCHBENCH_CACHE_DIR``, never a file's)
WRITE_LOCATIONS = ("cache_dir",)

# Filled by every module of touchbench.datasets (imported on first use of the registry).
DATASETS: Registry = Registry("dataset", package="touchbench.datasets")
