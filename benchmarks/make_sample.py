"""Build touchbench/data/haart-sample.parquet from real HAART: subjects s01
and s04, substrate none, cover none, all seven gestures (14 captures)."""

from pathlib import Path

import numpy as np

from touchbench.catalog import load_dataset
from touchbench.datasets.sample import SAMPLE_PATH

ds = load_dataset("haart")
m = ds.meta
idx = np.flatnonzero(m["subject"].isin(["s01", "s04"]) & (m["substrate"] == "none") & (m["cover"] == "none"))
sample = ds.subset(idx, name="haart-sample")
sample.provenance = {"note": "14 captures of real haart: s01 and s04, substrate none, cover none"}
sample.to_parquet(SAMPLE_PATH)
print(f"{SAMPLE_PATH}: {len(sample)} captures, {Path(SAMPLE_PATH).stat().st_size} bytes, hash {sample.content_hash}")
