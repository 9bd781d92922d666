"""Decision latency of ``touchbench stream`` on one core: p50 and p99.

    python benchmarks/bench_stream.py [--model m.joblib] [--trees 1000]
    python benchmarks/bench_stream.py --dataset haart-sample --trees 2 --sklearn-decisions 2   # seconds

The model: the five Gaus et al. feature sets (SD, BMH, MSD, SMMHH, LBP-TOP)
and their random forest (``gaus-rf``, 1000 trees), trained on 2-second
windows (training hop 2 s) of every HAART capture of subjects s02..s10
(``--model`` reuses a saved one). The stream: the 84 captures of subject
s01 one after another (about 11 minutes of frames), replayed as fast as the
recogniser takes them, a decision every 0.5 s.

Configurations:

- ``2s``: one 2-second window (the recogniser's default for this model);
- ``1s+2s``: two windows at once, the most confident decides (Flagg 2012,
  section 4.5; the model was trained on 2-s windows only, so this line is
  about latency, not accuracy);
- ``2s-sklearn``: one window, but the forest's own ``predict_proba``
  instead of the flat-array walk (same probabilities; on the first
  ``--sklearn-decisions`` decisions only, it is slow).

One core: the process is pinned to one CPU and BLAS/OpenMP limited to one
thread before numpy is imported. Latency per decision: features of every
window + classifier + combination (see ``touchbench.deploy.stream``), as
wall time (what ``touchbench stream`` reports; on a busy machine it includes
waiting for the core) and as the thread's CPU time (the work itself; equal
to wall time on an idle core).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

GAUS = [("sd", {}), ("bmh", {}), ("msd", {}), ("smmhh", {}), ("lbptop", {})]


def pin_one_core() -> int:
    cpus = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpus[-1]})
    return cpus[-1]


def train(ds, trees: int, out: Path | None):
    from touchbench.deploy.model import fit_model
    from touchbench.methods import MethodSpec

    train_ds = ds.subset(np.flatnonzero(ds.meta["subject"].to_numpy() != "s01"))
    t0 = time.perf_counter()
    spec = MethodSpec("gaus-rf", tuple(GAUS), "gaus-rf", {"n_estimators": trees})
    model = fit_model(train_ds, spec, seed=0, windows=[2.0], train_hop=2.0,
                      features_label="sd+bmh+msd+smmhh+lbptop", label="gaus-rf", selection="haart subjects s02..s10")
    print(f"trained in {time.perf_counter() - t0:.0f} s on {model.manifest['dataset']['n_samples']} windows",
          file=sys.stderr)
    if out is not None:
        model.save(out)
    return model


def stream(model, frames, truth, windows, fast=True, limit=None):
    from touchbench.deploy.stream import SlidingRecognizer

    rec = SlidingRecognizer(model, windows_s=windows, hop_s=0.5, threshold=0.5, fast=fast)
    rec.warm_up()
    lat, cpu, correct, n = [], [], 0, 0
    for i, f in enumerate(frames):
        c0 = time.thread_time()
        d = rec.push(f)
        if d is None:
            continue
        cpu.append(1000 * (time.thread_time() - c0))
        lat.append(d.latency_ms)
        correct += d.best == truth[i]
        n += 1
        if limit and n >= limit:
            break
    a, c = np.asarray(lat), np.asarray(cpu)
    return {"decisions": n, "p50_ms": float(np.percentile(a, 50)), "p99_ms": float(np.percentile(a, 99)),
            "max_ms": float(a.max()), "cpu_p50_ms": float(np.percentile(c, 50)),
            "cpu_p99_ms": float(np.percentile(c, 99)), "window_accuracy": correct / n}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=None, help="Load this model if it exists, else train and save it there.")
    ap.add_argument("--trees", type=int, default=1000)
    ap.add_argument("--sklearn-decisions", type=int, default=100)
    ap.add_argument("--json", default=None)
    ap.add_argument("--dataset", default="haart", help="HAART captures (s01 streamed, the others trained on)")
    args = ap.parse_args(argv)
    cpu = pin_one_core()

    from touchbench.catalog import load_dataset
    from touchbench.core.threads import single_thread
    from touchbench.deploy.model import TrainedModel

    ds = load_dataset(args.dataset)
    path = Path(args.model) if args.model else None
    model = TrainedModel.load(path) if path is not None and path.is_file() else train(ds, args.trees, path)
    s01 = np.flatnonzero(ds.meta["subject"].to_numpy() == "s01")
    frames = np.concatenate([ds.captures[i] for i in s01])
    truth = np.concatenate([[ds.meta["gesture"].iloc[i]] * ds.captures[i].shape[0] for i in s01])
    print(f"pinned to cpu {cpu}; {len(s01)} captures of s01, {len(frames)} frames; "
          f"load average {os.getloadavg()[0]:.1f}", file=sys.stderr)
    out = {}
    with single_thread():
        out["2s"] = stream(model, frames, truth, [2.0])
        out["1s+2s"] = stream(model, frames, truth, [1.0, 2.0])
        out["2s-sklearn"] = stream(model, frames, truth, [2.0], fast=False, limit=args.sklearn_decisions)
    for k, r in out.items():
        print(f"{k:11s} {r['decisions']:5d} decisions  wall p50 {r['p50_ms']:6.2f} ms  p99 {r['p99_ms']:6.2f} ms  "
              f"max {r['max_ms']:7.2f} ms | CPU p50 {r['cpu_p50_ms']:6.2f} ms  p99 {r['cpu_p99_ms']:6.2f} ms | "
              f"window accuracy {100 * r['window_accuracy']:.1f}%")
    out["trees"] = len(model.estimator.estimators_)
    out["load_average_end"] = os.getloadavg()[0]
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
