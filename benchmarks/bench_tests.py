"""Test-suite wall time: in one process and spread over pytest-xdist workers (``make test``), from
a cold start (as a fresh clone) and warm (as a second run).

    python benchmarks/bench_tests.py                       # one process, then two workers; cold, then warm
    python benchmarks/bench_tests.py --workers 2 --state cold --repeats 3
    python benchmarks/bench_tests.py -- tests/test_api.py  # some tests only (pytest's arguments)

Each run is ``python -m pytest -q -p no:cacheprovider`` on the repository's tests, as ``make test``
runs it: ``-n 0`` for ``--workers 1`` (one process; xdist stays loaded, so its markers are known),
``-n N --dist loadgroup`` otherwise, then the arguments after ``--`` (test paths relative to the
repository root, as there). Its working folder is a folder of its own under ``cache_dir() /
"benchmarks" / "tests"``, which holds what a run leaves for the next: ``TOUCHBENCH_CACHE_DIR``
(converted datasets, feature caches, the registry index), Hypothesis's example database
(``.hypothesis/``, kept in the working folder) and ``NUMBA_CACHE_DIR`` (the machine code numba
compiles for aeon's peers, otherwise kept beside aeon in the virtual environment, which CI builds
anew). ``cold``: all new and empty for every run, as in CI's fresh clone. ``warm``: one such folder
for every warm run, filled by one untimed run first. (Python's bytecode of the repository is not
removed: a fresh clone also compiles it once, a few seconds.) The rest
of the environment (``CI``, ``TOUCHBENCH_DATA_DIR``) is this process's. The settings take turns
within each of the ``--repeats`` rounds, so that a machine getting busier slows them alike.

Printed: for each run, the machine's load average (1, 5 and 15 minutes) just before it, its wall
time and the CPU time of pytest and every process it waited for, pytest's summary line and the tests
that failed, one a line (a failing run is reported, not hidden; the script then exits with 1);
then, per setting, the median wall time over the ``--repeats`` runs and its speed-up over the first
setting. A run takes minutes (8 to 12 in one process on a two-core machine), hence one repeat by
default.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from contextlib import ExitStack
from pathlib import Path

from workdir import fresh_dir

from touchbench.core.paths import data_dir

ROOT = Path(__file__).resolve().parent.parent
STATES = ("cold", "warm")


def pytest_command(workers: int, extra: list[str]) -> list[str]:
    """``make test``'s pytest command with ``workers`` processes (1: no worker process at all), on the
    repository's tests (or the test paths in ``extra``, made absolute) from any working folder."""
    spread = ["-n", "0"] if workers == 1 else ["-n", str(workers), "--dist", "loadgroup"]
    paths = {a for a in extra if not a.startswith("-") and (ROOT / a.split("::")[0]).exists()}
    args = [str(ROOT / a) if a in paths else a for a in extra] + ([] if paths else [str(ROOT / "tests")])
    return [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--rootdir", str(ROOT), *spread, *args]


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def one_run(workers: int, extra: list[str], work: Path) -> tuple[float, float, str, list[str]]:
    """Wall time, CPU time, pytest's summary line and the lines naming the tests that failed (none when
    every test passed), for one run in the working folder ``work`` (its caches and Hypothesis folder)."""
    env = dict(os.environ, TOUCHBENCH_CACHE_DIR=str(work / "cache"), TOUCHBENCH_DATA_DIR=str(data_dir()),
               NUMBA_CACHE_DIR=str(work / "numba"))
    cpu0, t0 = children_cpu(), time.perf_counter()
    r = subprocess.run(pytest_command(workers, extra), cwd=work, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, children_cpu() - cpu0
    lines = [line for line in r.stdout.splitlines() if line.strip()]
    summary = lines[-1].strip("= ") if lines else r.stderr.strip()[-200:]
    failures = [line for line in lines if line.startswith(("FAILED ", "ERROR "))]
    return wall, cpu, summary, failures or ([] if r.returncode == 0 else [f"pytest exited with {r.returncode}"])


def load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, action="append",
                    help="test processes of one setting (1: one process); repeatable; default 1 and 2")
    ap.add_argument("--state", choices=STATES, action="append",
                    help="cold (new cache and Hypothesis folder each run) or warm; repeatable; default both")
    ap.add_argument("--repeats", type=int, default=1, help="runs of each setting (default 1)")
    ap.add_argument("pytest_args", nargs="*", help="passed on to pytest (after --)")
    args = ap.parse_args()
    settings = [(w, s) for s in dict.fromkeys(args.state or STATES) for w in args.workers or [1, 2]]
    walls: dict[tuple[int, str], list[float]] = {k: [] for k in settings}
    failed = False
    with ExitStack() as stack:
        warm = stack.enter_context(fresh_dir(__file__)) if any(s == "warm" for _, s in settings) else None
        if warm is not None:  # the untimed run that fills the warm folder
            failed |= bool(one_run(settings[0][0], args.pytest_args, warm)[3])
        for round_ in range(args.repeats):
            for w, state in settings:
                before = load()
                with ExitStack() as run_stack:
                    work = warm if state == "warm" else run_stack.enter_context(fresh_dir(__file__))
                    wall, cpu, summary, failures = one_run(w, args.pytest_args, work)
                walls[w, state].append(wall)
                failed |= bool(failures)
                print(f"round {round_ + 1}, {w} worker(s), {state}: load {before} -> {wall:7.1f} s wall, "
                      f"{cpu:7.1f} s CPU  {summary}", flush=True)
                for line in failures:
                    print(f"    {line[:200]}", flush=True)
    base = statistics.median(walls[settings[0]])
    for w, state in settings:
        m = statistics.median(walls[w, state])
        print(f"{w} worker(s), {state}: median {m:7.1f} s over {len(walls[w, state])} run(s), {base / m:.2f}x "
              f"the first setting's time")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
