"""The frame-length sweep of Al-mashhadani et al. 2021 (section 3,
Fig. 5), quick version: leave-one-subject-out CNN accuracy for several L
(F = floor(432 / L) frames per window) on the paper's subjects 1, 3, 5 and 7.

Usage::

    python benchmarks/bench_cnn_lsweep.py                   # L = 5, 10, 20, 30, 40, 50
    python benchmarks/bench_cnn_lsweep.py --L 5,10,15,20,25,30,35,40,45,50   # the full Fig. 5 grid

Each (L, subject) cell is one fit, about 15 to 40 s on one core with the
default first-window setting. Measured (shared 2-core machine, seed 0, first
window, held-out-subject early stopping), accuracy for s01 s03 s05 s07, mean:

- L =  5 (F = 86): 54.8 47.0 40.3 61.9, mean 51.0%
- L = 10 (F = 43): 57.1 44.6 49.4 56.0, mean 51.8%
- L = 20 (F = 21): 46.4 54.2 44.2 51.2, mean 49.0%
- L = 30 (F = 14): 52.4 48.2 45.5 53.6, mean 49.9%
- L = 40 (F = 10): 53.6 44.6 37.7 50.0, mean 46.5%
- L = 50 (F =  8): 51.2 43.4 46.8 51.2, mean 48.1%

Flat within fold-to-fold noise; no peak at L = 30 as in the paper's Fig. 5.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_cnn_loso import haart_raw, loso  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--L", default="5,10,20,30,40,50")
    ap.add_argument("--subjects", default="s01,s03,s05,s07")
    ap.add_argument("--windows", default="first")
    ap.add_argument("--max-epochs", type=int, default=100)
    ap.add_argument("--patience", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dataset", default="haart", help="HAART captures to use (haart-sample: a smoke run in seconds)")
    ap.add_argument("--no-groups", dest="use_groups", action="store_false",
                    help="stratified capture split for early stopping instead of held-out training subjects")
    a = ap.parse_args(argv)
    X, y, s, grid, how = haart_raw(a.dataset)
    subjects = a.subjects.split(",")
    print(f"{a.dataset}, {how}; subjects {subjects}; windows {a.windows}; {os.cpu_count()} cores, no GPU")
    print(f"{'L':>3} {'F':>4} " + " ".join(f"{x:>6}" for x in subjects) + "   mean  s/fold")
    for L in [int(v) for v in a.L.split(",")]:
        params = dict(L=L, train_windows=a.windows, test_windows=a.windows, max_epochs=a.max_epochs,
                      patience=a.patience)
        t0 = time.perf_counter()
        rows = loso(X, y, s, grid, subjects, params, a.seed, a.use_groups, log=lambda *_: None)
        accs = [r[1] for r in rows]
        per = (time.perf_counter() - t0) / len(rows)
        print(f"{L:>3} {432 // L:>4} " + " ".join(f"{x:6.1%}" for x in accs) + f" {np.mean(accs):6.1%} {per:6.1f}",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
