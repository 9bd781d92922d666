"""The CPU time of each listing command (`data list`, `features list`, `classifiers list`,
`protocols list`, `plugins list`), against the Python floor.

Runs each command N times in fresh processes, interleaved, and prints the median CPU time
(user + system, of the process and its children: what a loaded machine cannot hide, unlike
wall time) and the median wall time, of two cases: *index*, the registry index in the cache
(touchbench.core.listing) written before the runs, as after a listing's first run; *no index*, a
new, empty cache folder each run (the listing imports the registries and writes the index)::

    python benchmarks/bench_listing.py --runs 5
    python benchmarks/bench_listing.py --runs 5 --checkout ../other-checkout   # the same, of another checkout
    python benchmarks/bench_listing.py --runs 3 --base ../old-checkout         # and that checkout's times beside
    python benchmarks/bench_listing.py --runs 1 --command "data list"          # one listing only

``--checkout`` puts that folder first on ``PYTHONPATH`` (same interpreter), to time another
checkout; ``--base`` adds a third case, the same commands of another checkout (its own cache folder,
written before the runs), timed in the same rounds, so that a change and the code before it are
compared under the same load.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

COMMANDS = (["data", "list"], ["features", "list"], ["classifiers", "list"], ["protocols", "list"],
            ["plugins", "list"])
ENTRY = "from touchbench.cli.main import cli; cli()"


def timed(cmd: list[str], env: dict[str, str], cwd: str) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one run of ``cmd`` in folder ``cwd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=cwd)
    _, _, usage = os.wait4(proc.pid, 0)
    return usage.ru_utime + usage.ru_stime, time.perf_counter() - t0


def checkout_env(folder: str | None, cache: str) -> dict[str, str]:
    """The environment of a run: ``folder`` first on ``PYTHONPATH`` (None: as installed), ``cache`` the
    cache folder."""
    env = dict(os.environ, TOUCHBENCH_CACHE_DIR=cache)
    if folder:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (os.path.abspath(folder), env.get("PYTHONPATH")) if p)
    return env


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--checkout", default=None, help="a touchbench checkout to import instead of the installed one")
    ap.add_argument("--base", default=None, help="another checkout, timed beside (e.g. the code before a change)")
    ap.add_argument("--command", action="append", choices=[" ".join(c) for c in COMMANDS],
                    help="only this listing (repeatable; default: all)")
    args = ap.parse_args()
    commands = [c for c in COMMANDS if not args.command or " ".join(c) in args.command]
    root = tempfile.mkdtemp(prefix="bench-listing-")
    envs = {"index": checkout_env(args.checkout, os.path.join(root, "warm"))}
    if args.base:
        envs["base"] = checkout_env(args.base, os.path.join(root, "base"))
    for env in envs.values():  # the index written (where the checkout keeps one) before any timing
        for c in commands:
            subprocess.run([sys.executable, "-c", ENTRY, *c], env=env, cwd=root, capture_output=True)
    cases = [(" ".join(c), kind, [sys.executable, "-c", ENTRY, *c]) for c in commands
             for kind in ("index", "no index", *(("base",) if args.base else ()))]
    cases.append(("python -c pass (floor)", "index", [sys.executable, "-c", "pass"]))
    cpu: dict[tuple[str, str], list[float]] = {(n, k): [] for n, k, _ in cases}
    wall: dict[tuple[str, str], list[float]] = {(n, k): [] for n, k, _ in cases}
    for run in range(args.runs):
        for name, kind, cmd in cases:
            env = envs.get(kind) or checkout_env(args.checkout, os.path.join(root, f"empty-{run}-{name.replace(' ', '-')}"))
            c, w = timed(cmd, env, root)  # not in a checkout: `python -c` puts the working folder first
            cpu[name, kind].append(c)
            wall[name, kind].append(w)
    for (name, kind), times in cpu.items():
        label = name if name.startswith("python") else f"{name} ({kind})"
        print(f"{label:28s} CPU median {statistics.median(times):.2f} s (min {min(times):.2f}, "
              f"max {max(times):.2f}); wall median {statistics.median(wall[name, kind]):.2f} s, {args.runs} runs")
    shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
