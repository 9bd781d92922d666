"""One test set scored with several seeds: the leaderboard's interval and test over captures and seeds
(Owen's pigeonhole bootstrap, :mod:`touchbench.reports.bootstrap`, and its test,
:mod:`touchbench.reports.seeds`).

The key case is built by hand: two methods on 100 test captures and four seeds, A ahead by 20 points
on seeds 0 and 2 and behind by 10 on seeds 1 and 3. Over the captures alone A is right (on at least
half of its seeds) on 10 captures B never gets right and the reverse on none, McNemar's p = 2 / 2**10;
over seeds, the order flips, so the table must not call them different. A second pair, 40 points
apart on every seed, must be. The bootstrap's variance is checked against its exact value, derived
here from the multinomial weights' covariance; its resample distribution on tiny matrices is
checked in tests/test_reports_bootstrap.py.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from touchbench.reports.compare import compare_methods
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import to_markdown
from touchbench.reports.results import load_results
from touchbench.reports.bootstrap import pigeonhole
from touchbench.reports.seeds import FEW_CAPTURES, pigeonhole_test
from touchbench.reports.testing import FakeMethod, write_fake_run

N = 100
CAPS = pd.DataFrame({"capture_id": [f"c{i:03d}" for i in range(N)], "subject": [f"s{i % 10}" for i in range(N)],
                     "gesture": [("pat", "rub")[i % 2] for i in range(N)]})
IDS = CAPS["capture_id"].tolist()


def _run(tmp_path, right: dict[str, list[int]]) -> list:
    """A challenge split scored by each method of ``right`` (label -> the number of leading captures
    it gets right with each seed), one results folder per repetition; the leaderboard."""
    n_seeds = len(next(iter(right.values())))
    for r in range(n_seeds):
        methods = [FakeMethod("all", label, wrong={"challenge": IDS[k[r]:]}) for label, k in right.items()]
        write_fake_run(tmp_path / "runs" / f"rep{r}", CAPS, {"challenge": IDS}, methods, scheme={"name": "challenge"},
                       run_id=f"run{r}", repetition=r)
    return build_leaderboards(load_results([tmp_path / "runs"]))


def _row(lb, label: str) -> pd.Series:
    return lb.rows[lb.rows["classifier"] == label].iloc[0]


FLIP = {"a": [70, 50, 70, 50], "b": [50, 60, 50, 60]}  # A - B: +20, -10, +20, -10 points by seed
WIDE = {"a": [90, 88, 92, 90], "b": [50, 52, 48, 50]}  # A - B: +40 points on every seed


def test_an_order_that_flips_between_seeds_is_not_called_a_difference(tmp_path):
    [lb] = _run(tmp_path, FLIP)
    a, b = _row(lb, "a"), _row(lb, "b")
    assert a["rank"] == 1 and a["accuracy"] == pytest.approx(0.60) and b["accuracy"] == pytest.approx(0.55)
    # the per-seed spread, by hand: A 70, 50, 70, 50 -> sd sqrt(4 * 0.1**2 / 3)
    assert a["n_seeds"] == 4 and a["seed_min"] == pytest.approx(0.5) and a["seed_max"] == pytest.approx(0.7)
    assert a["accuracy_sd"] == pytest.approx(math.sqrt(0.04 / 3))
    assert b["test"] == "pigeonhole" and b["ci_method"] == "pigeonhole"
    assert b["diff_vs_best"] == pytest.approx(-0.05)
    assert b["diff_ci_low"] < 0 < b["diff_ci_high"]
    # seeds drawn only from {1, 3} (the draws' chance is 5/16 of 1 or fewer from {0, 2}) put B ahead
    assert b["p_value"] > 0.3 and not b["differs"]
    md = to_markdown([lb])
    assert "60.0 ± 11.5 (4 seeds, 50.0–70.0)" in md and "(captures × seeds)" in md and "pigeonhole bootstrap" in md


def test_a_wide_margin_on_every_seed_is_called_a_difference(tmp_path):
    [lb] = _run(tmp_path, WIDE)
    b = _row(lb, "b")
    assert b["test"] == "pigeonhole" and b["diff_vs_best"] == pytest.approx(-0.40)
    assert b["differs"] and b["p_value"] < 0.001 and b["diff_ci_high"] < -0.25


def test_compare_uses_the_same_test(tmp_path):
    [lb] = _run(tmp_path, FLIP)
    rs = load_results([tmp_path / "runs"])
    c = compare_methods(rs, lb, "all/a", "all/b")
    assert c.test.test == "pigeonhole" and c.test.n == N
    assert c.test.pvalue == pytest.approx(float(_row(lb, "b")["p_value"]))
    # the pairs: each capture's correctness averaged over the four seeds
    pairs = c.pairs.set_index("unit")
    assert pairs.loc["c055", "a"] == 0.5 and pairs.loc["c055", "b"] == 0.5  # A on seeds 0, 2; B on 1, 3
    assert pairs.loc["c065", "a"] == 0.5 and pairs.loc["c065", "b"] == 0.0


def _flip_matrices() -> tuple[np.ndarray, np.ndarray]:
    a, b = np.zeros((N, 4)), np.zeros((N, 4))
    for j in range(4):
        a[:FLIP["a"][j], j] = 1
        b[:FLIP["b"][j], j] = 1
    return a, b


def _exact_variance(y: np.ndarray) -> float:
    """The pigeonhole bootstrap's variance of the mean, exactly: ``w`` ~ Multinomial(R, 1/R) has
    covariance ``S_R = I - J / R`` and mean 1 (``v`` likewise over the C columns), so
    ``var(w' Y v) = tr(Y' S_R Y (S_C + 1 1')) + 1' Y S_C Y' 1``, over ``(R C)**2``."""
    r, c = y.shape
    s_r, s_c = np.eye(r) - np.ones((r, r)) / r, np.eye(c) - np.ones((c, c)) / c
    one_r = np.ones(r)
    total = np.trace(y.T @ s_r @ y @ (s_c + np.ones((c, c)))) + one_r @ y @ s_c @ y.T @ one_r
    return float(total / (r * c) ** 2)


def test_pigeonhole_resamples_have_the_exact_mean_and_variance():
    a, b = _flip_matrices()
    for theta, y in ((pigeonhole(a, resamples=20000, seed=1).resampled, a),
                     (pigeonhole(a, b, paired=True, resamples=20000, seed=1).resampled, a - b)):
        assert theta.dtype == np.float64 and theta.size == 20000
        assert theta.mean() == pytest.approx(y.mean(), abs=4 * math.sqrt(_exact_variance(y) / 20000))
        assert theta.var() == pytest.approx(_exact_variance(y), rel=0.05)  # sd of the estimate: about 1 %


def test_the_seeds_widen_the_interval_beyond_the_captures_alone():
    a, _ = _flip_matrices()
    boot = pigeonhole(a)
    # a bootstrap over the captures of the pooled cells alone: rows resampled, every seed kept
    rng = np.random.default_rng(0)
    rows = rng.integers(0, N, size=(4000, N))
    caps_only = np.percentile(a[rows].mean(axis=(1, 2)), [2.5, 97.5])
    assert boot.high - boot.low > 1.3 * (caps_only[1] - caps_only[0])


def test_degenerate_inputs_have_defined_tests():
    t = pigeonhole_test(np.ones((6, 3)), np.ones((6, 3)))
    assert (t.pvalue, t.p_greater, t.p_less, t.mean_difference, t.ci_low, t.ci_high) == (1.0, 0.5, 0.5, 0.0, 0.0, 0.0)
    t = pigeonhole_test(np.ones((6, 3)), np.zeros((6, 3)), resamples=999)  # right always against wrong always
    assert t.mean_difference == 1.0 and t.ci_low == t.ci_high == 1.0 and t.pvalue == pytest.approx(2 / 1000)
    # one capture: the mean difference, no interval and no p (left out of Holm's family)
    t = pigeonhole_test([[1.0, 1.0, 0.0]], [[0.0, 0.0, 0.0]])
    assert t.n == 1 and t.mean_difference == pytest.approx(2 / 3) and math.isnan(t.pvalue)
    assert math.isnan(t.ci_low) and t.note == FEW_CAPTURES
    # one seed: a bootstrap over the captures alone, the variance of a proportion's p (1 - p) / n
    one = np.r_[np.ones(30), np.zeros(10)][:, None]
    assert pigeonhole(one, resamples=5000, seed=3).resampled.var() == pytest.approx(0.75 * 0.25 / 40, rel=0.08)
    with pytest.raises(ValueError, match="shape"):
        pigeonhole_test(np.ones((3, 2)), np.ones((3, 3)))


@settings(max_examples=30, deadline=None)
@given(pair=st.integers(1, 10).flatmap(lambda r: st.integers(1, 4).flatmap(
    lambda c: st.tuples(*[arrays(np.float64, (r, c), elements=st.sampled_from([0.0, 1.0]))] * 2))))
def test_swapping_the_methods_mirrors_the_test(pair):
    a, b = pair
    ab, ba = pigeonhole_test(a, b, resamples=300), pigeonhole_test(b, a, resamples=300)
    assert ab.mean_difference == pytest.approx(-ba.mean_difference, abs=1e-12)
    if len(a) < 2:  # one capture: no test either way
        assert math.isnan(ab.pvalue) and math.isnan(ba.pvalue)
        return
    assert ab.pvalue == pytest.approx(ba.pvalue) and 0.0 < ab.pvalue <= 1.0
    assert ab.p_greater == pytest.approx(ba.p_less)
    assert ab.ci_low == pytest.approx(-ba.ci_high, abs=1e-12)
