"""Test-suite wall time: in one process and spread over pytest-xdist workers (``make test``).

    python benchmarks/bench_tests.py                       # one process, then two workers; 1 repeat
    python benchmarks/bench_tests.py --workers 2 --workers 4 --repeats 3
    python benchmarks/bench_tests.py -- tests/test_api.py  # some tests only (pytest's arguments)

Each run is ``python -m pytest -q -p no:cacheprovider`` from the repository root, as ``make test``
runs it: ``-n 0`` for ``--workers 1`` (one process; xdist stays loaded, so its markers are known),
``-n N --dist loadgroup`` otherwise, then the arguments after ``--``. Every run gets a new, empty
``TOUCHBENCH_CACHE_DIR`` under ``cache_dir() / "benchmarks" / "tests"``, removed afterwards (CI's
fresh checkout starts from an empty one too); the rest of the environment (``CI``,
``TOUCHBENCH_DATA_DIR``) is this process's. The settings take turns
within each of the ``--repeats`` rounds, so that a machine getting busier slows them alike.

Printed: for each run, the machine's load average (1, 5 and 15 minutes) just before it, its wall
time, pytest's summary line and the tests that failed, one a line (a failing run is reported, not
hidden; the script then exits with 1); then, per setting, the median wall time over the
``--repeats`` runs and its speed-up over the first setting. A run takes minutes (5 to 8 in one
process on a two-core machine), hence one repeat by default.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from workdir import fresh_dir

ROOT = Path(__file__).resolve().parent.parent


def pytest_command(workers: int, extra: list[str]) -> list[str]:
    """``make test``'s pytest command with ``workers`` processes (1: no worker process at all)."""
    spread = ["-n", "0"] if workers == 1 else ["-n", str(workers), "--dist", "loadgroup"]
    return [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *spread, *extra]


def one_run(workers: int, extra: list[str]) -> tuple[float, str, list[str]]:
    """Wall time, pytest's summary line and the lines naming the tests that failed (none when every
    test passed), for one run in a new cache."""
    with fresh_dir(__file__) as cache:
        env = dict(os.environ, TOUCHBENCH_CACHE_DIR=str(cache))
        t0 = time.perf_counter()
        r = subprocess.run(pytest_command(workers, extra), cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    lines = [line for line in r.stdout.splitlines() if line.strip()]
    summary = lines[-1].strip("= ") if lines else r.stderr.strip()[-200:]
    failures = [line for line in lines if line.startswith(("FAILED ", "ERROR "))]
    return wall, summary, failures or ([] if r.returncode == 0 else [f"pytest exited with {r.returncode}"])


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, action="append",
                    help="test processes of one setting (1: one process); repeatable; default 1 and 2")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each setting (default 1)")
    ap.add_argument("pytest_args", nargs="*", help="passed on to pytest (after --)")
    args = ap.parse_args()
    settings = args.workers or [1, 2]
    walls: dict[int, list[float]] = {w: [] for w in settings}
    failed = False
    for round_ in range(args.repeats):
        for w in settings:
            before = load()
            wall, summary, failures = one_run(w, args.pytest_args)
            walls[w].append(wall)
            failed |= bool(failures)
            print(f"round {round_ + 1}, {w} worker(s): load {before} -> {wall:7.1f} s  {summary}", flush=True)
            for line in failures:
                print(f"    {line[:200]}", flush=True)
    base = statistics.median(walls[settings[0]])
    for w in settings:
        m = statistics.median(walls[w])
        print(f"{w} worker(s): median {m:7.1f} s over {len(walls[w])} run(s), {base / m:.2f}x "
              f"the {settings[0]}-worker time")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
