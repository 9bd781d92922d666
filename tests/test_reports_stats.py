"""Statistics of the leaderboard against hand computation and scipy called directly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
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
    rank_values,
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


# ----------------------------------------------------------------- degenerate limits and symmetry
def test_corrected_t_with_no_variance_has_no_p_and_no_sign_of_its_own():
    # every fold 75 points better: t = 0.75 / 0 is undefined, so is p (never 0, never an infinite t)
    for d in ([0.75] * 5, [-0.75] * 5):
        t = corrected_resampled_t(d, 0.25)
        assert t.test == "corrected-t" and t.n == 5 and t.mean_difference == d[0]
        assert math.isnan(t.pvalue) and math.isnan(t.statistic)
        assert all(math.isnan(v) for v in (t.statistic, t.pvalue, t.p_greater, t.p_less, t.effect_size,
                                           t.ci_low, t.ci_high, t.test_ci_low, t.test_ci_high))
        assert t.note == "no variance: every fold differs by the same amount"
    # fold accuracies that differ by one sixth in every fold differ in their last bits: still no variance
    d = np.array([1.0, 5 / 6, 4 / 6, 1.0]) - np.array([5 / 6, 4 / 6, 3 / 6, 5 / 6])
    assert np.std(d) > 0 and math.isnan(corrected_resampled_t(d, 0.2).pvalue)
    # every difference zero: no difference; p = 1 (nothing is closer to 0 than 0), one-sided p 1/2 each
    z = corrected_resampled_t([0.0, 0.0, 0.0], 0.25)
    assert (z.statistic, z.pvalue, z.p_greater, z.p_less, z.note) == (0.0, 1.0, 0.5, 0.5, "")


def test_meta_analysis_leaves_out_a_table_with_no_variance_and_never_reverses_it():
    flat = corrected_resampled_t([0.75] * 5, 0.25)  # A better by 75 points in every fold
    var = corrected_resampled_t([0.02, 0.05, 0.01, 0.04, 0.03], 0.25)  # t = 2 sqrt(2), 4 df (by hand above)
    z = stats.norm.isf(stats.t.sf(2 * math.sqrt(2), 4))
    m = meta_analysis([flat, var])
    assert m.z == pytest.approx(z) and m.z > 0  # the other table alone: toward A
    assert m.combined == [False, True] and math.isnan(m.z_tables[0])
    assert m.pvalue == pytest.approx(2 * stats.t.sf(2 * math.sqrt(2), 4))
    swapped = meta_analysis([corrected_resampled_t([-0.75] * 5, 0.25),
                             corrected_resampled_t([-0.02, -0.05, -0.01, -0.04, -0.03], 0.25)])
    assert swapped.z == pytest.approx(-z) and swapped.pvalue == pytest.approx(m.pvalue)
    # only tables without a p: nothing to combine
    none = meta_analysis([flat, corrected_resampled_t([0.5] * 3, 0.25)])
    assert none.combined == [False, False] and math.isnan(none.z) and math.isnan(none.pvalue)


def test_meta_analysis_keeps_a_one_sided_p_near_1_on_its_side():
    # fold differences 0.4 +- 0.001: t of about 850 on 9 df; swapped, the p of "A better" is 1 - 1e-23,
    # which float64 rounds to 1 (an infinite z): the table's z comes from the other, small tail
    d = np.full(10, 0.4) + np.array([0.001, -0.001] * 5)
    t, r = corrected_resampled_t(d, 0.1), corrected_resampled_t(-d, 0.1)
    assert r.p_greater == 1.0 and 0 < r.p_less < 1e-20
    m, s = meta_analysis([t]), meta_analysis([r])
    assert m.z == pytest.approx(stats.norm.isf(stats.t.sf(t.statistic, 9)), rel=1e-12)
    assert s.z == -m.z and m.z > 9


def test_mcnemar_interval_inverts_the_exact_test_by_hand():
    # b = 14 captures only A right, c = 4 only B right, 232 both right, n = 250:
    # p = 2 * P(X >= 14), X ~ Bin(18, 1/2) = 2 * (C(18,14) + C(18,15) + C(18,16) + C(18,17) + 1) / 2**18
    a = [True] * 14 + [False] * 4 + [True] * 232
    b = [False] * 14 + [True] * 4 + [True] * 232
    t = mcnemar_exact(a, b)
    assert t.pvalue == pytest.approx(2 * (3060 + 816 + 153 + 18 + 1) / 2 ** 18)
    # Clopper-Pearson of 14 / 18 from the beta quantiles, mapped by (b + c) / n * (2 pi - 1)
    lo, hi = stats.beta.ppf(0.025, 14, 5), stats.beta.ppf(0.975, 15, 4)
    assert (t.ci_low, t.ci_high) == (pytest.approx(18 / 250 * (2 * lo - 1)), pytest.approx(18 / 250 * (2 * hi - 1)))
    assert (t.test_ci_low, t.test_ci_high, t.test_ci_method) == (t.ci_low, t.ci_high, "exact-conditional")
    assert 0 < t.ci_low < 4 / 250 < t.ci_high
    # all discordant captures one way: the lower bound of the share is 0.025**(1/b) (P(X = b) = pi**b)
    t = mcnemar_exact([True] * 6 + [True] * 10, [False] * 6 + [True] * 10)
    assert t.ci_low == pytest.approx(6 / 16 * (2 * 0.025 ** (1 / 6) - 1)) and t.ci_high == pytest.approx(6 / 16)
    # no discordant capture: p = 1 and no interval
    same = mcnemar_exact([True, False], [True, False])
    assert same.pvalue == 1.0 and math.isnan(same.ci_low) and math.isnan(same.test_ci_low)


_differences = st.one_of(
    st.lists(st.floats(-1, 1, allow_subnormal=False), min_size=2, max_size=8),
    st.tuples(st.floats(-1, 1, allow_subnormal=False), st.integers(2, 8)).map(lambda vk: [vk[0]] * vk[1]),
    st.lists(st.sampled_from([-1 / 6, 0.0, 1 / 6, 2 / 6]), min_size=2, max_size=8),
)
_captures = st.lists(st.tuples(st.booleans(), st.booleans()), min_size=1, max_size=60)
_tables = st.lists(st.one_of(st.tuples(st.just("t"), _differences, st.floats(0.01, 1.0)),
                             st.tuples(st.just("m"), _captures)), min_size=1, max_size=4)


def _both_orders(table):
    """A table's test of A against B and of B against A."""
    if table[0] == "t":
        d = np.asarray(table[1])
        return corrected_resampled_t(d, table[2]), corrected_resampled_t(-d, table[2])
    x, y = [p[0] for p in table[1]], [p[1] for p in table[1]]
    return mcnemar_exact(x, y), mcnemar_exact(y, x)


def _same(u, v):
    return (math.isnan(u) and math.isnan(v)) or u == pytest.approx(v, rel=1e-9, abs=1e-12)


@given(_tables)
@settings(max_examples=150, deadline=None)
def test_swapping_the_methods_negates_z_and_keeps_p(tables):
    ab, ba = zip(*(_both_orders(t) for t in tables))
    m, s = meta_analysis(ab), meta_analysis(ba)
    assert _same(m.z, -s.z) and _same(m.pvalue, s.pvalue)
    assert _same(m.p_greater_combined, s.p_less_combined)
    assert m.combined == s.combined
    assert all(_same(u, -v) for u, v in zip(m.z_tables, s.z_tables))
    for t, r in zip(ab, ba):
        assert _same(t.pvalue, r.pvalue) and _same(t.p_greater, r.p_less) and _same(t.p_less, r.p_greater)
        assert _same(t.ci_low, -r.ci_high) and t.note == r.note


@given(_tables)
@settings(max_examples=150, deadline=None)
def test_tables_that_all_favour_a_only_push_toward_a(tables):
    # every fold difference made nonnegative, every discordant capture one A gets right
    fav = [("t", np.abs(t[1]), t[2]) if t[0] == "t" else ("m", [(x or y, x and y) for x, y in t[1]]) for t in tables]
    m = meta_analysis([_both_orders(t)[0] for t in fav])
    assert math.isnan(m.z) or m.z >= 0
    assert all(math.isnan(z) or z >= 0 for z in m.z_tables)


@given(st.integers(0, 80), st.integers(0, 80), st.integers(0, 40))
@settings(max_examples=200, deadline=None)
def test_mcnemar_interval_excludes_0_exactly_when_p_is_below_005(b, c, both):
    t = mcnemar_exact([True] * b + [False] * c + [True] * both + [False],
                      [False] * b + [True] * c + [True] * both + [False])
    if b + c == 0:
        assert t.pvalue == 1.0 and math.isnan(t.ci_low)
        return
    assert (t.ci_low > 0 or t.ci_high < 0) == (t.pvalue < 0.05)
    assert t.ci_low <= t.mean_difference <= t.ci_high and (t.test_ci_low, t.test_ci_high) == (t.ci_low, t.ci_high)


def test_rank_values_make_one_accuracy_of_equal_ones_in_another_order():
    assert 0.1 + 0.2 != 0.3
    r = rank_values([0.1 + 0.2, 0.3, 0.30000000001, math.nan, 0.0])
    assert r[0] == r[1] and r[2] > r[1] and math.isnan(r[3]) and r[4] == 0.0
    assert rank_values([1e-300 * 3, 3e-300])[0] == rank_values([3e-300])[0]
