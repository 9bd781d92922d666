"""One test set scored with several seeds: the interval and the paired test over captures and seeds.

A scheme with a single test set (a challenge split, a transfer, another
dataset: :attr:`touchbench.protocols.schemes.Splitter.single_test_set`) runs
every method with several seeds (its repetitions). A method's accuracy then
varies with two crossed factors: the test capture and the seed. An interval
over the captures alone (Wilson's) or a test over the captures alone
(McNemar's, each capture's correctness a vote over the seeds) treats the
seeds as fixed, and tells a user comparing two methods of one test set
that a difference is real that another seed reverses.

**What is computed** (a table's method, or a pair of methods, with two or
more seeds on the one test set they share, from the predictions):

- ``Y[i, j]``: 1 when capture ``i`` is right with the method's ``j``-th seed
  (its seeds ordered by repetition), else 0; the captures every seed
  tested. A pair of methods: ``D[i, j] = Y_a[i, j] - Y_b[i, j]`` on the
  captures both tested, the ``j``-th seed of one paired with the ``j``-th of
  the other (the same repetition) for ``j`` below the smaller number of seeds.
- The figure: the mean of ``Y`` (the mean over seeds of the accuracy),
  with the spread of the per-seed accuracies (min, max, sample sd).
- **Owen's pigeonhole bootstrap** for a crossed random-effects design
  (Owen 2007; :mod:`touchbench.reports.bootstrap`, which states the
  estimator, its constants and its degenerate cases): the captures and the
  seeds resampled independently. The interval: the 2.5 and 97.5
  percentiles of the resampled means (``ci_method`` ``"pigeonhole"``), of
  ``Y`` for a method's accuracy, of ``mean(Y_a) - mean(Y_b)`` for a
  difference, the ``j``-th seeds of the two drawn together (``paired``).
- The test of a difference (``test`` ``"pigeonhole"``): one-sided
  ``p_greater = (1 + #{theta* <= 0}) / (B + 1)`` (``a`` better),
  ``p_less = (1 + #{theta* >= 0}) / (B + 1)``, two-sided ``p = min(1, 2
  min(p_greater, p_less))``: the percentile interval's inversion, so it
  excludes 0 when ``p < 0.05`` up to the resampling's resolution. Its
  ``statistic`` is the mean difference over the resamples' sd, ``n`` the
  paired captures, ``effect_size`` Cohen's ``d_z`` of the captures' mean
  differences over the seeds. The
  leaderboard's call "differs from the best" on such a table is this test,
  Holm-adjusted over the table as every test is.

**Degenerate input**: the bootstrap's (every cell equal, or a difference
of one value everywhere: the interval ``[mean, mean]``; fewer than two
captures: no interval). A difference of zero everywhere gives ``p = 1``
and one-sided p-values 1/2, as McNemar's test without a discordant capture;
one of another single value, ``p = 2 / (B + 1)``; fewer than two captures,
no p (``note``: :data:`FEW_CAPTURES`), left out of Holm's family.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from .bootstrap import LEVEL, PIGEONHOLE_RESAMPLES, PIGEONHOLE_SEED, pigeonhole
from .labels import _pct
from .paired import _compare, _latest
from .stats import PairedTest, _d_z

__all__ = ["CI_NOTES", "FEW_CAPTURES", "PIGEONHOLE", "compare_pair", "legend_note", "pigeonhole_test",
           "seed_fields", "seed_matrix", "seed_test", "seeds_note"]

#: the test and interval's name in a table's rows (``test``, ``ci_method``, ``diff_ci_method``)
PIGEONHOLE = "pigeonhole"
#: why a pigeonhole test has no p-value
FEW_CAPTURES = "fewer than two paired captures"


def pigeonhole_test(a: Any, b: Any, level: float = LEVEL, resamples: int = PIGEONHOLE_RESAMPLES,
                    seed: int = PIGEONHOLE_SEED) -> PairedTest:
    """The paired test of ``a`` against ``b`` (two captures x seeds matrices of correctness, the
    same captures and seed indices): the pigeonhole bootstrap of ``mean(a) - mean(b)``, the seeds
    paired (module docstring)."""
    boot = pigeonhole(a, b, paired=True, level=level, resamples=resamples, seed=seed)
    n, mean, lo, hi = boot.captures, boot.mean, boot.low, boot.high
    if not np.isfinite(lo):
        return PairedTest(PIGEONHOLE, "capture", n, mean, math.nan, math.nan, note=FEW_CAPTURES)
    if boot.fixed and mean == 0.0:
        return PairedTest(PIGEONHOLE, "capture", n, 0.0, math.nan, 1.0, 0.5, 0.5, math.nan, 0.0, 0.0,
                          PIGEONHOLE, test_ci_low=0.0, test_ci_high=0.0, test_ci_method=PIGEONHOLE)
    theta = boot.resampled
    greater = float((1.0 + np.count_nonzero(theta <= 0.0)) / (theta.size + 1.0))
    less = float((1.0 + np.count_nonzero(theta >= 0.0)) / (theta.size + 1.0))
    sd = float(np.std(theta, ddof=1))
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    per_capture = d.reshape(len(d), -1).mean(axis=1)
    return PairedTest(PIGEONHOLE, "capture", n, mean, mean / sd if sd > 0 else math.nan,
                      min(1.0, 2.0 * min(greater, less)), greater, less, _d_z(per_capture), lo, hi, PIGEONHOLE, test_ci_low=lo, test_ci_high=hi, test_ci_method=PIGEONHOLE)


# ----------------------------------------------------------------- from a table's predictions
def seed_matrix(preds: pd.DataFrame | None, method: str, fold_key: str) -> pd.DataFrame:
    """``method``'s correctness on the test set ``fold_key``: one row per capture every seed tested
    (index ``capture_id``), one column per seed in repetition order (``0, 1, ...``), float64; an
    extra column ``subject``. Empty when there are no predictions."""
    if preds is None or preds.empty:
        return pd.DataFrame()
    p = preds[(preds["method_id"] == method) & (preds["fold_key"] == fold_key)]
    if p.empty:
        return pd.DataFrame()
    p = _latest(p)
    if "repetition" not in p:  # predictions read without their task's repetition: by seed alone
        p = p.assign(repetition=0)
    runs = sorted({(int(r), int(s)) for r, s in zip(p["repetition"], p["seed"])})
    index = {k: i for i, k in enumerate(runs)}
    p = p.assign(seed_index=[index[(int(r), int(s))] for r, s in zip(p["repetition"], p["seed"])],
                 correct=p["correct"].astype(np.float64))
    y = p.pivot_table(index="capture_id", columns="seed_index", values="correct", aggfunc="mean").dropna()
    y.columns = [int(c) for c in y.columns]
    return y.assign(subject=p.drop_duplicates("capture_id").set_index("capture_id")["subject"].reindex(y.index))


def _seeded_fold(folds: pd.DataFrame, method: str) -> str | None:
    """The one test set (fold key) of ``method`` in the table, or None when it has several."""
    keys = folds.loc[folds["method_id"] == method, "fold_key"]
    return str(keys.iloc[0]) if len(keys) == 1 else None


def _seeds(y: pd.DataFrame) -> list[int]:
    return [c for c in y.columns if c != "subject"]


def seed_fields(g: pd.DataFrame, f: pd.DataFrame, preds: pd.DataFrame | None, method: str) -> dict[str, Any]:
    """A leaderboard row's fields for a method with several seeds on its one test set (``g``: its
    scores, ``f``: its fold values): the spread of its per-seed accuracies (``n_seeds``,
    ``accuracy_sd``, ``seed_min``, ``seed_max``) and the pigeonhole interval over captures and seeds
    (``ci_low``, ``ci_high``, ``ci_method``; where it has one: two or more captures); ``{}`` otherwise
    (the table keeps its own)."""
    if len(f) != 1:
        return {}
    per_seed = g.groupby(["repetition", "seed"])["accuracy"].mean().to_numpy(np.float64)
    if len(per_seed) < 2:
        return {}
    out: dict[str, Any] = {"n_seeds": int(len(per_seed)), "accuracy_sd": float(np.std(per_seed, ddof=1)),
                           "seed_min": float(per_seed.min()), "seed_max": float(per_seed.max())}
    y = seed_matrix(preds, method, str(f["fold_key"].iloc[0]))
    if len(y) and len(_seeds(y)) >= 2:
        boot = pigeonhole(y[_seeds(y)].to_numpy())
        if np.isfinite(boot.low):
            out.update(ci_low=boot.low, ci_high=boot.high, ci_method=PIGEONHOLE)
    return out


def seed_test(folds: pd.DataFrame, preds: pd.DataFrame | None, a: str,
              b: str) -> tuple[PairedTest, pd.DataFrame] | None:
    """The pigeonhole test of ``a`` against ``b`` when both scored one same test set with two or more
    paired seeds, with the pairs (one row per capture: ``unit``, ``a``, ``b`` the mean correctness
    over the paired seeds, ``subject``, ``fold_key``); None otherwise (another test fits)."""
    key = _seeded_fold(folds, a)
    if key is None or key != _seeded_fold(folds, b):
        return None
    ya, yb = seed_matrix(preds, a, key), seed_matrix(preds, b, key)
    if ya.empty or yb.empty:
        return None
    cols = [c for c in _seeds(ya) if c in _seeds(yb)]
    caps = ya.index.intersection(yb.index)
    if len(cols) < 2 or not len(caps):
        return None
    ma, mb = ya.loc[caps, cols].to_numpy(), yb.loc[caps, cols].to_numpy()
    pairs = pd.DataFrame({"unit": caps.astype(str), "a": ma.mean(axis=1), "b": mb.mean(axis=1),
                          "subject": ya.loc[caps, "subject"].to_numpy(), "fold_key": key})
    return pigeonhole_test(ma, mb), pairs


def compare_pair(folds: pd.DataFrame, preds: pd.DataFrame | None, a: str, b: str) -> tuple[PairedTest, pd.DataFrame]:
    """The paired test of ``a`` against ``b`` in a table and its pairs: the pigeonhole test where they
    share one test set scored with several seeds (:func:`seed_test`), else the test that fits their
    pairing (:func:`touchbench.reports.paired._compare`)."""
    return seed_test(folds, preds, a, b) or _compare(folds, preds, a, b)


#: the note after an interval of a single test set, by its method (the rows' ``ci_method``)
CI_NOTES = {"wilson": "Wilson", PIGEONHOLE: "captures × seeds"}


def seeds_note(r: Any, sep: str = " ") -> str:
    """The note after a single test set's accuracy scored with several seeds: their number and the
    range of their accuracies (``sep`` before it); "" for any other row."""
    n = r.get("n_seeds", 1)
    if r["ci_method"] not in CI_NOTES or not n or n <= 1:
        return ""
    lo, hi = r.get("seed_min", math.nan), r.get("seed_max", math.nan)
    span = f", {_pct(lo)}–{_pct(hi)}" if np.isfinite(lo) and np.isfinite(hi) else ""
    return f"{sep}({int(n)} seeds{span})"


def legend_note(rows: pd.DataFrame) -> str:
    """The legend's sentence for a table whose rows use the pigeonhole bootstrap ("" when none does)."""
    used = ("ci_method" in rows and bool((rows["ci_method"] == PIGEONHOLE).any())) or \
        ("test" in rows and bool((rows["test"] == PIGEONHOLE).any()))
    if not used:
        return ""
    return (" One test set scored with several seeds: the accuracy is the mean over the seeds (sd, min–max over "
            "them); its interval and the test against the best resample the test captures and the seeds "
            "(Owen's pigeonhole bootstrap, 2007), so a difference that another seed reverses is not called one.")
