"""Per-capture cost of touchbench's own methods and the peers side by side: features + prediction of one capture, one core.

    python benchmarks/bench_touch_latency.py [--runs 5] [--captures 40] [--methods touch-et-fast,minirocket]
    python benchmarks/bench_touch_latency.py --dataset haart-sample --runs 1 --captures 1 --methods touch-et-fast

Every method of the shipped protocol ``touch-haart`` (its challenge evaluation) but the CNN (and
the CNN too with ``--methods``) is fitted once on the challenge's training
captures of ``haart-challenge`` (578 captures, seed 0, the protocol's
parameters), then times the path a live recogniser takes: one capture's
432 x 8 x 8 frames in, a label out (``predict`` on one flattened capture;
for touchbench's own methods that includes computing their features, for
the peers aeon's transform). For each method and each of ``--runs`` runs,
``--captures`` test captures are labelled one at a time, in the same
interleaved order for every method (so machine load hits all alike); a
run's figure is the median over its captures, and the script prints the
median over runs, as wall time and as the thread's CPU time (the work
itself). Accuracy on the 251 test captures is printed beside it, so the
speed-up "at the accuracy MiniRocket reaches" can be read off one run.

One core: pinned to one CPU, BLAS/OpenMP limited to one thread before
numpy is imported.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

DEFAULT_METHODS = "touch-et-fast,touch-et,touch-xgb,touch-et-win,touch-et-tuned,minirocket,multirocket"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--captures", type=int, default=40, help="test captures labelled one at a time per run")
    ap.add_argument("--methods", default=DEFAULT_METHODS)
    ap.add_argument("--dataset", default="haart-challenge", help="captures with a train/test split column")
    args = ap.parse_args()

    from touchbench.catalog import load_dataset
    from touchbench.classifiers import make_classifier
    from touchbench.methods import METHODS, FeaturePipeline, method_spec

    cpus = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpus[-1]})
    ds = load_dataset(args.dataset)
    split = ds.meta["split"].astype(str).to_numpy()
    tr, te = np.flatnonzero(split == "train"), np.flatnonzero(split == "test")
    X = np.stack(ds.captures).reshape(len(ds.captures), -1).astype(np.float64)
    y = ds.meta["gesture"].astype(str).to_numpy()
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    fitted, acc, fit_s = {}, {}, {}
    caps = ds.captures
    subjects = ds.meta["subject"].astype(str).to_numpy()
    for m in methods:
        t0 = time.perf_counter()
        if m in METHODS:  # a named method: the captures -> its feature sets -> its estimator
            pipe = FeaturePipeline(method_spec(m), random_state=0, sensor=ds.sensor)
            pipe.fit([caps[i] for i in tr], y[tr], groups=subjects[tr])
            predict = (lambda p: lambda idx: p.predict([caps[i] for i in idx]))(pipe)
        else:  # a classifier on the raw frames (the peers)
            est = make_classifier(m, random_state=0, sensor=ds.sensor).fit(X[tr], y[tr])
            predict = (lambda e: lambda idx: e.predict(X[idx]))(est)
        fit_s[m] = time.perf_counter() - t0
        acc[m] = float(np.mean(predict(te) == y[te]))
        fitted[m] = predict
        predict(te[:1])  # warm-up (compiled forest, aeon's numba kernels)
        print(f"fitted {m}: {fit_s[m]:.1f} s, test accuracy {100 * acc[m]:.1f} %", flush=True)

    rng = np.random.default_rng(0)
    wall = {m: [] for m in methods}
    cpu = {m: [] for m in methods}
    for _ in range(args.runs):
        chosen = rng.choice(te, size=min(args.captures, len(te)), replace=False)
        w_run = {m: [] for m in methods}
        c_run = {m: [] for m in methods}
        for i in chosen:
            for m in methods:
                c0, t0 = time.thread_time(), time.perf_counter()
                fitted[m]([i])
                w_run[m].append(time.perf_counter() - t0)
                c_run[m].append(time.thread_time() - c0)
        for m in methods:
            wall[m].append(1000 * float(np.median(w_run[m])))
            cpu[m].append(1000 * float(np.median(c_run[m])))

    load = os.getloadavg()
    print(f"\none capture (432 x 8 x 8) -> label, one core (cpu {cpus[-1]}), load average {load[0]:.1f}; "
          f"median over {args.runs} runs of the median over {args.captures} captures")
    ref = "minirocket" if "minirocket" in methods else None
    print(f"{'method':16s} {'test acc %':>10s} {'CPU ms':>8s} {'wall ms':>8s} {'fit s':>7s}" + (f" {'x faster than minirocket (CPU)':>32s}" if ref else ""))
    for m in sorted(methods, key=lambda k: np.median(cpu[k])):
        line = f"{m:16s} {100 * acc[m]:10.1f} {np.median(cpu[m]):8.2f} {np.median(wall[m]):8.2f} {fit_s[m]:7.1f}"
        if ref:
            line += f" {np.median(cpu[ref]) / np.median(cpu[m]):32.1f}"
        print(line)


if __name__ == "__main__":
    main()
