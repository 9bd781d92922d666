"""Run-engine benchmarks: overhead per task, cold vs warm feature cache, 1 vs 2 jobs.

    python benchmarks/bench_engine.py                 # all three, 3 repeats each
    python benchmarks/bench_engine.py --what cache --repeats 1

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
    measurement (one warm-up + 5 repeats of features + predict), metrics and
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
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import time
from pathlib import Path

from workdir import fresh_dir

OVERHEAD_PROTOCOL = """\
name: bench-overhead
dataset: haart
scheme: loso
features:
  - [msd]
  - [sd]
classifiers:
  - {name: gaus-rf, params: {n_estimators: 100}, label: rf100}
seed: 0
"""


def _run(proto, out: Path, jobs: int = 1):
    from touchbench.engine import run_protocol

    t0 = time.perf_counter()
    res = run_protocol(proto, out, jobs=jobs, progress=False)
    return time.perf_counter() - t0, res


def bench_overhead(work: Path, repeats: int) -> dict:
    from touchbench.protocols.schema import parse_protocol

    proto = parse_protocol(OVERHEAD_PROTOCOL, work / "overhead.yaml")
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
        # the one-capture latency measurement: a warm-up + at least LATENCY_MIN_CALLS timed calls
        from touchbench.engine.tasks import LATENCY_MIN_CALLS

        lat.append(float(s["latency_ms"].mean()) / 1000 * (LATENCY_MIN_CALLS + 1))
    return {"tasks": n, "wall_per_task_s": statistics.median(per_task), "bare_fit_predict_s": statistics.median(bare),
            "overhead_per_task_s": statistics.median(over), "latency_measurement_s": statistics.median(lat),
            "runs": repeats}


def bench_cache(work: Path, repeats: int, protocol: str) -> dict:
    from touchbench.core.paths import cache_dir
    from touchbench.protocols.library import find_protocol
    from touchbench.protocols.schema import load_protocol

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


def bench_jobs(work: Path, repeats: int) -> dict:
    from touchbench.protocols.schema import parse_protocol

    proto = parse_protocol(OVERHEAD_PROTOCOL, work / "overhead.yaml")
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
    args = ap.parse_args(argv)

    json_path = Path(args.json).resolve() if args.json else None
    home = os.getcwd()
    with fresh_dir(__file__) as work:
        os.environ["TOUCHBENCH_CACHE_DIR"] = str(work / "cache")
        os.chdir(work)
        try:
            figures = run_all(args, work)
        finally:
            os.chdir(home)
    if json_path:
        json_path.write_text(json.dumps(figures, indent=2))


def run_all(args, work: Path) -> dict:
    from touchbench.catalog import load_dataset

    for name in ("haart", "haart-challenge"):
        load_dataset(name)  # convert once, outside the timings
    print(f"cpus {os.cpu_count()}, load average {os.getloadavg()[0]:.1f}", file=sys.stderr)
    figures = {}
    if args.what in ("all", "overhead"):
        figures["overhead"] = r = bench_overhead(work, args.repeats)
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
        figures["jobs"] = r = bench_jobs(work, args.repeats)
        print(f"jobs: 1 job {r['jobs1_s']:.1f} s, 2 jobs {r['jobs2_s']:.1f} s ({r['speedup']:.2f}x) "
              f"(median of {r['runs']})")
    figures["load_average_end"] = os.getloadavg()[0]
    return figures

if __name__ == "__main__":
    main()
