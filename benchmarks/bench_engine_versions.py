"""One protocol under two versions of touchbench, side by side: wall time and accuracies.

    python benchmarks/bench_engine_versions.py --base 7c44a25 --protocol example-haart-loso --jobs 2 --runs 1
    python benchmarks/bench_engine_versions.py --base 7c44a25 --protocol example-haart-loso \\
        --filter subject=s01,s02,s03 --runs 3

``--base REV`` is checked out into a git worktree under this benchmark's
folder (``cache_dir() / "benchmarks" / "engine_versions"``), removed at the
end (``--base`` may also be a folder holding another checkout); the other
side is this checkout. Each run of each side starts from an empty feature cache
and an empty results folder, with the dataset cache already converted (the
real-data conversion is not timed), and runs ``touchbench run PROTOCOL
--jobs N`` in a subprocess with the same Python, alternating which side
goes first. Printed: each side's wall times and their median, the ratio of
the medians, and the accuracy of every method on both sides (equal when
the change kept the numbers).

``--filter column=a,b`` restricts the dataset (written into a copy of the
protocol) for a shorter measurement on the same methods.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import yaml

from compare_runs import side_root
from touchbench.core.paths import data_dir
from touchbench.protocols.library import find_protocol
from workdir import bench_dir

REPO = Path(__file__).resolve().parent.parent
RUN = "from touchbench.cli.main import cli; cli()"


def protocol_file(src: Path, name: str, filters: dict[str, list[str]], out: Path) -> Path:
    """The protocol ``name`` as the version in ``src`` ships it, with ``filters`` added."""
    cands = [*src.glob(f"touchbench/protocols/{name}.yaml"), *src.glob(f"protocols/{name}.yaml"),
             *src.glob(f"touchbench/protocols/papers/{name}.yaml"), *src.glob(f"protocols/papers/{name}.yaml")]
    if not cands:
        raise SystemExit(f"{src}: no protocol {name!r}")
    data = yaml.safe_load(cands[0].read_text())
    if filters:
        data.setdefault("dataset", {})
        if isinstance(data["dataset"], str):
            data["dataset"] = {"name": data["dataset"]}
        data["dataset"].setdefault("filters", {}).update(filters)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(yaml.safe_dump(data, sort_keys=False))
    return out


def one_run(src: Path, proto: Path, cache: Path, datasets: Path, results: Path, jobs: int) -> float:
    shutil.rmtree(cache, ignore_errors=True)
    shutil.rmtree(results, ignore_errors=True)
    cache.mkdir(parents=True)
    if datasets.is_dir():
        shutil.copytree(datasets, cache / "datasets")
    env = {**os.environ, "PYTHONPATH": str(src), "TOUCHBENCH_CACHE_DIR": str(cache), "PYTHONHASHSEED": "0",
           "TOUCHBENCH_DATA_DIR": str(data_dir())}  # the base checkout lives elsewhere: name the data
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", RUN, "run", str(proto), "--out", str(results), "--jobs", str(jobs),
                        "--no-progress"], cwd=src, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{src}: touchbench run failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    return wall


def accuracies(results: Path) -> pd.Series:
    s = pd.read_parquet(results / "scores.parquet")
    s = s[s["status"] == "ok"]
    return s.groupby(["features", "classifier"])["accuracy"].mean() * 100


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="git revision (or checkout folder) of the 'before' side")
    ap.add_argument("--protocol", required=True, help="protocol name in this checkout")
    ap.add_argument("--base-protocol", default=None, help="its name in the base revision [default: the same]")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--filter", action="append", default=[], metavar="COLUMN=A,B",
                    help="restrict the dataset (repeatable)")
    args = ap.parse_args()
    filters = {}
    for f in args.filter:
        col, _, vals = f.partition("=")
        filters[col] = vals.split(",")
    root = bench_dir(__file__)
    with contextlib.ExitStack() as stack:
        compare(args, filters, root, side_root(args.base, root, stack))


def compare(args, filters: dict[str, list[str]], root: Path, base_src: Path) -> None:
    head_src = REPO
    find_protocol(args.protocol)  # fails early with the known names
    protos = {"base": protocol_file(base_src, args.base_protocol or args.protocol, filters, root / "base.yaml"),
              "head": protocol_file(head_src, args.protocol, filters, root / "head.yaml")}
    srcs = {"base": base_src, "head": head_src}
    # convert the dataset once (not timed): a run of the head side with an empty filter does it
    datasets = root / "datasets-warm"
    if not datasets.is_dir():
        from touchbench.catalog import load_dataset
        from touchbench.protocols.loading import load_protocol

        os.environ["TOUCHBENCH_CACHE_DIR"] = str(root / "warm")
        load_dataset(load_protocol(protos["head"]).dataset.name)
        if (root / "warm" / "datasets").is_dir():  # a scene is generated, not cached
            shutil.copytree(root / "warm" / "datasets", datasets)
    walls: dict[str, list[float]] = {"base": [], "head": []}
    for i in range(args.runs):
        order = ["base", "head"] if i % 2 == 0 else ["head", "base"]
        for side in order:
            w = one_run(srcs[side], protos[side], root / f"cache-{side}", datasets, root / f"results-{side}", args.jobs)
            walls[side].append(w)
            print(f"run {i + 1} {side}: {w:.1f} s", flush=True)
    med = {k: statistics.median(v) for k, v in walls.items()}
    print(f"\nwall time, median of {args.runs} run(s), --jobs {args.jobs}: base ({args.base}) {med['base']:.1f} s, "
          f"head {med['head']:.1f} s: {med['base'] / med['head']:.2f}x")
    acc = pd.DataFrame({"base": accuracies(root / "results-base"), "head": accuracies(root / "results-head")})
    acc["equal"] = (acc["base"] - acc["head"]).abs() < 1e-9
    print("\naccuracy % (mean over folds):")
    print(acc.round(2).to_string())


if __name__ == "__main__":
    main()
