"""Peak memory (RSS) of a full ``cost-like`` run under leave-one-subject-out.

    python benchmarks/bench_memory_cost.py                     # msd + gaus-rf (50 trees)
    python benchmarks/bench_memory_cost.py --features sd,bmh,msd,smmhh,lbptop --trees 1000
    python benchmarks/bench_memory_cost.py --scene tiny --trees 2     # another scene (tiny: seconds)

The synthetic CoST scene (``scene:cost-like``: 31 subjects, 7805 captures
of 8 x 8 at 135 Hz) is evaluated by the run engine under LOSO (31 folds)
in a child process with ``--jobs 1``; the child reports its peak resident
set size (``getrusage``), its resident size right after generating the
scene, and the size of the captures themselves. The default configuration
(the cheap MSD set and a 50-tree forest) keeps the run short on a shared
machine; peak memory is driven by the dataset, the cached feature matrix
and one fold's training matrix, which the number of trees barely changes
(a forest's nodes grow with the training set, not with the feature count).
The child's cache and results go to a fresh folder under
``cache_dir() / "benchmarks" / "memory_cost"``, removed afterwards.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

from workdir import fresh_dir

PROTOCOL = """\
name: bench-memory-cost
dataset: scene:{scene}
scheme: loso
features:
  - [{features}]
classifiers:
  - {{name: gaus-rf, params: {{n_estimators: {trees}}}}}
seed: 0
"""


def child(scene: str, features: str, trees: int, work: Path) -> None:
    os.environ["TOUCHBENCH_CACHE_DIR"] = str(work / "cache")
    from touchbench.catalog import load_dataset
    from touchbench.engine import run_protocol
    from touchbench.protocols.loading import parse_protocol

    t0 = time.perf_counter()
    ds = load_dataset(f"scene:{scene}")
    rss_load = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    data_mb = sum(c.nbytes for c in ds.captures) / 2**20
    proto = parse_protocol(PROTOCOL.format(scene=scene, features=features, trees=trees), work / "p.yaml")
    res = run_protocol(proto, work / "out", jobs=1, progress=False, dataset=ds)
    print(json.dumps({
        "captures": len(ds), "subjects": int(ds.meta["subject"].nunique()), "frames": int(ds.n_frames.sum()),
        "dataset_mb": data_mb, "rss_after_scene_mb": rss_load,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "tasks": res.n_tasks, "failed": res.n_failed, "seconds": time.perf_counter() - t0,
        "accuracy_mean": float(res.summary["accuracy_mean"].iloc[0]),
    }))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--features", default="msd", help="Comma-separated feature sets of the one combination.")
    ap.add_argument("--trees", type=int, default=50)
    ap.add_argument("--scene", default="cost-like", help="the synthetic scene evaluated")
    ap.add_argument("--json", default=None)
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    features = ", ".join(f.strip() for f in args.features.split(",") if f.strip())
    if args.child:
        child(args.scene, features, args.trees, Path(args.child))
        return
    with fresh_dir(__file__) as work:
        cmd = [sys.executable, __file__, "--scene", args.scene, "--features", args.features, "--trees", str(args.trees),
               "--child", str(work)]
        out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        sys.exit(f"the child run failed:\n{out.stderr[-3000:]}")
    r = json.loads(out.stdout.strip().splitlines()[-1])
    print(f"{args.scene} LOSO, [{features}] + gaus-rf({args.trees} trees), --jobs 1: {r['tasks']} tasks "
          f"({r['failed']} failed) in {r['seconds']:.0f} s, mean accuracy {100 * r['accuracy_mean']:.1f}%")
    print(f"{r['captures']} captures, {r['subjects']} subjects, {r['frames']} frames = {r['dataset_mb']:.0f} MB of captures; "
          f"RSS after generating the scene {r['rss_after_scene_mb']:.0f} MB; peak RSS {r['peak_rss_mb']:.0f} MB")
    if args.json:
        Path(args.json).write_text(json.dumps({**r, "features": features, "trees": args.trees}, indent=2))


if __name__ == "__main__":
    main()
