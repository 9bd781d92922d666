"""``haart-sample``: a small slice of real HAART shipped inside the package
(subjects s01 and s04, substrate none, cover none, all seven gestures: 14
captures), so the README's first command works on a machine without
../shared/data. Built from real ``haart`` by ``benchmarks/make_sample.py``.
"""

from __future__ import annotations

from pathlib import Path

from .model import TouchDataset
from .registry import DATASETS

SAMPLE_PATH = Path(__file__).resolve().parent.parent / "data" / "haart-sample.parquet"


@DATASETS.register("haart-sample", description="14 real HAART captures shipped with touchbench (s01, s04; none/none)", real=True)
def load_haart_sample(cache_dir=None, data_dir=None, refresh: bool = False) -> TouchDataset:
    return TouchDataset.from_parquet(SAMPLE_PATH).with_name("haart-sample")
