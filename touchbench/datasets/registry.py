"""Registered datasets.

An entry is a loader ``f(cache_dir=None, data_dir=None, refresh=False) ->
TouchDataset``; its other keyword parameters are the options a protocol's
``dataset: {options: ...}`` may give. An entry whose options can fail
declares ``check_options=f`` (``f(options) -> (option, why) | None``),
asked when a protocol is validated, before any data is read. :func:`touchbench.catalog.load_dataset` resolves a
reference (a registered name, ``scene:NAME`` or a Parquet path).
"""

from __future__ import annotations

from ..core.registry import Registry

#: the loader parameters that name where it writes (its Parquet cache): a
#: protocol may not set them (the cache folder is the user's choice,
#: ``TOUCHBENCH_CACHE_DIR``, never a file's)
WRITE_LOCATIONS = ("cache_dir",)
#: the loader parameters that say where it reads and whether to rebuild: not options of the data
LOADER_PLACES = ("cache_dir", "data_dir", "refresh")

# Filled by every module of touchbench.datasets (imported on first use of the registry).
DATASETS: Registry = Registry("dataset", package="touchbench.datasets")
