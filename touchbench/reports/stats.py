"""Statistics of the leaderboard: fold summaries, intervals, paired tests, Holm.

Choices (stated once, used everywhere):

- **Spread and interval over folds.** A method's accuracy is the mean of its
  per-fold accuracies (as Gaus et al. 2015, Sec. 4.1, and Al-mashhadani et
  al. 2021, Table 2, report them); the spread is the sample standard
  deviation (``ddof=1``) and the 95 % interval is Student's t interval
  ``mean +- t(0.975, n-1) * sd / sqrt(n)`` over the ``n`` folds. Folds are
  not independent (their training sets overlap), so the interval is a
  description of fold-to-fold variation, not an exact confidence statement
  (Bengio & Grandvalet 2004); it is still the interval the literature means.
- **One fold** (the challenge split): no spread; the interval is the Wilson
  score interval of the accuracy as a binomial proportion over the test
  captures.
- **Paired test against the best method.** Differences are paired by fold
  (same test captures) or, when the methods share fewer than two folds, by
  test subject. With at most :data:`EXACT_MAX_PAIRS` pairs the test is the
  exact permutation test of the mean difference: all ``2**n`` sign flips of
  the differences are enumerated, and the two-sided p-value is the share of
  flips whose ``|mean|`` is at least the observed one (the same value as
  ``scipy.stats.permutation_test(..., permutation_type="samples",
  n_resamples=inf)``). With more pairs it is the Wilcoxon signed-rank test
  (``scipy.stats.wilcoxon``, zero differences dropped, two-sided, scipy's
  choice of exact or normal distribution). Few pairs cannot reach a small
  p-value: with ``n`` pairs the smallest exact p is ``2 / 2**n`` (0.25 for 3
  subjects, 0.0625 for 5 folds); the leaderboard shows ``n`` beside ``p``.
- **Multiple comparisons.** The p-values of one table (every method against
  the best) are adjusted with Holm's step-down method; a method "differs"
  when its adjusted p is below ``alpha`` (0.05).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np
from scipy import stats

__all__ = [
    "EXACT_MAX_PAIRS",
    "PairedTest",
    "exact_sign_flip_pvalue",
    "fold_interval",
    "holm",
    "paired_test",
    "wilson_interval",
]

#: Up to this many pairs the exact permutation test is used (2**15 = 32768 sign flips).
EXACT_MAX_PAIRS = 15


def fold_interval(values: Sequence[float], level: float = 0.95) -> tuple[float, float, float, float]:
    """``(mean, sd, low, high)`` of per-fold values (accuracies): Student's t interval, clipped to
    [0, 1].

    ``sd`` and the interval are NaN for fewer than two values.
    """

    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    n = len(x)
    if n == 0:
        return (math.nan, math.nan, math.nan, math.nan)
    mean = float(np.mean(x))
    if n < 2:
        return (mean, math.nan, math.nan, math.nan)
    sd = float(np.std(x, ddof=1))
    half = float(stats.t.ppf(0.5 + level / 2.0, n - 1)) * sd / math.sqrt(n)
    # an accuracy lies in [0, 1]: the t interval, symmetric, is clipped there
    return (mean, sd, max(0.0, mean - half), min(1.0, mean + half))


def wilson_interval(successes: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``successes / n``."""

    if n <= 0:
        return (math.nan, math.nan)
    z = float(stats.norm.ppf(0.5 + level / 2.0))
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def exact_sign_flip_pvalue(d: Sequence[float]) -> float:
    """Two-sided exact permutation p-value of the mean of paired differences ``d``.

    Under the null hypothesis each difference is equally likely to have
    either sign; every one of the ``2**n`` sign assignments is enumerated.
    p = #{flips: |mean(s * d)| >= |mean(d)|} / 2**n, with a relative
    tolerance of 1e-9 so that ties in floating point count as ties.
    """
    x = np.asarray(d, dtype=np.float64)
    n = len(x)
    if n == 0:
        return math.nan
    if n > 20:
        raise ValueError(f"exact enumeration of 2**{n} sign flips is too large; use the Wilcoxon test")
    signs = np.array(list(itertools.product((1.0, -1.0), repeat=n)), dtype=np.float64)
    null = np.abs(signs @ x) / n
    obs = abs(float(np.mean(x)))
    tol = 1e-9 * max(1.0, obs)
    return float(np.count_nonzero(null >= obs - tol) / len(null))


@dataclass(frozen=True)
class PairedTest:
    """The result of a paired comparison of ``a`` against ``b`` (``a - b``)."""

    test: str  # "exact-permutation", "wilcoxon" or "none"
    paired_by: str  # "fold", "subject" or ""
    n: int
    mean_difference: float
    statistic: float
    pvalue: float

    def as_dict(self) -> dict:
        return asdict(self)


def paired_test(a: Sequence[float], b: Sequence[float], paired_by: str = "fold",
                exact_max: int = EXACT_MAX_PAIRS) -> PairedTest:
    """Paired two-sided test of ``a`` against ``b`` (see the module docstring).

    Fewer than two pairs: no test (``pvalue`` NaN). All differences zero:
    p = 1 (the methods agree on every pair).
    """

    x = np.asarray(a, dtype=np.float64)
    y = np.asarray(b, dtype=np.float64)
    if x.shape != y.shape:
        raise ValueError(f"paired samples differ in length: {x.shape} vs {y.shape}")
    d = x - y
    keep = np.isfinite(d)
    d = d[keep]
    n = len(d)
    mean_d = float(np.mean(d)) if n else math.nan
    if n < 2:
        return PairedTest("none", paired_by, n, mean_d, math.nan, math.nan)
    if np.all(d == 0):
        test = "exact-permutation" if n <= exact_max else "wilcoxon"
        return PairedTest(test, paired_by, n, 0.0, 0.0, 1.0)
    if n <= exact_max:
        return PairedTest("exact-permutation", paired_by, n, mean_d, mean_d, exact_sign_flip_pvalue(d))
    res = stats.wilcoxon(d, zero_method="wilcox", alternative="two-sided")
    return PairedTest("wilcoxon", paired_by, n, mean_d, float(res.statistic), float(res.pvalue))


def holm(pvalues: Sequence[float]) -> np.ndarray:
    """Holm's step-down adjustment (Holm 1979) of a family of p-values.

    Sorted ascending, ``p_(i)`` (i = 1..m) becomes
    ``max_{j <= i} min(1, (m - j + 1) * p_(j))``; NaN p-values (no test)
    are left out of the family and stay NaN.
    """
    p = np.asarray(pvalues, dtype=np.float64)
    out = np.full(p.shape, np.nan)
    idx = np.flatnonzero(np.isfinite(p))
    m = len(idx)
    if m == 0:
        return out
    order = idx[np.argsort(p[idx], kind="stable")]
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p[i]))
        out[i] = running
    return out
