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
  (A. B. Owen 2007, "The pigeonhole bootstrap", Annals of Applied
  Statistics 1(2):386-411, Sec. 2-3): each resample draws the ``R`` rows
  (captures) with replacement and, independently, the ``C`` columns (seeds)
  with replacement, and takes the mean of the ``R x C`` cells so chosen
  (with the draws' counts ``w_r``, ``w_c``: ``w_r' Y w_c / (R C)``). Its
  variance estimates ``var(mean) = s_A^2 / R + s_B^2 / C + s_E^2 / (R C)``
  (capture, seed and interaction components), erring on the large side by
  about the interaction term (Owen 2007, Theorem 2: the pigeonhole bootstrap
  is mildly conservative), where a bootstrap over the captures alone misses
  ``s_B^2 / C``. :data:`PIGEONHOLE_RESAMPLES` resamples, seeded
  (:data:`PIGEONHOLE_SEED`), float64.
- The interval: the 2.5 and 97.5 percentiles of the resampled means
  (``ci_method`` ``"pigeonhole"``), of ``Y`` for a method's accuracy, of
  ``D`` for a difference.
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

**Degenerate input** (defined, never from resampling noise): every cell
equal (one capture and one seed, a deterministic method right on the same
captures with every seed and a constant matrix...) gives the interval
``[mean, mean]`` (width 0); a difference of zero everywhere gives ``p = 1``
and one-sided p-values 1/2, as McNemar's test without a discordant capture.
A single seed is a bootstrap over the captures alone (column draws of one
column change nothing). The interval always holds the observed mean: the
percentile interval is widened to it in the rare case resampling leaves it
outside.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from .labels import _pct
from .paired import _compare, _latest
from .stats import PairedTest, _d_z

__all__ = ["CI_NOTES", "PIGEONHOLE", "PIGEONHOLE_RESAMPLES", "PIGEONHOLE_SEED", "compare_pair", "legend_note",
           "pigeonhole_interval", "pigeonhole_means", "pigeonhole_test", "seed_fields", "seed_matrix", "seed_test",
           "seeds_note"]

#: the test and interval's name in a table's rows (``test``, ``ci_method``, ``diff_ci_method``)
PIGEONHOLE = "pigeonhole"
#: resamples of the pigeonhole bootstrap
PIGEONHOLE_RESAMPLES = 10000
#: its seed: the same interval and p on every reading of the results
PIGEONHOLE_SEED = 0
_CHUNK = 500  # resamples computed at once (memory: _CHUNK x captures float64)


def _matrix(y: Any) -> np.ndarray:
    x = np.asarray(y, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.size == 0:
        raise ValueError(f"a captures x seeds matrix with at least one cell is needed, not shape {x.shape}")
    return x


def pigeonhole_means(y: Any, resamples: int = PIGEONHOLE_RESAMPLES, seed: int = PIGEONHOLE_SEED) -> np.ndarray:
    """The means of ``resamples`` pigeonhole resamples of ``y`` (rows: captures, columns: seeds; see
    the module docstring): rows and columns drawn independently with replacement, float64."""
    x = _matrix(y)
    r, c = x.shape
    rng = np.random.default_rng(seed)
    out = np.empty(resamples, dtype=np.float64)
    for start in range(0, resamples, _CHUNK):
        b = min(_CHUNK, resamples - start)
        w_r = rng.multinomial(r, np.full(r, 1.0 / r), size=b).astype(np.float64)  # b x R counts
        w_c = rng.multinomial(c, np.full(c, 1.0 / c), size=b).astype(np.float64)  # b x C counts
        out[start:start + b] = np.einsum("br,br->b", w_r, w_c @ x.T) / (r * c)
    return out


def _constant(x: np.ndarray) -> bool:
    return bool(np.ptp(x) == 0.0)


def pigeonhole_interval(y: Any, level: float = 0.95, resamples: int = PIGEONHOLE_RESAMPLES,
                        seed: int = PIGEONHOLE_SEED) -> tuple[float, float, float]:
    """``(mean, low, high)``: the mean of ``y`` (captures x seeds) and the percentile interval of its
    pigeonhole resamples; ``[mean, mean]`` when every cell is equal (module docstring)."""
    x = _matrix(y)
    if _constant(x):  # the cells' one value, exactly (a sum of equal values may round)
        v = float(x.flat[0])
        return v, v, v
    mean = float(np.mean(x))
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(pigeonhole_means(x, resamples, seed), [tail, 100.0 - tail])
    return mean, min(float(lo), mean), max(float(hi), mean)


def pigeonhole_test(a: Any, b: Any, level: float = 0.95, resamples: int = PIGEONHOLE_RESAMPLES,
                    seed: int = PIGEONHOLE_SEED) -> PairedTest:
    """The paired test of ``a`` against ``b`` (two captures x seeds matrices of correctness, the
    same captures and seed indices): the pigeonhole bootstrap of ``D = a - b`` (module docstring)."""
    xa, xb = _matrix(a), _matrix(b)
    if xa.shape != xb.shape:
        raise ValueError(f"paired matrices differ in shape: {xa.shape} vs {xb.shape}")
    d = xa - xb
    n = d.shape[0]
    per_capture = d.mean(axis=1)
    mean, lo, hi = pigeonhole_interval(d, level, resamples, seed)
    if _constant(d):
        if mean == 0.0:
            return PairedTest(PIGEONHOLE, "capture", n, 0.0, math.nan, 1.0, 0.5, 0.5, math.nan, 0.0, 0.0,
                              PIGEONHOLE, test_ci_low=0.0, test_ci_high=0.0, test_ci_method=PIGEONHOLE)
        theta = np.full(resamples, mean)
    else:
        theta = pigeonhole_means(d, resamples, seed)
    greater = float((1.0 + np.count_nonzero(theta <= 0.0)) / (resamples + 1.0))
    less = float((1.0 + np.count_nonzero(theta >= 0.0)) / (resamples + 1.0))
    sd = float(np.std(theta, ddof=1))
    return PairedTest(PIGEONHOLE, "capture", n, mean, mean / sd if sd > 0 else math.nan,
                      min(1.0, 2.0 * min(greater, less)), greater, less, _d_z(per_capture), lo, hi, PIGEONHOLE,
                      test_ci_low=lo, test_ci_high=hi, test_ci_method=PIGEONHOLE)


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
    (``ci_low``, ``ci_high``, ``ci_method``); ``{}`` otherwise (the table keeps its own)."""
    if len(f) != 1:
        return {}
    per_seed = g.groupby(["repetition", "seed"])["accuracy"].mean().to_numpy(np.float64)
    if len(per_seed) < 2:
        return {}
    out: dict[str, Any] = {"n_seeds": int(len(per_seed)), "accuracy_sd": float(np.std(per_seed, ddof=1)),
                           "seed_min": float(per_seed.min()), "seed_max": float(per_seed.max())}
    y = seed_matrix(preds, method, str(f["fold_key"].iloc[0]))
    if len(y) and len(_seeds(y)) >= 2:
        _, lo, hi = pigeonhole_interval(y[_seeds(y)].to_numpy())
        out.update(ci_low=lo, ci_high=hi, ci_method=PIGEONHOLE)
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
