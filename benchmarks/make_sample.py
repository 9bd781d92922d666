"""Build touchbench/data/haart-sample.parquet from real HAART: subjects s01
and s04, substrate none, cover none, all seven gestures (14 captures).

    python benchmarks/make_sample.py                    # rewrites the shipped sample
    python benchmarks/make_sample.py --out sample.parquet   # writes it elsewhere
"""

import argparse
from pathlib import Path

import numpy as np

from touchbench.catalog import load_dataset
from touchbench.datasets.sample import SAMPLE_PATH


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=SAMPLE_PATH, help="where to write it (default: the shipped sample)")
    out = ap.parse_args().out
    ds = load_dataset("haart")
    m = ds.meta
    idx = np.flatnonzero(m["subject"].isin(["s01", "s04"]) & (m["substrate"] == "none") & (m["cover"] == "none"))
    sample = ds.subset(idx, name="haart-sample")
    sample.provenance = {"note": "14 captures of real haart: s01 and s04, substrate none, cover none"}
    sample.to_parquet(out)
    print(f"{out}: {len(sample)} captures, {Path(out).stat().st_size} bytes, hash {sample.content_hash}")


if __name__ == "__main__":
    main()
