"""What verifying the content hash on load costs, on the real HAART dataset.

``TouchDataset.from_parquet`` recomputes the content hash of every file it
loads (a file edited in place is new data). Prints the median of several
warm loads of ``load_dataset("haart")`` (from the dataset cache) and of the
hash computation alone, in a fresh cache directory removed afterwards.
Usage: python benchmarks/bench_dataset_hash.py [--repeats 7] [--name haart]
"""

from __future__ import annotations

import argparse
import statistics
import time

from workdir import fresh_dir

from touchbench.catalog import load_dataset


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--name", default="haart")
    args = ap.parse_args()
    with fresh_dir(__file__) as cache:
        ds = load_dataset(args.name, cache_dir=cache)  # cold: converts the raw files into the cache
        loads, hashes = [], []
        for _ in range(args.repeats):
            t = time.perf_counter()
            again = load_dataset(args.name, cache_dir=cache)
            loads.append(time.perf_counter() - t)
            again._hash = None
            t = time.perf_counter()
            assert again.content_hash == ds.content_hash
            hashes.append(time.perf_counter() - t)
        n_bytes = sum(c.nbytes for c in ds.captures)
        print(f"{args.name}: {len(ds)} captures, {n_bytes / 1e6:.1f} MB of frames; n={args.repeats}")
        print(f"  warm load (read + hash) median {statistics.median(loads) * 1000:6.0f} ms "
              f"(min {min(loads) * 1000:.0f}, max {max(loads) * 1000:.0f})")
        print(f"  content hash alone      median {statistics.median(hashes) * 1000:6.0f} ms "
              f"(min {min(hashes) * 1000:.0f}, max {max(hashes) * 1000:.0f})")


if __name__ == "__main__":
    main()
