"""Run-engine benchmarks: overhead per task, cold vs warm feature cache, 1 vs 2 jobs.

    python benchmarks/bench_engine.py                 # all three, 3 repeats each
    python benchmarks/bench_engine.py --what cache --repeats 1
    python benchmarks/bench_engine.py --what overhead --base f2fe39c --repeats 3
    python benchmarks/bench_engine.py --repeats 1 --dataset haart-sample --protocol tiny   # seconds

Everything runs on the real HAART data in a fresh cache and results folder
under ``cache_dir() / "benchmarks" / "engine"``, removed afterwards (the
user's feature cache and results are not touched; the HAART conversion is done once,
before timing). Figures are medians over ``--repeats`` runs, wall time.

overhead
    HAART, LOSO (10 folds), feature sets ``msd`` and ``sd``, ``gaus-rf``
    with 100 trees: 20 tasks, run with a warm feature cache and ``--jobs
    1``. The bare cost of a task is ``fit + predict`` of the same forest on
    the same matrices (the scores' ``fit_seconds`` + ``predict_seconds``);
    the overhead is the run's wall time per task minus that, which covers
    reading the cached matrices, predict_proba, the one-capture latency
    measurement (one warm-up + timed calls of features + predict), metrics and
    the atomic result fragment, plus the run's fixed costs (planning,
    merging the reports, the manifest) spread over the tasks.
cache
    The Gaus HAART protocol ``gaus-tables6-7-haart`` (the five Gaus feature
    sets combined, ``gaus-rf`` and ``gaus-boost`` with 1000 trees, challenge
    train -> test: 2 tasks). ``cold``: empty feature cache, new results
    folder. ``warm``: feature cache filled, new results folder (every task
    recomputed). ``rerun``: the same command again (finished tasks are
    skipped; the engine only checks that the reports are current).
jobs
    The overhead protocol, warm feature cache, new results folder, with
    ``--jobs 1`` and ``--jobs 2``.

``--base REV`` (with ``--what overhead``): the overhead of REV's code and of
this checkout's, side by side. REV is checked out with ``git worktree add
--detach`` into a temporary folder (removed afterwards); each of the
``--repeats`` rounds runs base then head, each a subprocess of this script
(``--repeats 1``) with ``PYTHONPATH`` set to that side's root and that
side's own feature cache (filled by the side's first run, which also does
the warm-up). This script drives both sides, so both must have
``run_protocol`` and ``parse_protocol`` as used here.
Printed: each side's median overhead and wall time per task, and head / base.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from workdir import bench_dir, fresh_dir

OVERHEAD_PROTOCOL = """\
name: bench-overhead
dataset: {dataset}
scheme: loso
features:
  - [msd]
  - [sd]
classifiers:
  - {{name: gaus-rf, params: {{n_estimators: 100}}, label: rf100}}
seed: 0
"""


def _run(proto, out: Path, jobs: int = 1):
    from touchbench.engine import run_protocol

    t0 = time.perf_counter()
    res = run_protocol(proto, out, jobs=jobs, progress=False)
    return time.perf_counter() - t0, res


def overhead_protocol(work: Path, dataset: str):
    from touchbench.protocols.loading import parse_protocol

    return parse_protocol(OVERHEAD_PROTOCOL.format(dataset=dataset), work / "overhead.yaml")


def bench_overhead(work: Path, repeats: int, warmup: bool = True, dataset: str = "haart") -> dict:
    proto = overhead_protocol(work, dataset)
    if warmup:
        _run(proto, work / "warmup-overhead")  # fills the feature cache
    per_task, bare, over, lat = [], [], [], []
    for i in range(repeats):
        wall, res = _run(proto, work / f"overhead-{i}")
        s = res.scores
        n = len(s)
        b = float((s["fit_seconds"] + s["predict_seconds"]).sum()) / n
        per_task.append(wall / n)
        bare.append(b)
        over.append(wall / n - b)
        # the one-capture latency measurement, at the least: a warm-up + the fewest timed calls
        # (LATENCY_MIN_CALLS; before the time budget, LATENCY_REPEATS passes)
        from touchbench.engine import tasks

        calls = getattr(tasks, "LATENCY_MIN_CALLS", getattr(tasks, "LATENCY_REPEATS", 5))
        lat.append(float(s["latency_ms"].mean()) / 1000 * (calls + 1))
    return {"tasks": n, "wall_per_task_s": statistics.median(per_task), "bare_fit_predict_s": statistics.median(bare),
            "overhead_per_task_s": statistics.median(over), "latency_measurement_s": statistics.median(lat),
            "runs": repeats}


def bench_cache(work: Path, repeats: int, protocol: str) -> dict:
    from touchbench.core.paths import cache_dir
    from touchbench.protocols.library import find_protocol
    from touchbench.protocols.loading import load_protocol

    proto = load_protocol(find_protocol(protocol))
    cold, warm, rerun = [], [], []
    for i in range(repeats):
        shutil.rmtree(cache_dir() / "features", ignore_errors=True)
        shutil.rmtree(cache_dir() / "engine-datasets", ignore_errors=True)
        t, _ = _run(proto, work / f"cold-{i}")
        cold.append(t)
        t, _ = _run(proto, work / f"warm-{i}")
        warm.append(t)
        t, res = _run(proto, work / f"warm-{i}")
        assert res.noop
        rerun.append(t)
    c, w, r = statistics.median(cold), statistics.median(warm), statistics.median(rerun)
    return {"protocol": proto.name, "cold_s": c, "warm_s": w, "rerun_s": r,
            "cold_over_warm": c / w, "cold_over_rerun": c / r, "runs": repeats}


def bench_jobs(work: Path, repeats: int, dataset: str = "haart") -> dict:
    proto = overhead_protocol(work, dataset)
    _run(proto, work / "warmup-jobs")
    out = {}
    for jobs in (1, 2):
        times = [_run(proto, work / f"jobs{jobs}-{i}", jobs=jobs)[0] for i in range(repeats)]
        out[f"jobs{jobs}_s"] = statistics.median(times)
    out["speedup"] = out["jobs1_s"] / out["jobs2_s"]
    out["runs"] = repeats
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--what", choices=["all", "overhead", "cache", "jobs"], default="all")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--protocol", default="gaus-tables6-7-haart", help="The protocol of the cache benchmark.")
    ap.add_argument("--json", default=None, help="Also write the figures here.")
    ap.add_argument("--dataset", default="haart", help="The dataset of the overhead and jobs benchmarks.")
    ap.add_argument("--base", default=None, metavar="REV",
                    help="With --what overhead: measure REV's code and this checkout's, alternating.")
    ap.add_argument("--cache", default=None, help=argparse.SUPPRESS)  # a side's feature cache (--base)
    args = ap.parse_args(argv)
    if args.base:
        if args.what != "overhead":
            ap.error("--base measures the overhead only: add --what overhead")
        compare_overhead(args.base, args.repeats)
        return

    json_path = Path(args.json).resolve() if args.json else None
    home = os.getcwd()
    with fresh_dir(__file__) as work:
        cache = Path(args.cache).resolve() if args.cache else work / "cache"
        args.warmup = not cache.is_dir()
        os.environ["TOUCHBENCH_CACHE_DIR"] = str(cache)
        os.chdir(work)
        try:
            figures = run_all(args, work)
        finally:
            os.chdir(home)
    if json_path:
        json_path.write_text(json.dumps(figures, indent=2))


def run_all(args, work: Path) -> dict:
    from touchbench.catalog import load_dataset
    from touchbench.protocols.library import find_protocol
    from touchbench.protocols.loading import load_protocol

    names = [args.dataset]
    if args.what in ("all", "cache"):
        names.append(load_protocol(find_protocol(args.protocol)).dataset.name)
    for name in dict.fromkeys(names):
        load_dataset(name)  # convert once, outside the timings
    print(f"cpus {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}", file=sys.stderr)
    figures = {}
    if args.what in ("all", "overhead"):
        figures["overhead"] = r = bench_overhead(work, args.repeats, getattr(args, "warmup", True), args.dataset)
        print(f"overhead: {r['tasks']} tasks, {1000 * r['wall_per_task_s']:.0f} ms per task, bare fit+predict "
              f"{1000 * r['bare_fit_predict_s']:.0f} ms, overhead {1000 * r['overhead_per_task_s']:.0f} ms per task, "
              f"of which ~{1000 * r['latency_measurement_s']:.0f} ms measure the one-capture latency "
              f"(median of {r['runs']})")
    if args.what in ("all", "cache"):
        figures["cache"] = r = bench_cache(work, args.repeats, args.protocol)
        print(f"cache: {r['protocol']}: cold {r['cold_s']:.1f} s, warm {r['warm_s']:.1f} s "
              f"({r['cold_over_warm']:.1f}x), rerun {r['rerun_s']:.2f} s ({r['cold_over_rerun']:.0f}x) "
              f"(median of {r['runs']})")
    if args.what in ("all", "jobs"):
        figures["jobs"] = r = bench_jobs(work, args.repeats, args.dataset)
        print(f"jobs: 1 job {r['jobs1_s']:.1f} s, 2 jobs {r['jobs2_s']:.1f} s ({r['speedup']:.2f}x) "
              f"(median of {r['runs']})")
    figures["load_average_end"] = os.getloadavg()[0]
    return figures


def overhead_once(root: Path, cache: Path, out: Path) -> dict:
    """One overhead run of the code in ``root`` (a subprocess of this script) with the feature cache ``cache``."""
    from touchbench.core.paths import data_dir

    env = {**os.environ, "PYTHONPATH": str(root), "TOUCHBENCH_DATA_DIR": str(data_dir())}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--what", "overhead", "--repeats", "1",
           "--json", str(out), "--cache", str(cache)]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{root}: overhead run failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    return json.loads(out.read_text())["overhead"]


def compare_overhead(rev: str, repeats: int) -> None:
    """The overhead per task of ``rev``'s code and this checkout's, runs alternating (base, head, base, ...)."""
    from compare_runs import REPO, checkout

    work = Path(tempfile.mkdtemp(prefix="versions-", dir=bench_dir(__file__)))
    runs: dict[str, list[dict]] = {"base": [], "head": []}
    print(f"cpus {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}", file=sys.stderr)
    try:
        with checkout(rev, work) as base_root:
            roots = {"base": base_root, "head": REPO}
            for i in range(repeats):
                for side, root in roots.items():
                    r = overhead_once(root, work / f"cache-{side}", work / f"{side}-{i}.json")
                    runs[side].append(r)
                    print(f"run {i + 1} {side}: {1000 * r['overhead_per_task_s']:.0f} ms overhead, "
                          f"{1000 * r['wall_per_task_s']:.0f} ms per task", flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    med = {side: {k: statistics.median(r[k] for r in rs) for k in ("overhead_per_task_s", "wall_per_task_s")}
           for side, rs in runs.items()}
    for side, name in (("base", rev), ("head", "this checkout")):
        print(f"overhead {side} ({name}): {1000 * med[side]['overhead_per_task_s']:.0f} ms per task, "
              f"{1000 * med[side]['wall_per_task_s']:.0f} ms wall per task (median of {repeats})")
    print(f"head / base: overhead {med['head']['overhead_per_task_s'] / med['base']['overhead_per_task_s']:.2f}x, "
          f"wall per task {med['head']['wall_per_task_s'] / med['base']['wall_per_task_s']:.2f}x")


if __name__ == "__main__":
    main()
