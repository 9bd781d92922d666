"""Statistics of the leaderboard against hand computation and scipy called directly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from touchbench.reports.pareto import pareto_front
from touchbench.reports.stats import (
    corrected_resampled_t,
    datasets_needed,
    fold_interval,
    friedman,
    holm,
    mcnemar_exact,
    meta_analysis,
    nemenyi_cd,
    no_test,
    subject_bootstrap,
    wilson_interval,
)


def test_fold_interval_by_hand():
    # mean 0.7, sd 0.1, t(0.975, 2) = 4.302652729..., half = 4.3027 * 0.1 / sqrt(3) = 0.248414
    mean, sd, lo, hi = fold_interval([0.6, 0.7, 0.8])  # within [0, 1]: not clipped
    assert mean == pytest.approx(0.7)
    assert sd == pytest.approx(0.1)
    assert lo == pytest.approx(0.7 - 0.2484138, abs=1e-6)
    assert hi == pytest.approx(0.7 + 0.2484138, abs=1e-6)


def test_fold_interval_is_clipped_to_0_and_1():
    # mean 0.9, sd 0.1 over 3 folds: 0.9 + 0.2484138 = 1.148 runs past an accuracy's 1
    mean, sd, lo, hi = fold_interval([0.8, 0.9, 1.0])
    assert (lo, hi) == (pytest.approx(0.9 - 0.2484138, abs=1e-6), 1.0)
    # mean 0.1: 0.1 - 0.2484 < 0
    mean, sd, lo, hi = fold_interval([0.0, 0.1, 0.2])
    assert (lo, hi) == (0.0, pytest.approx(0.1 + 0.2484138, abs=1e-6))


def test_fold_interval_single_value_has_no_spread():
    mean, sd, lo, hi = fold_interval([0.66])
    assert mean == pytest.approx(0.66)
    assert math.isnan(sd) and math.isnan(lo) and math.isnan(hi)


def test_wilson_interval_known_value():
    # 8 of 10: the textbook Wilson 95 % interval is (0.4902, 0.9433)
    lo, hi = wilson_interval(8, 10)
    assert lo == pytest.approx(0.4902, abs=1e-4)
    assert hi == pytest.approx(0.9433, abs=1e-4)


def test_mcnemar_exact_by_hand_and_against_scipy():
    # a right and b wrong on 5 captures, never the reverse: p = 2 * (1/2)**5
    a = np.array([1, 1, 1, 1, 1, 1, 0, 1], dtype=bool)
    b = np.array([0, 0, 0, 0, 0, 1, 0, 1], dtype=bool)
    t = mcnemar_exact(a, b)
    assert (t.test, t.paired_by, t.n, t.statistic) == ("mcnemar-exact", "capture", 8, 5.0)
    assert t.pvalue == pytest.approx(2 / 32)
    assert t.p_greater == pytest.approx(1 / 32) and t.p_less == pytest.approx(1.0)
    assert t.mean_difference == pytest.approx(5 / 8)
    rng = np.random.default_rng(3)
    a, b = rng.random(300) < 0.7, rng.random(300) < 0.6
    n10, n01 = int(np.sum(a & ~b)), int(np.sum(~a & b))
    t = mcnemar_exact(a, b)
    assert t.pvalue == pytest.approx(stats.binomtest(n10, n10 + n01, 0.5).pvalue, rel=1e-12)
    assert t.mean_difference == pytest.approx(a.mean() - b.mean())
    # no discordant capture: nothing against the null
    same = mcnemar_exact(a, a)
    assert same.pvalue == 1.0 and same.mean_difference == 0.0
    with pytest.raises(ValueError):
        mcnemar_exact([True], [True, False])


def test_corrected_resampled_t_by_hand():
    # d: mean 0.03, sample variance (1 + 4 + 4 + 1 + 0)e-4 / 4 = 2.5e-4; n_test / n_train = 1/4:
    # se = sqrt((1/5 + 1/4) * 2.5e-4) = sqrt(1.125e-4), t = 0.03 / se = 2 sqrt(2), 4 df
    d = [0.02, 0.05, 0.01, 0.04, 0.03]
    t = corrected_resampled_t(d, 0.25)
    se = math.sqrt(1.125e-4)
    assert t.test == "corrected-t" and t.n == 5 and t.paired_by == "fold"
    assert t.statistic == pytest.approx(2 * math.sqrt(2))
    assert t.pvalue == pytest.approx(2 * stats.t.sf(2 * math.sqrt(2), 4))
    # the uncorrected paired t (scipy) is larger: the correction inflates the variance
    assert stats.ttest_1samp(d, 0.0).statistic == pytest.approx(0.03 / math.sqrt(2.5e-4 / 5))
    assert t.pvalue > stats.ttest_1samp(d, 0.0).pvalue
    half = stats.t.ppf(0.975, 4) * se
    assert (t.ci_low, t.ci_high) == (pytest.approx(0.03 - half), pytest.approx(0.03 + half))
    assert t.effect_size == pytest.approx(0.03 / math.sqrt(2.5e-4))
    assert t.p_greater == pytest.approx(stats.t.sf(2 * math.sqrt(2), 4))
    assert corrected_resampled_t([0.1], 0.25).test == "none"
    assert corrected_resampled_t([0.0, 0.0, 0.0], 0.25).pvalue == 1.0


def test_subject_bootstrap_by_hand():
    # two subjects of 10 captures, differences 0 and 2 of 10: a resample is {1, 1} (0), {1, 2} or
    # {2, 1} (0.1) or {2, 2} (0.2), each pair with probability 1/4: 2.5 % and 97.5 % quantiles 0 and 0.2
    lo, hi = subject_bootstrap([8, 9], [8, 7], [10, 10])
    assert (lo, hi) == (pytest.approx(0.0), pytest.approx(0.2))
    assert subject_bootstrap([8, 9], [8, 7], [10, 10]) == (lo, hi)  # seeded
    assert all(math.isnan(v) for v in subject_bootstrap([8], [7], [10]))


def test_friedman_by_hand_and_against_scipy():
    # ranks per table (1 = best): [1,2,3], [1,2,3], [1,3,2], [1,2,3]: rank sums 4, 9, 11; chi2 =
    # 12 / (N k (k+1)) * sum R^2 - 3 N (k+1) = 12 / 48 * 218 - 48 = 6.5; 2 df: p = exp(-6.5 / 2)
    acc = np.array([[0.9, 0.8, 0.7], [0.95, 0.7, 0.6], [0.8, 0.5, 0.6], [0.7, 0.65, 0.6]])
    f = friedman(acc, 0.05)
    assert f.statistic == pytest.approx(6.5) and f.pvalue == pytest.approx(math.exp(-3.25))
    assert f.pvalue == pytest.approx(stats.friedmanchisquare(*acc.T).pvalue)
    assert (f.n_datasets, f.k) == (4, 3)
    # Nemenyi CD, Demsar (2006) Table 5: q_0.05 = 2.343 for 3 methods
    assert f.cd == pytest.approx(2.343 * math.sqrt(3 * 4 / (6 * 4)), abs=1e-3)
    two = friedman(acc[:, :2], 0.05)
    assert math.isnan(two.pvalue) and two.k == 2


def test_nemenyi_critical_difference_and_datasets_needed():
    # Demsar (2006) Table 5(a): q_0.05 = 1.960 (2 methods), 3.031 (8); q_0.10 = 2.780 (8)
    assert nemenyi_cd(8, 5, 0.05) == pytest.approx(3.031 * math.sqrt(8 * 9 / 30), abs=1e-3)
    assert nemenyi_cd(8, 5, 0.10) == pytest.approx(2.780 * math.sqrt(8 * 9 / 30), abs=1e-3)
    # 2 methods: 1.960 * sqrt(1 / N) <= 1 from N = 3.84, so 4 tables; 8 methods: 3.031**2 * 72 / (6 * 49) = 2.25
    assert datasets_needed(2, 0.05) == 4 and datasets_needed(8, 0.05) == 3
    f = friedman(np.array([[0.9, 0.8], [0.7, 0.6], [0.5, 0.4]]), 0.05)
    assert not f.can_separate and f.datasets_needed == 4


def test_meta_analysis_against_scipy_stouffer():
    t1 = corrected_resampled_t([0.02, 0.05, 0.01, 0.04, 0.03], 0.25)
    t2 = mcnemar_exact([True] * 12 + [False] * 4 + [True] * 20, [False] * 12 + [True] * 4 + [True] * 20)
    m = meta_analysis([t1, t2, no_test("fold", [0.1])])
    assert m.n == [5, 36]
    z = (math.sqrt(5) * stats.norm.isf(t1.p_greater) + 6 * stats.norm.isf(t2.p_greater)) / math.sqrt(5 + 36)
    assert m.z == pytest.approx(z)
    ref = stats.combine_pvalues([t1.p_greater, t2.p_greater], method="stouffer", weights=[math.sqrt(5), 6])
    assert m.p_greater_combined == pytest.approx(ref.pvalue)
    assert m.pvalue == pytest.approx(2 * stats.norm.sf(z))
    # effect sizes: d_z of each table's paired units (captures: +1 on 12, -1 on 4, 0 on 20)
    d = np.array([1] * 12 + [-1] * 4 + [0] * 20, dtype=float)
    assert m.effect_sizes == pytest.approx([0.03 / math.sqrt(2.5e-4), d.mean() / d.std(ddof=1)])
    with pytest.raises(ValueError):
        meta_analysis([no_test("fold", [])])


def test_holm_by_hand():
    # sorted: 0.005*4 = 0.02, 0.01*3 = 0.03, 0.03*2 = 0.06, max(0.06, 0.04*1) = 0.06
    adj = holm([0.01, 0.04, 0.03, 0.005])
    np.testing.assert_allclose(adj, [0.03, 0.06, 0.06, 0.02])


def test_holm_caps_at_one_and_skips_nan():
    adj = holm([0.2, np.nan, 0.01, 0.9])
    # family of 3: 0.01*3 = 0.03, 0.2*2 = 0.4, max(0.4, 0.9) = 0.9
    np.testing.assert_allclose(adj, [0.4, np.nan, 0.03, 0.9])
    np.testing.assert_allclose(holm([0.6, 0.7]), [1.0, 1.0])


def test_pareto_front_by_hand():
    acc = [0.90, 0.85, 0.80, 0.85, 0.70, np.nan]
    lat = [10.0, 2.0, 1.0, 3.0, 0.5, 0.1]
    # 0.85@3 is dominated by 0.85@2; nan never on the front
    assert pareto_front(acc, lat).tolist() == [True, True, True, False, True, False]
    # exact ties are both on the front
    assert pareto_front([0.8, 0.8], [1.0, 1.0]).tolist() == [True, True]
