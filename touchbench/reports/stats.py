"""Statistics of the leaderboard: fold summaries, intervals, the paired test that fits the design,
Holm, and the comparisons across evaluations.

Which test is used when (stated once, used everywhere):

- **Spread and interval over folds.** A method's accuracy is the mean of its
  per-fold accuracies (as Gaus et al. 2015, Sec. 4.1, and Al-mashhadani et
  al. 2021, Table 2, report them); the spread is the sample standard
  deviation (``ddof=1``) and the 95 % interval is Student's t interval
  ``mean +- t(0.975, n-1) * sd / sqrt(n)`` over the ``n`` folds. Folds are
  not independent (their training sets overlap), so the interval is a
  description of fold-to-fold variation, not an exact confidence statement
  (Bengio & Grandvalet 2004); it is still the interval the literature means.
- **One fold** (the challenge split) with one seed: no spread; the interval
  is the Wilson score interval of the accuracy as a binomial proportion over
  the test captures. With several seeds, below ("One test set, several
  seeds").
- **Two methods on one test set** (they share a single fold) with one seed: McNemar's
  exact test on the paired test captures (Dietterich 1998, Sec. 3.1; the
  exact binomial form, since the discordant counts are often small): ``b``
  captures the first method gets right and the second wrong, ``c`` the
  reverse, ``p = binomtest(b, b + c, 1/2)`` two-sided (:func:`mcnemar_exact`).
  A capture evaluated with several seeds counts as right for a method when
  it is right for at least half of that method's seeds. The unit is the
  capture: ``n`` is the number of paired test captures. The test's own
  interval of the difference ``(b - c) / n`` is conditional on the ``b + c``
  discordant captures: the Clopper-Pearson interval ``[L, U]`` of the share
  ``b / (b + c)`` (scipy's ``BinomTestResult.proportion_ci(method="exact")``),
  which inverts the exact binomial test, mapped to ``(b + c) / n * (2 L - 1,
  2 U - 1)`` (Fay 2010, "Two-sided exact tests and matching confidence
  intervals for discrete data", R Journal 2(1): McNemar's exact test with the
  interval of its discordant-pair ratio; at the null share 1/2 the binomial
  is symmetric, so the central interval matches the two-sided test): it
  excludes 0 exactly when ``p < 0.05``. Without a discordant capture there
  is no interval (``p = 1``).
- **Two methods over folds** (k-fold, leave-one-subject-out, repeated
  splits: at least two shared folds): the corrected resampled t-test of
  Nadeau & Bengio (2003, Sec. 4, the "corrected resampled t"): over the
  ``J`` paired fold differences ``d``, ``t = mean(d) / sqrt((1/J +
  n_test/n_train) * var(d))`` with ``J - 1`` degrees of freedom, where
  ``n_test/n_train`` is the mean ratio over the folds; the variance is
  inflated because training sets overlap (:func:`corrected_resampled_t`). The
  unit is the fold: ``n`` is the number of paired folds. Its interval,
  ``mean(d) +- t(0.975, J-1) * se``, inverts the test.
- **Degenerate limits of the corrected t** (float64; ``var(d)`` is zero when
  its sd is at most ``1e-12 * max(1, max |d|)``, the rounding of fold
  accuracies that differ by one same fraction). Every fold differing by the
  same nonzero amount: ``t = mean / 0`` is undefined, and so are ``p``, the
  one-sided p-values, ``d_z`` and the interval (NaN; the test's ``note``
  says "no variance: every fold differs by the same amount"), never
  ``p = 0`` nor an infinite ``t``. Every difference zero (``|mean(d)| <=
  1e-12``): no difference, ``t = 0``, ``p = 1``, one-sided p-values 1/2, no
  interval; ``p`` is the probability under the null of a difference at
  least as far from 0 as the observed one, and nothing is closer than 0 --
  the convention of McNemar's exact test without a discordant pair (above;
  statsmodels' ``mcnemar(exact=True)``: ``min(1, 2 * binom.cdf(0, 0, 1/2))
  = 1``).
- **Interval of a difference.** Where subjects are the unit (a single test
  set holding two or more subjects, or folds that each test one subject, as
  leave-one-subject-out), a percentile bootstrap over the test subjects
  (:func:`subject_bootstrap`: subjects resampled with replacement, the
  difference of the pooled accuracies, :data:`BOOTSTRAP_RESAMPLES`
  resamples, seeded: :data:`BOOTSTRAP_SEED`); it resamples subjects, never
  captures, since captures of one person are not independent. Otherwise, the
  test's own interval: the corrected t interval ``mean(d) +- t(0.975, J-1)
  * sqrt((1/J + n_test/n_train) * var(d))``, or McNemar's exact conditional
  one. The decision is the test's; the bootstrap interval describes the
  difference between people and need not agree with it, so the test's own
  interval is kept beside it (``test_ci_low`` / ``test_ci_high``).
- **One test set, several seeds** (a scheme with a single test set runs every
  method with several seeds): the interval of a method's accuracy and the
  test of two methods resample the captures and the seeds, Owen's pigeonhole
  bootstrap for crossed random effects (the estimator:
  :mod:`touchbench.reports.bootstrap`; the test: :mod:`touchbench.reports.seeds`),
  instead of Wilson's interval and McNemar's test over the captures alone.
- **Multiple comparisons.** The p-values of one table (every method against
  the best) are adjusted with Holm's step-down method; a method "differs"
  when its adjusted p is below ``alpha`` (0.05). An undefined p (above) is
  left out of the family. ``compare`` reports one comparison's p unadjusted.
- **Ranks.** Accuracies equal to 12 significant digits (:data:`RANK_DIGITS`,
  :func:`rank_values`) are one accuracy: the same fractions summed in another
  order differ in their last bits (``0.1 + 0.2 != 0.3``), never by a real
  difference, and get one rank.
- **Across evaluations** (datasets, or schemes of one dataset: each table
  is one data set in Demsar's sense, never its folds): the methods' ranks
  within each table, averaged (Demsar 2006, Sec. 3.2.2); the Friedman test
  over the tables (``scipy.stats.friedmanchisquare``: at least three methods
  and two tables; :func:`friedman`); the Nemenyi critical difference
  ``CD = q_alpha * sqrt(k (k + 1) / (6 N))`` with ``q_alpha`` the
  studentized range quantile over ``sqrt(2)`` (Demsar 2006, Sec. 3.2.2,
  Table 5; :func:`nemenyi_cd`). When even the largest possible rank
  difference ``k - 1`` is below ``CD``, no diagram can separate two methods:
  none is drawn, and :func:`datasets_needed` says how many tables would
  be. One ``alpha`` serves the table tests, Friedman and the diagram.
- **Two methods across evaluations**: a meta-analysis as MOABB's
  (Jayaram & Barachant 2018; ``moabb.analysis.meta_analysis``): per table the
  standardized mean difference of the paired units of its test (Cohen's
  ``d_z = mean(d) / sd(d)``), the one-sided p of "the first is better" from
  the table's test, combined by Stouffer's method weighted by ``sqrt(n)``
  (as ``scipy.stats.combine_pvalues(method="stouffer")``); the combined
  two-sided p is twice the smaller one-sided one (:func:`meta_analysis`).
  A table's ``z`` is taken from its smaller one-sided p, signed
  (``Phi^-1(1 - p_greater)`` when that is the smaller, else ``-Phi^-1(1 -
  p_less)``, 0 when they are equal): for a continuous test it is Stouffer's
  ``z``, computed in the tail where float64 keeps it (``1 - 1e-20`` is 1,
  whose ``z`` is infinite); for McNemar's, whose one-sided p-values add to
  more than 1, it is the same on both sides, so that swapping the methods
  negates every ``z`` and keeps the two-sided p, and a table whose
  differences all favour one method can only push toward it. One-sided
  p-values below the smallest float64 are taken at it (``|z| <= 37.5``). A
  table whose corrected t is undefined (every fold differing by the same
  amount) is left out of the combination and named with the direction of
  its differences: it has no p-value, and a capped ``z`` would be a number of
  our choosing. With no table left, the combined ``z`` and p are undefined.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Sequence

import numpy as np
from scipy import stats

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "Friedman",
    "MetaAnalysis",
    "NO_VARIANCE",
    "ZERO_DIFFERENCE",
    "PairedTest",
    "RANK_DIGITS",
    "TEST_NAMES",
    "TEST_SHORT",
    "corrected_resampled_t",
    "datasets_needed",
    "fold_interval",
    "friedman",
    "holm",
    "mcnemar_exact",
    "meta_analysis",
    "nemenyi_cd",
    "no_test",
    "rank_values",
    "subject_bootstrap",
    "wilson_interval",
]

#: Resamples of the bootstrap over subjects.
BOOTSTRAP_RESAMPLES = 10000
#: Seed of the bootstrap over subjects (the same interval on every run).
BOOTSTRAP_SEED = 0
#: The tests' names as reports write them.
TEST_NAMES = {"mcnemar-exact": "McNemar's exact test", "corrected-t": "corrected resampled t-test",
              "pigeonhole": "pigeonhole bootstrap over captures and seeds", "none": "no test"}
#: The tests' short names, for a table cell.
TEST_SHORT = {"mcnemar-exact": "McNemar", "corrected-t": "corrected t", "pigeonhole": "pigeonhole"}
#: Why a corrected t-test has no p-value: every fold differs by the same amount.
NO_VARIANCE = "no variance: every fold differs by the same amount"
#: A mean of fold differences at most this far from 0 (with no variance) is no difference.
ZERO_DIFFERENCE = 1e-12
#: Significant digits to which accuracies are one when ranked.
RANK_DIGITS = 12


def rank_values(values: Sequence[float], digits: int = RANK_DIGITS) -> np.ndarray:
    """``values`` rounded to ``digits`` significant digits (float64; NaN kept): what ranks
    compare, so that one accuracy computed in another order (``0.1 + 0.2`` and ``0.3``) is one."""
    x = np.asarray(values, dtype=np.float64)
    # Python's formatting rounds correctly at any magnitude; NaN and infinities read back as themselves
    return np.array([float(f"{v:.{digits}g}") for v in x.ravel()], dtype=np.float64).reshape(x.shape)


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


@dataclass(frozen=True)
class PairedTest:
    """A paired comparison of ``a`` against ``b`` (differences ``a - b``).

    ``test``: a key of :data:`TEST_NAMES`; ``paired_by``: the unit (``"capture"`` or ``"fold"``,
    ``""`` when nothing is paired); ``n``: paired units; ``statistic``: McNemar's ``b`` (captures
    only ``a`` gets right) or the corrected t; ``p_greater`` / ``p_less``: one-sided p-values of
    ``a`` better / worse (1/2 each when the pairs say nothing); ``effect_size``: Cohen's ``d_z`` of
    the paired differences; ``ci_low`` / ``ci_high``: 95 % interval of the difference, by
    ``ci_method`` (``"subject-bootstrap"`` over ``n_subjects`` subjects where subjects are the unit,
    else the test's); ``test_ci_low`` / ``test_ci_high``: the 95 % interval that inverts the test
    (``test_ci_method``: ``"exact-conditional"`` for McNemar's, ``"corrected-t"``), which excludes 0
    exactly when ``pvalue < 0.05``; ``note``: why ``pvalue`` is undefined (:data:`NO_VARIANCE`).
    """

    test: str
    paired_by: str
    n: int
    mean_difference: float
    statistic: float
    pvalue: float
    p_greater: float = math.nan
    p_less: float = math.nan
    effect_size: float = math.nan
    ci_low: float = math.nan
    ci_high: float = math.nan
    ci_method: str = ""
    n_subjects: int = 0
    test_ci_low: float = math.nan
    test_ci_high: float = math.nan
    test_ci_method: str = ""
    note: str = ""

    def as_dict(self) -> dict:
        return asdict(self)


def no_test(paired_by: str, d: Sequence[float]) -> PairedTest:
    """No test (fewer than two folds, or no paired capture): the mean difference where there is one."""
    x = np.asarray(d, dtype=np.float64)
    return PairedTest("none", paired_by, len(x), float(np.mean(x)) if len(x) else math.nan, math.nan, math.nan)


def _sd(d: np.ndarray) -> float:
    """The sample sd of paired differences, 0 where it is rounding error (fold accuracies that differ
    by one same fraction differ in their last bits)."""
    sd = float(np.std(d, ddof=1)) if len(d) > 1 else 0.0
    return sd if sd > 1e-12 * max(1.0, float(np.max(np.abs(d)))) else 0.0


def _d_z(d: np.ndarray) -> float:
    """Cohen's ``d_z``: the mean of paired differences over their sample sd (NaN when it is 0)."""
    sd = _sd(d)
    return float(np.mean(d)) / sd if sd > 0 else math.nan


def mcnemar_exact(a_correct: Sequence[bool], b_correct: Sequence[bool], level: float = 0.95) -> PairedTest:
    """McNemar's exact test of two methods' correctness on the same test captures (see the module
    docstring): ``b`` = captures only ``a`` gets right, ``c`` = only ``b``; ``p =
    binomtest(b, b + c, 1/2)``, two-sided; p = 1 without a discordant capture. Its interval
    (``ci_*`` and ``test_ci_*``) is the exact conditional one, Clopper-Pearson's of ``b / (b + c)``
    mapped to the difference (Fay 2010); the one-sided p-values are ``P(X >= b)`` and ``P(X >= c)``
    with ``X ~ Binomial(b + c, 1/2)``, so that swapping the methods swaps them exactly."""
    x = np.asarray(a_correct, dtype=bool)
    y = np.asarray(b_correct, dtype=bool)
    if x.shape != y.shape:
        raise ValueError(f"paired captures differ in number: {x.shape} vs {y.shape}")
    n = len(x)
    if n == 0:
        return no_test("capture", [])
    b, c = int(np.sum(x & ~y)), int(np.sum(~x & y))
    d = x.astype(np.float64) - y.astype(np.float64)
    if b + c == 0:
        return PairedTest("mcnemar-exact", "capture", n, 0.0, 0.0, 1.0, 0.5, 0.5, math.nan)
    res = stats.binomtest(b, b + c, 0.5)
    greater, less = (float(stats.binom.sf(k - 1, b + c, 0.5)) for k in (b, c))
    ci = res.proportion_ci(confidence_level=level, method="exact")
    share = (b + c) / n  # the difference is share * (2 pi - 1), pi the discordant captures a gets right
    lo, hi = share * (2.0 * ci.low - 1.0), share * (2.0 * ci.high - 1.0)
    return PairedTest("mcnemar-exact", "capture", n, (b - c) / n, float(b), float(res.pvalue), greater, less,
                      _d_z(d), lo, hi, "exact-conditional", test_ci_low=lo, test_ci_high=hi,
                      test_ci_method="exact-conditional")


def corrected_resampled_t(d: Sequence[float], test_train_ratio: float, level: float = 0.95) -> PairedTest:
    """Nadeau & Bengio's corrected resampled t-test of paired fold differences ``d`` (see the
    module docstring), with its interval (``ci_*`` and ``test_ci_*``); ``test_train_ratio``: the
    folds' mean ``n_test / n_train``. No variance: undefined (NaN, ``note`` :data:`NO_VARIANCE`)
    unless every difference is 0 (``p = 1``), as the module docstring defines."""
    x = np.asarray(d, dtype=np.float64)
    j = len(x)
    if j < 2 or not np.isfinite(test_train_ratio):
        return no_test("fold", x)
    mean = float(np.mean(x))
    se = math.sqrt(1.0 / j + test_train_ratio) * _sd(x)
    if se == 0.0:
        if abs(mean) <= ZERO_DIFFERENCE:
            return PairedTest("corrected-t", "fold", j, 0.0, 0.0, 1.0, 0.5, 0.5)
        return PairedTest("corrected-t", "fold", j, mean, math.nan, math.nan, note=NO_VARIANCE)
    t = mean / se
    half = float(stats.t.ppf(0.5 + level / 2.0, j - 1)) * se
    lo, hi = mean - half, mean + half
    return PairedTest("corrected-t", "fold", j, mean, t, float(2 * stats.t.sf(abs(t), j - 1)),
                      float(stats.t.sf(t, j - 1)), float(stats.t.cdf(t, j - 1)), _d_z(x),
                      lo, hi, "corrected-t", test_ci_low=lo, test_ci_high=hi, test_ci_method="corrected-t")


def subject_bootstrap(right_a: Sequence[float], right_b: Sequence[float], n: Sequence[float], *,
                      level: float = 0.95, resamples: int = BOOTSTRAP_RESAMPLES,
                      seed: int = BOOTSTRAP_SEED) -> tuple[float, float]:
    """Percentile bootstrap interval of the accuracy difference over subjects: per subject the
    captures ``a`` and ``b`` got right and the captures tested; each resample draws the subjects
    with replacement and takes ``(sum right_a - sum right_b) / sum n``. NaN for fewer than two
    subjects."""
    ra, rb, m = (np.asarray(v, dtype=np.float64) for v in (right_a, right_b, n))
    if len(m) < 2:
        return (math.nan, math.nan)
    idx = np.random.default_rng(seed).integers(0, len(m), size=(resamples, len(m)))
    diff = (ra[idx].sum(axis=1) - rb[idx].sum(axis=1)) / m[idx].sum(axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(diff, [tail, 100.0 - tail])
    return (float(lo), float(hi))


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


@dataclass(frozen=True)
class Friedman:
    """The Friedman test over ``n_datasets`` tables of ``k`` methods, and the Nemenyi critical
    difference at ``alpha`` (NaN statistic and p when there are fewer than three methods or two
    tables)."""

    statistic: float
    pvalue: float
    n_datasets: int
    k: int
    alpha: float
    cd: float

    @property
    def can_separate(self) -> bool:
        """Whether the largest possible mean rank difference (``k - 1``) reaches the critical difference."""
        return self.k >= 2 and self.n_datasets >= 2 and self.k - 1 >= self.cd

    @property
    def datasets_needed(self) -> int:
        return datasets_needed(self.k, self.alpha)


def _q_alpha(k: int, alpha: float) -> float:
    """Demsar's ``q_alpha``: the studentized range quantile of ``k`` means (infinite df) over sqrt(2)."""
    return float(stats.studentized_range.ppf(1.0 - alpha, k, np.inf)) / math.sqrt(2.0)


def nemenyi_cd(k: int, n_datasets: int, alpha: float) -> float:
    """Nemenyi's critical difference of mean ranks: ``q_alpha * sqrt(k (k + 1) / (6 N))``."""
    return _q_alpha(k, alpha) * math.sqrt(k * (k + 1) / (6.0 * n_datasets))


def datasets_needed(k: int, alpha: float) -> int:
    """The fewest tables at which ``k`` methods can be separated: the smallest ``N`` with
    ``k - 1 >= CD``, i.e. ``N >= q_alpha**2 k (k + 1) / (6 (k - 1)**2)`` (at least 2)."""
    return max(2, math.ceil(_q_alpha(k, alpha) ** 2 * k * (k + 1) / (6.0 * (k - 1) ** 2) - 1e-12))


def friedman(scores: np.ndarray, alpha: float) -> Friedman:
    """The Friedman test of ``scores`` (rows: tables, columns: methods; higher is better)."""
    x = np.asarray(scores, dtype=np.float64)
    n, k = x.shape
    cd = nemenyi_cd(k, n, alpha) if k >= 2 and n >= 1 else math.nan
    if k < 3 or n < 2:
        return Friedman(math.nan, math.nan, n, k, alpha, cd)
    res = stats.friedmanchisquare(*x.T)
    return Friedman(float(res.statistic), float(res.pvalue), n, k, alpha, cd)


@dataclass(frozen=True)
class MetaAnalysis:
    """Two methods across tables, per table with a test (in the order given): the effect size
    (``d_z``), units, one-sided p of ``a`` better, its signed ``z`` (``z_tables``) and whether it is
    ``combined`` (False: its p is undefined, NaN ``z``); Stouffer's combined ``z`` (positive: ``a``
    better), the two-sided combined p and the one-sided ones (NaN when no table is combined)."""

    effect_sizes: list[float]
    n: list[int]
    p_greater: list[float]
    z: float
    pvalue: float
    p_greater_combined: float
    p_less_combined: float
    z_tables: list[float] = field(default_factory=list)
    combined: list[bool] = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)


def _signed_z(p_greater: float, p_less: float) -> float:
    """A table's Stouffer ``z`` from its smaller one-sided p, signed (module docstring): positive
    when ``a`` is the better, 0 when the two are equal; NaN when they are undefined."""
    if not (np.isfinite(p_greater) and np.isfinite(p_less)):
        return math.nan
    tiny = np.finfo(np.float64).tiny
    if p_greater < p_less:
        return float(stats.norm.isf(max(p_greater, tiny)))
    if p_less < p_greater:
        return -float(stats.norm.isf(max(p_less, tiny)))
    return 0.0


def meta_analysis(tests: Sequence[PairedTest]) -> MetaAnalysis:
    """MOABB's meta-analysis of one comparison across tables (see the module docstring): Stouffer's
    ``Z = sum(w z) / sqrt(sum w^2)``, ``w = sqrt(n)``; tables without a test are left out, and so
    are those whose p is undefined (``combined`` False)."""
    done = [t for t in tests if t.test != "none"]
    if not done:
        raise ValueError("no table has a test of the two methods to combine")
    z = np.array([_signed_z(t.p_greater, t.p_less) for t in done], dtype=np.float64)
    ok = np.isfinite(z)
    w = np.sqrt(np.array([t.n for t in done], dtype=np.float64))[ok]
    big_z = float(np.sum(w * z[ok]) / math.sqrt(np.sum(w * w))) if ok.any() else math.nan
    greater, less = float(stats.norm.sf(big_z)), float(stats.norm.sf(-big_z))
    return MetaAnalysis([t.effect_size for t in done], [t.n for t in done], [t.p_greater for t in done],
                        big_z, float(2 * stats.norm.sf(abs(big_z))), greater, less,
                        [float(v) for v in z], [bool(v) for v in ok])
