"""Kill-and-resume soak: SIGKILL a real HAART run at random moments, resume it, compare.

Each trial starts ``touchbench run`` on a real HAART protocol (leave one
subject out, two feature sets, a random forest; ``--jobs 2``) with an empty
cache folder of its own, so that a kill can land while the dataset cache is
written, while features are computed, while tasks run or while the fragments
are merged. The kill comes at a random moment of the uninterrupted run's
duration (uniform in 5-95 %, seeded); a run that ends before its moment is
not a kill and is not counted. After the kill the script waits for the run's
processes (its parallel workers included) to end, counts those still alive
after 15 s, then runs the same command again to the end and compares with
the uninterrupted run:

- ``predictions.parquet`` and ``confusion.parquet``: byte for byte;
- ``scores.parquet``: every column but the measured times (seconds,
  latency, finish time), value for value.

A trial is byte-identical when all three hold. Prints one line per trial and
the counts::

    python benchmarks/bench_kill_resume.py --kills 20
    python benchmarks/bench_kill_resume.py --kills 1 --jobs 1 --dataset haart-sample   # seconds

Files go to ``cache_dir()/benchmarks/kill_resume`` (``benchmarks/workdir.py``);
needs ../shared/data/haart (or ``TOUCHBENCH_DATA_DIR``).
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from workdir import bench_dir  # noqa: E402

PROTOCOL = """\
name: soak-haart
description: {dataset}, leave one subject out, MSD and Zhou basic features, a 50-tree random forest
dataset: {dataset}
target: gesture
scheme: loso
features:
  - [msd]
  - [zhou-basic]
classifiers:
  - name: gaus-rf
    params: {{n_estimators: 50}}
seed: 0
"""
TIMES = ["feature_seconds_per_capture", "feature_fit_seconds", "fit_seconds", "predict_seconds", "latency_ms",
         "finished_at"]


def descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (read from /proc)."""
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d.name))
    out, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out


def alive(pid: int) -> bool:
    try:
        return "\nState:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False


def command(root: Path, out: Path, jobs: int) -> list[str]:
    exe = Path(sys.executable).with_name("touchbench")  # the command of this environment
    return [str(exe if exe.is_file() else "touchbench"), "run", str(root / "soak-haart.yaml"), "--out", str(out),
            "--jobs", str(jobs), "--no-progress"]


def start(root: Path, out: Path, cache: Path, jobs: int) -> subprocess.Popen:
    env = {**os.environ, "TOUCHBENCH_CACHE_DIR": str(cache)}
    return subprocess.Popen(command(root, out, jobs), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)


def finish(root: Path, out: Path, cache: Path, jobs: int) -> float:
    t0 = time.perf_counter()
    p = start(root, out, cache, jobs)
    _, err = p.communicate()
    if p.returncode != 0:
        raise SystemExit(f"the run failed (exit {p.returncode}):\n{err}")
    return time.perf_counter() - t0


def stage(out: Path, cache: Path) -> str:
    """Where the run was when it was killed, from what it had written."""
    if (out / "scores.parquet").is_file():
        return "merge"
    n = len(list((out / "fragments").glob("*.scores.parquet"))) if (out / "fragments").is_dir() else 0
    if n:
        return f"tasks ({n} done)"
    if any((cache / "features").glob("*.npy")):
        return "features"
    return "dataset"


def same(ref: Path, out: Path) -> list[str]:
    diffs = [name for name in ("predictions.parquet", "confusion.parquet")
             if (ref / name).read_bytes() != (out / name).read_bytes()]
    a = pd.read_parquet(ref / "scores.parquet").drop(columns=TIMES)
    b = pd.read_parquet(out / "scores.parquet").drop(columns=TIMES)
    if not a.equals(b):
        diffs.append("scores.parquet")
    return diffs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dataset", default="haart", help="the protocol's dataset")
    args = ap.parse_args()
    root = bench_dir(__file__)
    shutil.rmtree(root, ignore_errors=True)
    root.mkdir(parents=True)
    (root / "soak-haart.yaml").write_text(PROTOCOL.format(dataset=args.dataset))
    rng = random.Random(args.seed)

    ref = root / "reference"
    duration = finish(root, ref, root / "cache-reference", args.jobs)
    print(f"uninterrupted run: {duration:.1f} s (cold cache, --jobs {args.jobs})", flush=True)

    identical, leftovers, kills, trial, early = 0, 0, 0, 0, 0
    while kills < args.kills:
        out, cache = root / f"trial-{trial}", root / f"cache-{trial}"
        trial += 1
        delay = rng.uniform(0.05, 0.95) * duration
        p = start(root, out, cache, args.jobs)
        deadline = time.monotonic() + delay
        family: set[int] = set()
        while time.monotonic() < deadline and p.poll() is None:
            family |= descendants(p.pid)
            time.sleep(0.05)
        family |= descendants(p.pid)
        where = stage(out, cache)
        if p.poll() is not None:  # it ended before its kill moment (a busy machine varies): not a kill
            early += 1
            shutil.rmtree(cache, ignore_errors=True)
            shutil.rmtree(out, ignore_errors=True)
            continue
        p.send_signal(signal.SIGKILL)
        p.wait()
        kills += 1
        end = time.monotonic() + 15
        while any(alive(c) for c in family) and time.monotonic() < end:
            time.sleep(0.1)
        left = [c for c in family if alive(c)]
        leftovers += len(left)
        for c in left:  # do not let them disturb the next trials
            os.kill(c, signal.SIGKILL)
        finish(root, out, cache, args.jobs)
        diffs = same(ref, out)
        identical += not diffs
        print(f"kill {kills:2d}: at {delay:5.1f} s ({where}), {len(family)} child processes, {len(left)} left alive "
              f"after 15 s; resumed: {'identical' if not diffs else 'DIFFERENT: ' + ', '.join(diffs)}", flush=True)
        shutil.rmtree(cache, ignore_errors=True)
        shutil.rmtree(out, ignore_errors=True)
    if early:
        print(f"({early} run(s) ended before their kill moment: not counted)")
    print(f"\nSIGKILLs: {kills}; byte-identical outcomes: {identical}/{kills}; processes of a killed run left alive: "
          f"{leftovers}")


if __name__ == "__main__":
    main()
