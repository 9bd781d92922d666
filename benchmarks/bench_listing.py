"""The CPU time of each listing command (`data list`, `features list`, `classifiers list`,
`protocols list`, `plugins list`), against the Python floor.

Runs each command N times in fresh processes, interleaved, and prints the median CPU time
(user + system, of the process and its children: what a loaded machine cannot hide, unlike
wall time) and the median wall time::

    python benchmarks/bench_listing.py --runs 5
    python benchmarks/bench_listing.py --runs 5 --checkout ../other-checkout   # the same, of another checkout

``--checkout`` puts that folder first on ``PYTHONPATH`` (same interpreter), to compare a
change with the code before it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

COMMANDS = (["data", "list"], ["features", "list"], ["classifiers", "list"], ["protocols", "list"],
            ["plugins", "list"])
ENTRY = "from touchbench.cli.main import cli; cli()"


def timed(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one run of ``cmd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    _, _, usage = os.wait4(proc.pid, 0)
    return usage.ru_utime + usage.ru_stime, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--checkout", default=None, help="a touchbench checkout to import instead of the installed one")
    args = ap.parse_args()
    env = dict(os.environ)
    if args.checkout:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (os.path.abspath(args.checkout), env.get("PYTHONPATH")) if p)
    cases = {" ".join(c): [sys.executable, "-c", ENTRY, *c] for c in COMMANDS}
    cases["python -c pass (floor)"] = [sys.executable, "-c", "pass"]
    cpu: dict[str, list[float]] = {k: [] for k in cases}
    wall: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(args.runs):
        for name, cmd in cases.items():
            c, w = timed(cmd, env)
            cpu[name].append(c)
            wall[name].append(w)
    for name in cases:
        print(f"{name:24s} CPU median {statistics.median(cpu[name]):.2f} s (min {min(cpu[name]):.2f}, "
              f"max {max(cpu[name]):.2f}); wall median {statistics.median(wall[name]):.2f} s, {args.runs} runs")


if __name__ == "__main__":
    main()
