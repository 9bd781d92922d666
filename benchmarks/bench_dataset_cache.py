"""Cold conversion and warm (cached) load of the real HAART datasets.

Prints the median of several warm loads in a fresh cache directory under
``cache_dir() / "benchmarks" / "dataset_cache"``, removed afterwards.
Usage: python benchmarks/bench_dataset_cache.py [--repeats 7] [--name haart --name haart-challenge]
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
    ap.add_argument("--name", action="append", help="dataset (repeatable; default haart and haart-challenge)")
    args = ap.parse_args()
    with fresh_dir(__file__) as cache:
        for name in args.name or ("haart", "haart-challenge"):
            t = time.perf_counter()
            ds = load_dataset(name, cache_dir=cache)
            cold = time.perf_counter() - t
            warm = []
            for _ in range(args.repeats):
                t = time.perf_counter()
                again = load_dataset(name, cache_dir=cache)
                warm.append(time.perf_counter() - t)
            assert again.content_hash == ds.content_hash
            print(f"{name:16s} captures={len(ds)}  cold (parse raw + write cache) {cold:6.2f} s  "
                  f"warm load median {statistics.median(warm) * 1000:6.0f} ms  (min {min(warm) * 1000:.0f}, "
                  f"max {max(warm) * 1000:.0f}, n={args.repeats})")


if __name__ == "__main__":
    main()
