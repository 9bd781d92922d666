"""Leave-one-subject-out CNN on real HAART (Al-mashhadani et al.
2021, Table 2: 83.2% +- 13%).

Loads real HAART with ``touchbench.catalog.load_dataset("haart")``, turns
every capture into the ``raw-window`` feature set (all 432 frames; the CNN
cuts its own sub-windows), and for each of the 10 subjects trains the
``cnn`` classifier on the other nine and tests on that one. Prints per-fold
accuracy and time, then mean (and population standard deviation across
folds, as the paper's Table 2 reports one) and mean time per fold.

The early-stopping validation split comes from the training fold only:
with ``--use-groups`` (default) whole training subjects are held out
(``fit(X, y, groups=subjects)``), otherwise a stratified capture split.

Usage::

    python benchmarks/bench_cnn_loso.py                       # the paper's setting: first window, L = 30
    python benchmarks/bench_cnn_loso.py --windows all --max-epochs 30 --patience 5
    python benchmarks/bench_cnn_loso.py --L 10 --subjects s01,s03,s05,s07

This is a benchmark, not a test: it takes minutes. Measured on a shared
2-core x86_64 machine, no GPU, one torch thread, seed 0, early stopping on
one held-out training subject (the machine was loaded, so times are upper
bounds):

- paper setting (first window, L = 30, max 100 epochs, patience 10):
  per fold 52.4, 54.2, 48.2, 44.0, 45.5, 38.6, 53.6, 46.4, 46.4, 33.3%;
  mean 46.3% (sd 6.2%); 34 s per fold (5.6 min in all);
- ``--windows all --max-epochs 30 --patience 5`` (all 30 windows of every
  capture for training, soft vote over the 30 test windows): 63.1, 69.9,
  63.9, 71.4, 59.7, 63.9, 66.7, 56.0, 78.6, 46.4%; mean 63.9% (sd 8.4%);
  253 s per fold (42 min).

The paper reports 83.2% (sd 13%); see touchbench/classifiers/cnn.py for
what the paper leaves unspecified (optimiser, epochs, scaling).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np


def haart_raw(dataset: str = "haart"):
    """(X, gestures, subjects) of real HAART (or another dataset of 432-frame HAART captures, such as
    ``haart-sample``), X from the ``raw-window`` set."""
    from touchbench.catalog import load_dataset

    ds = load_dataset(dataset)
    try:
        from touchbench.features.base import FEATURES

        X = FEATURES.create("raw-window", frames=432, shorter="pad").fit_transform(ds.captures)  # HAART: 432 frames
        how = "raw-window feature set"
    except Exception as e:  # the feature set is another module's; fall back to stacking the frames
        X = np.stack([np.asarray(c, dtype=np.float64).reshape(-1) for c in ds.captures])
        how = f"stacked frames (raw-window unavailable: {e})"
    y = ds.meta["gesture"].astype(str).to_numpy()
    s = ds.meta["subject"].astype(str).to_numpy()
    return np.asarray(X, dtype=np.float64), y, s, ds.sensor.grid, how


def loso(X, y, s, grid, subjects, params, seed, use_groups, log=print):
    from touchbench.classifiers import make_classifier

    rows = []
    for subj in subjects:
        te = s == subj
        tr = ~te
        clf = make_classifier("cnn", random_state=seed, grid=tuple(grid), **params)
        t0 = time.perf_counter()
        clf.fit(X[tr], y[tr], groups=s[tr] if use_groups else None)
        fit_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        acc = float(np.mean(clf.predict(X[te]) == y[te]))
        pred_s = time.perf_counter() - t0
        rows.append((subj, acc, fit_s + pred_s, clf.n_epochs_, clf.best_epoch_, int(te.sum())))
        log(f"  {subj}: accuracy {acc:6.1%}  ({int(te.sum())} captures)  time {fit_s + pred_s:6.1f} s"
            f"  epochs {clf.n_epochs_} (best {clf.best_epoch_})")
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--L", type=int, default=30, help="windows per capture (F = floor(432 / L)); 30 in the paper")
    ap.add_argument("--windows", default="first", help="train and test windows: 'first' (paper) or 'all'")
    ap.add_argument("--vote", default="soft", choices=["soft", "hard"])
    ap.add_argument("--max-epochs", type=int, default=100)
    ap.add_argument("--patience", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--subjects", default=None, help="comma-separated subset, e.g. s01,s03 (default: all)")
    ap.add_argument("--dataset", default="haart", help="HAART captures to use (haart-sample: a smoke run in seconds)")
    ap.add_argument("--no-groups", dest="use_groups", action="store_false",
                    help="stratified capture split for early stopping instead of held-out training subjects")
    a = ap.parse_args(argv)

    t0 = time.perf_counter()
    X, y, s, grid, how = haart_raw(a.dataset)
    subjects = a.subjects.split(",") if a.subjects else sorted(set(s))
    params = dict(L=a.L, train_windows=a.windows, test_windows=a.windows, vote=a.vote,
                  max_epochs=a.max_epochs, patience=a.patience, n_jobs=a.threads)
    print(f"{a.dataset}: {X.shape[0]} captures x {X.shape[1]} values ({how}); load {time.perf_counter() - t0:.1f} s")
    print(f"machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}, no GPU used; "
          f"python {sys.version.split()[0]}")
    print(f"cnn params: {params}, seed {a.seed}, early stopping on "
          + ("held-out training subjects" if a.use_groups else "a stratified split of training captures"))
    rows = loso(X, y, s, grid, subjects, params, a.seed, a.use_groups)
    accs = np.array([r[1] for r in rows])
    times = np.array([r[2] for r in rows])
    n = np.array([r[5] for r in rows])
    print(f"mean accuracy over {len(rows)} folds: {accs.mean():.1%} (sd {accs.std():.1%});"
          f" pooled over captures: {np.sum(accs * n) / n.sum():.1%}")
    print(f"time per fold: mean {times.mean():.1f} s, total {times.sum() / 60:.1f} min")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
