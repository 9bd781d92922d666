"""Statistics of the leaderboard against hand computation and scipy called directly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from touchbench.reports.pareto import pareto_front
from touchbench.reports.stats import (
    exact_sign_flip_pvalue,
    fold_interval,
    holm,
    paired_test,
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


def test_exact_sign_flip_by_hand():
    # d = 1, 2, 3: the 8 signed sums are 6, 4, 2, 0, 0, -2, -4, -6; |sum| >= 6 twice -> p = 2/8
    assert exact_sign_flip_pvalue([1.0, 2.0, 3.0]) == pytest.approx(0.25)
    # one negative: sums of +-1 +-2 +-3 with observed 1 + 2 - 3 = 0 -> every flip is as extreme
    assert exact_sign_flip_pvalue([1.0, 2.0, -3.0]) == pytest.approx(1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_exact_sign_flip_matches_scipy_permutation_test(seed):
    rng = np.random.default_rng(seed)
    d = rng.normal(0.03, 0.05, size=8)
    ref = stats.permutation_test((d,), np.mean, permutation_type="samples", n_resamples=np.inf,
                                 alternative="two-sided")
    assert exact_sign_flip_pvalue(d) == pytest.approx(ref.pvalue, rel=1e-12)


def test_exact_sign_flip_with_tied_accuracies_matches_scipy():
    # fold accuracies are ratios of small integers: ties in |d| are common
    d = np.array([1, 1, 2, -1, 0, 1, 1, 2, 3, -1]) / 58.0
    ref = stats.permutation_test((d,), np.mean, permutation_type="samples", n_resamples=np.inf,
                                 alternative="two-sided")
    assert exact_sign_flip_pvalue(d) == pytest.approx(ref.pvalue, rel=1e-9)


def test_paired_test_uses_exact_permutation_for_few_folds():
    a = np.array([0.80, 0.75, 0.90, 0.85, 0.70, 0.82, 0.79, 0.88, 0.91, 0.77])
    b = a - np.array([0.05, 0.02, 0.03, -0.01, 0.04, 0.02, 0.06, 0.01, 0.03, 0.02])
    t = paired_test(a, b)
    assert t.test == "exact-permutation" and t.n == 10
    ref = stats.permutation_test((a - b,), np.mean, permutation_type="samples", n_resamples=np.inf)
    assert t.pvalue == pytest.approx(ref.pvalue, rel=1e-9)
    assert t.mean_difference == pytest.approx(0.027)


def test_paired_test_uses_wilcoxon_for_many_folds():
    rng = np.random.default_rng(5)
    a = rng.uniform(0.6, 0.9, size=40)
    b = a - rng.normal(0.01, 0.03, size=40)
    t = paired_test(a, b)
    ref = stats.wilcoxon(a - b, zero_method="wilcox", alternative="two-sided")
    assert t.test == "wilcoxon" and t.n == 40
    assert t.pvalue == pytest.approx(ref.pvalue, rel=1e-12)
    assert t.statistic == pytest.approx(ref.statistic)


def test_paired_test_identical_and_too_few():
    same = paired_test([0.5, 0.6, 0.7], [0.5, 0.6, 0.7])
    assert same.pvalue == 1.0 and same.mean_difference == 0.0
    one = paired_test([0.5], [0.4])
    assert one.test == "none" and math.isnan(one.pvalue)
    with pytest.raises(ValueError):
        paired_test([0.1, 0.2], [0.1])


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
