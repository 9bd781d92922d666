"""Owen's pigeonhole bootstrap (:mod:`touchbench.reports.bootstrap`), the one estimator of a mean over
test captures crossed with replicates (seeds, a curve point's draws).

On tiny matrices every resample can be listed: ``n`` draws with replacement from ``n`` items are
the ``n**n`` equally likely index tuples. The exact distribution of the statistic is built here from
that list with plain loops (the mean over the scored cells drawn, each counted as often as its row
and column were drawn), and the estimator's resamples must follow it; the interval's ends, where
the exact distribution puts an atom across the 2.5 % and 97.5 % points, are those atoms.
"""

from __future__ import annotations

import itertools
import math
from collections import defaultdict

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from touchbench.reports.bootstrap import PIGEONHOLE_RESAMPLES, PIGEONHOLE_SEED, pigeonhole

NAN = math.nan


def _draws(n: int):
    """Every tuple of ``n`` draws from ``n`` items, as counts, each of probability ``n**-n``."""
    for idx in itertools.product(range(n), repeat=n):
        counts = [0] * n
        for i in idx:
            counts[i] += 1
        yield counts, n ** -n


def _plain_mean(y, w_r, w_c):
    """The mean over the scored cells drawn, with loops (None when no scored cell was drawn)."""
    num = den = 0.0
    for i, row in enumerate(y):
        for j, v in enumerate(row):
            if not math.isnan(v):
                num += w_r[i] * w_c[j] * v
                den += w_r[i] * w_c[j]
    return num / den if den else None


def _exact(a, b=None, paired=True) -> dict[float, float]:
    """The exact distribution of the resampled statistic (atoms rounded to 12 digits), given that
    it is defined (the resample drew a scored cell of each matrix)."""
    dist: dict[float, float] = defaultdict(float)
    for w_r, p_r in _draws(len(a)):
        for w_a, p_a in _draws(len(a[0])):
            others = [(w_a, 1.0)] if b is None or paired else list(_draws(len(b[0])))
            for w_b, p_b in others:
                m = _plain_mean(a, w_r, w_a)
                m_b = 0.0 if b is None else _plain_mean(b, w_r, w_b)
                if m is not None and m_b is not None:
                    dist[round(m - m_b, 12)] += p_r * p_a * p_b
    total = sum(dist.values())
    return {v: p / total for v, p in dist.items()}


def _quantile(dist: dict[float, float], q: float) -> float:
    """The atom where the exact distribution function crosses ``q``, checked to cross it clearly
    (no atom's distribution function within 0.006 of ``q``, five sd of its estimate from 20000
    resamples), so that the resamples' percentile falls on it."""
    cdf = 0.0
    for v in sorted(dist):
        assert abs(cdf - q) > 0.006
        cdf += dist[v]
        if cdf > q:
            assert cdf - q > 0.006
            return v
    raise AssertionError("no atom")


def _follows(boot, dist):
    """The resamples take only the exact atoms, with their probabilities (within 4.5 sd)."""
    theta = np.round(boot.resampled, 12)
    values, counts = np.unique(theta, return_counts=True)
    assert set(values.tolist()) <= set(dist)
    n = theta.size
    for v, p in dist.items():
        seen = counts[values == v].sum() / n
        assert seen == pytest.approx(p, abs=4.5 * math.sqrt(p * (1 - p) / n) + 1e-9), v
    assert boot.low == pytest.approx(_quantile(dist, 0.025), abs=1e-12)
    assert boot.high == pytest.approx(_quantile(dist, 0.975), abs=1e-12)


def test_one_replicate_by_hand():
    # two captures, one right: the rows drawn (2, 0), (1, 1), (0, 2) with 1/4, 1/2, 1/4: means 1, 1/2, 0
    boot = pigeonhole([[1.0], [0.0]])
    assert (boot.mean, boot.low, boot.high, boot.captures) == (0.5, 0.0, 1.0, 2)
    assert np.mean(boot.resampled == 0.5) == pytest.approx(0.5, abs=0.02)


def test_a_mean_follows_its_exact_distribution():
    a = [[1.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
    boot = pigeonhole(a, resamples=20000, seed=2)
    assert boot.mean == pytest.approx(6 / 9)
    _follows(boot, _exact(a))


def test_cells_not_scored_count_only_where_scored():
    a = [[1.0, NAN, 0.0], [NAN, 1.0, 1.0], [0.0, 0.0, NAN]]
    boot = pigeonhole(a, resamples=20000, seed=3)
    assert boot.mean == pytest.approx(3 / 6)
    _follows(boot, _exact(a))


def test_a_paired_difference_draws_the_columns_together():
    a = [[1.0, 1.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]
    b = [[0.0, 1.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    boot = pigeonhole(a, b, paired=True, resamples=20000, seed=4)
    assert boot.mean == pytest.approx(6 / 9 - 4 / 9)
    _follows(boot, _exact(a, b, paired=True))


def test_independent_columns_draw_each_matrixs_own():
    a = [[0.0, NAN], [1.0, 1.0], [NAN, 1.0]]
    b = [[NAN, 1.0, NAN], [1.0, 0.0, 1.0], [1.0, 0.0, 1.0]]
    boot = pigeonhole(a, b, paired=False, resamples=20000, seed=5)
    assert boot.mean == pytest.approx(3 / 4 - 5 / 7)
    _follows(boot, _exact(a, b, paired=False))


def test_transposing_the_roles_is_not_the_same():
    # two points whose every draw gets capture 0 right and capture 1 wrong: the captures, drawn once for
    # both, cancel in every resample; transposed, the captures are each point's own draws: the means
    # 0, 1/2, 1 with 1/4, 1/2, 1/4 each, their difference -1 with 1/16
    a = [[1.0, 1.0], [0.0, 0.0]]
    same = pigeonhole(a, a, paired=False)
    assert (same.low, same.high) == (0.0, 0.0) and not same.fixed
    t = np.array(a).T
    swapped = pigeonhole(t, t, paired=False)
    assert (swapped.mean, swapped.low, swapped.high) == (0.0, -1.0, 1.0)


def test_degenerate_inputs_have_the_documented_outputs():
    c = pigeonhole(np.full((5, 3), 0.3))
    assert (c.mean, c.low, c.high, c.fixed) == (0.3, 0.3, 0.3, True)
    assert c.resampled.size == PIGEONHOLE_RESAMPLES and (c.resampled == 0.3).all()
    # a zero difference everywhere, and one of a single value
    z = pigeonhole(np.eye(4), np.eye(4))
    assert (z.mean, z.low, z.high, z.fixed) == (0.0, 0.0, 0.0, True)
    one = pigeonhole(np.ones((6, 3)), np.zeros((6, 3)))
    assert (one.mean, one.low, one.high) == (1.0, 1.0, 1.0)
    # two constant points of different draws and captures scored
    two = pigeonhole([[1.0, NAN], [1.0, 1.0]], [[0.5, 0.5, 0.5], [NAN, 0.5, NAN]], paired=False)
    assert (two.mean, two.low, two.high, two.fixed) == (0.5, 0.5, 0.5, True)
    # fewer than two captures: the mean, no interval, one capture with several replicates included
    for a, b in (([[1.0]], None), ([[1.0, 0.0, 1.0]], None), ([[1.0, 0.0]], [[0.0, 0.0]]),
                 ([[1.0], [NAN]], None)):
        few = pigeonhole(a, b)
        assert few.captures == 1 and few.resampled.size == 0
        assert few.mean == pytest.approx(np.nanmean(a) - (np.nanmean(b) if b else 0.0))
        assert math.isnan(few.low) and math.isnan(few.high)
    # nothing scored
    nothing = pigeonhole([[NAN, NAN]])
    assert all(math.isnan(v) for v in (nothing.mean, nothing.low, nothing.high))
    with pytest.raises(ValueError, match="shape"):
        pigeonhole(np.ones((3, 2)), np.ones((3, 3)))
    with pytest.raises(ValueError, match="captures"):
        pigeonhole(np.ones((3, 2)), np.ones((4, 2)), paired=False)


def test_rows_and_columns_nothing_scored_are_left_out():
    a = np.array([[1.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [0.0, 1.0, 1.0]])
    padded = np.full((6, 4), NAN)
    padded[np.ix_([0, 1, 3, 5], [0, 2, 3])] = a
    x, y = pigeonhole(a), pigeonhole(padded)
    assert (x.mean, x.low, x.high, x.captures) == (y.mean, y.low, y.high, y.captures)
    z = pigeonhole(a, seed=PIGEONHOLE_SEED)  # seeded: one interval on every call
    assert (x.low, x.high) == (z.low, z.high) and np.array_equal(x.resampled, z.resampled)


cells = st.integers(1, 8).flatmap(lambda r: st.integers(1, 4).flatmap(
    lambda c: arrays(np.float64, (r, c), elements=st.sampled_from([0.0, 1.0, 0.5, NAN]))))


@settings(max_examples=40, deadline=None)
@given(a=cells, b=cells, paired=st.booleans(), with_b=st.booleans())
def test_the_interval_holds_the_mean(a, b, paired, with_b):
    if with_b:  # b on a's captures: its shape when paired
        b = np.resize(b, a.shape) if paired else np.resize(b, (a.shape[0], b.shape[1]))
    boot = pigeonhole(a, b if with_b else None, paired=paired, resamples=200)
    if np.isfinite(boot.low):
        assert boot.low <= boot.mean <= boot.high
        assert boot.captures >= 2
    else:
        assert boot.captures < 2 or math.isnan(boot.mean) or boot.resampled.size == 0


@settings(max_examples=30, deadline=None)
@given(a=cells)
def test_a_matrix_against_itself_paired_is_no_difference(a):
    boot = pigeonhole(a, a, paired=True, resamples=200)
    if boot.captures >= 2:
        assert (boot.mean, boot.low, boot.high, boot.fixed) == (0.0, 0.0, 0.0, True)


@settings(max_examples=30, deadline=None)
@given(u=arrays(np.float64, st.integers(2, 8), elements=st.sampled_from([0.0, 1.0])), draws=st.integers(1, 4))
def test_shared_captures_cancel_and_their_transpose_does_not(u, draws):
    if np.ptp(u) == 0:
        u[0] = 1.0 - u[0]
    a = np.tile(u[:, None], (1, draws))  # every draw the same correctness per capture
    same = pigeonhole(a, a.copy(), paired=False, resamples=300)
    assert (same.low, same.high) == (0.0, 0.0)
    swapped = pigeonhole(a.T, a.T.copy(), paired=False, resamples=300)
    if draws >= 2:  # the transposed has the draws as captures
        assert swapped.low < 0.0 < swapped.high


@settings(max_examples=30, deadline=None)
@given(r=st.integers(2, 10), c=st.integers(1, 5), v=st.floats(0, 1))
def test_zero_variance_gives_a_zero_width_interval(r, c, v):
    boot = pigeonhole(np.full((r, c), v), resamples=300)
    assert boot.low == boot.high == boot.mean == v
