"""How long `touchbench --version` and `touchbench --help` take, against the Python floor.

Runs each command N times in fresh processes, interleaved (version, help, floor, version, ...)
so that a busy machine slows all three alike, and prints the medians::

    python benchmarks/bench_cli_startup.py --runs 15

The floor is `python -c pass` with the same interpreter: what no command line can go under.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path


def timed(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=15)
    args = ap.parse_args()
    exe = Path(sys.executable).with_name("touchbench")
    tb = [str(exe)] if exe.is_file() else [sys.executable, "-m", "touchbench.cli.main"]
    cases = {"touchbench --version": tb + ["--version"], "touchbench --help": tb + ["--help"],
             "python -c pass (floor)": [sys.executable, "-c", "pass"]}
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(args.runs):
        for name, cmd in cases.items():
            times[name].append(timed(cmd))
    for name, t in times.items():
        print(f"{name:24s} median {statistics.median(t):.3f} s  (min {min(t):.3f}, max {max(t):.3f}, {len(t)} runs)")


if __name__ == "__main__":
    main()
