"""Generation time of the full ``cost-like`` scene (target: the 7805
captures in under 30 s on one core).

Generates the scene ``--runs`` times in this process (one core: numpy's
small-array work is single-threaded; BLAS threads are pinned to 1 below)
and prints each run's wall and CPU time, then the median. The first,
untimed, generation of ``tiny`` pays the imports.

Usage::

    python benchmarks/bench_scenes.py                 # cost-like, 3 runs
    python benchmarks/bench_scenes.py --scene tpm-like --runs 5

On a machine shared with other jobs the wall time overstates the cost; the
CPU time (``time.process_time``) is the figure to compare with the target.
"""

from __future__ import annotations

import argparse
import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="cost-like")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seed", type=int, default=None)
    args = ap.parse_args()

    from touchbench.scenes import generate_scene, load_scene
    from touchbench.scenes.generate import generate

    generate_scene("tiny")  # imports, caches
    spec = load_scene(args.scene)
    walls, cpus = [], []
    for i in range(args.runs):
        w, c = time.perf_counter(), time.process_time()
        ds = generate(spec, seed=args.seed)
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
        print(f"run {i + 1}: {len(ds)} captures, {int(ds.n_frames.sum())} frames, wall {walls[-1]:.2f} s, cpu {cpus[-1]:.2f} s, hash {ds.content_hash[:12]}", flush=True)
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = float("nan")
    print(
        f"{args.scene}: median wall {statistics.median(walls):.2f} s, median cpu {statistics.median(cpus):.2f} s "
        f"over {args.runs} runs (python {platform.python_version()}, load average {load:.1f} on {os.cpu_count()} cores)"
    )


if __name__ == "__main__":
    main()
