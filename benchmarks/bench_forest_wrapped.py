"""Classifier time per stream decision for touchbench's extra-trees: the flat-array walk vs scikit-learn.

    python benchmarks/bench_forest_wrapped.py [--method touch-et] [--runs 7] [--decisions 100]
    python benchmarks/bench_forest_wrapped.py --dataset haart-sample --method touch-et-fast --runs 1 --decisions 2

The model: the method ``--method`` (default ``touch-et``: touch-rhythm +
cell-rhythm + contact-motion -> ``touch-extra-trees``, 500 trees, whose
estimator wraps a scikit-learn ``ExtraTreesClassifier`` behind an
importance-ranked column subset) fitted with :func:`touchbench.deploy.model.fit_model`
on the training captures of ``haart-challenge`` (seed 0), as ``touchbench train``
fits it. A decision classifies one window: here one test capture's feature
row, computed beforehand (the features cost the same on every path).

Paths, each timed on the same ``--decisions`` rows, interleaved, per run:

- ``flat walk``: what ``predict`` / ``stream`` now use,
  ``TrainedModel.proba_from_features`` through the compiled forest of the
  wrapped estimator (:mod:`touchbench.classifiers.fastforest`);
- ``scikit-learn``: the wrapped forest's own ``predict_proba`` on the
  selected columns (one Python call per tree);
- ``wrapper``: the wrapping estimator's ``predict_proba`` (input checks,
  then its own few-rows walk), what a model file used before the walk
  saw through wrappers.

A run's figure is the median over its decisions; the script prints the
median over runs, as wall time and as the thread's CPU time, side by side,
and checks that the three agree to 1e-12. One core: pinned to one CPU,
BLAS/OpenMP limited to one thread before numpy is imported.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402


def fitted_model(method: str, dataset: str = "haart-challenge"):
    """The model (fitted on the training captures of ``dataset``'s challenge split) and the test captures'
    feature rows."""
    from touchbench.catalog import load_dataset
    from touchbench.deploy.model import fit_model
    from touchbench.methods import method_spec

    ds = load_dataset(dataset)
    split = ds.meta["split"].astype(str).to_numpy()
    t0 = time.perf_counter()
    model = fit_model(ds.subset(np.flatnonzero(split == "train")), method_spec(method), seed=0)
    print(f"fitted {method} in {time.perf_counter() - t0:.0f} s", flush=True)
    test = [ds.captures[i] for i in np.flatnonzero(split == "test")]
    return model, np.asarray(model.transform(test), dtype=np.float64)


def paths(model):
    """The three ways to a decision's probabilities (module docstring), by name."""
    est = model.estimator
    forest, columns = est.forest_and_columns()
    return {
        "flat walk": lambda x: model.proba_from_features(x, fast=True),
        "scikit-learn": lambda x: forest.predict_proba(x[:, columns]),
        "wrapper": lambda x: est.predict_proba(x),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--method", default="touch-et")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--decisions", type=int, default=100, help="feature rows classified one at a time per run")
    ap.add_argument("--dataset", default="haart-challenge", help="captures with a train/test split column")
    args = ap.parse_args()
    cpus = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpus[-1]})
    model, X = fitted_model(args.method, args.dataset)
    ways = paths(model)
    for x in X[:20]:  # warm-up (the compiled arrays), and the paths agree
        got = {k: f(x[None, :]) for k, f in ways.items()}
        for k in got:
            np.testing.assert_allclose(got[k], got["scikit-learn"], rtol=0, atol=1e-12)
    rng = np.random.default_rng(0)
    wall = {k: [] for k in ways}
    cpu = {k: [] for k in ways}
    for _ in range(args.runs):
        rows = rng.choice(len(X), size=min(args.decisions, len(X)), replace=False)
        w_run = {k: [] for k in ways}
        c_run = {k: [] for k in ways}
        for i in rows:
            for k, f in ways.items():
                c0, t0 = time.thread_time(), time.perf_counter()
                f(X[i:i + 1])
                w_run[k].append(time.perf_counter() - t0)
                c_run[k].append(time.thread_time() - c0)
        for k in ways:
            wall[k].append(1000 * float(np.median(w_run[k])))
            cpu[k].append(1000 * float(np.median(c_run[k])))
    est = model.estimator
    print(f"\n{args.method}: {len(est.forest_and_columns()[0].estimators_)} trees, one row per decision, one core "
          f"(cpu {cpus[-1]}), load average {os.getloadavg()[0]:.1f}; median over {args.runs} runs of the median "
          f"over {args.decisions} decisions")
    print(f"{'path':14s} {'CPU ms':>8s} {'wall ms':>8s} {'x vs scikit-learn (CPU)':>24s}")
    for k in ways:
        print(f"{k:14s} {np.median(cpu[k]):8.3f} {np.median(wall[k]):8.3f} "
              f"{np.median(cpu['scikit-learn']) / np.median(cpu[k]):24.1f}")


if __name__ == "__main__":
    main()
