"""The counting helpers behind the faster Gaus sets, held to independent computations: numpy's
hazen quantiles and sorts, scipy's moments, runs listed one by one in Python, the float64 pyramid."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from scipy import stats

from touchbench.features.gaus_smmhh import pool2, pyramid_shapes, pyramid_video, run_length_histogram
from touchbench.features.numerics import SeriesCounts, count_true, hazen_points, total_variation

INT_DTYPES = [np.uint8, np.int8, np.uint16, np.int16, np.int32]


def series_batch(draw_seed: int, t: int, p: int, dtype, spread: int) -> np.ndarray:
    """(3, t, p) integers of ``dtype``: a few distinct values (ties), one constant cell, a wide cell."""
    rng = np.random.default_rng(draw_seed)
    info = np.iinfo(dtype)
    lo = max(int(info.min), -spread)
    x = rng.integers(lo, min(int(info.max), lo + spread) + 1, (3, t, p))
    x[:, :, 0] = x[:, :1, 0]  # a constant series
    x[:, :, -1] = rng.choice([lo, min(int(info.max), lo + spread)], (3, t))  # two values only
    return x.astype(dtype)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), t=st.sampled_from([1, 2, 3, 4, 7, 40, 432]), p=st.integers(1, 5),
       dtype=st.sampled_from(INT_DTYPES), spread=st.sampled_from([0, 1, 3, 30, 200]))
def test_counted_quantiles_and_order_statistics_equal_numpys(seed, t, p, dtype, spread):
    x = series_batch(seed, t, p, dtype, spread)
    counts = SeriesCounts.of(x, max_bins_per_value=np.inf)
    probs = (0.25, 0.5, 0.75, 0.0, 1.0, 0.1)
    expected = np.quantile(x.astype(np.float64), probs, axis=1, method="hazen")  # (probs, 3, p)
    got = counts.quantiles(probs)
    for k in range(len(probs)):
        assert_allclose(got[k].reshape(3, p), expected[k], rtol=1e-12, atol=1e-12)
    srt = np.sort(x, axis=1)
    stats_ = counts.order_stats([0, t - 1, t // 2])
    for rank, value in stats_.items():
        assert_array_equal(value.reshape(3, p), srt[:, rank])


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), t=st.sampled_from([1, 2, 3, 5, 64, 432]), dtype=st.sampled_from(INT_DTYPES),
       spread=st.sampled_from([0, 1, 2, 50, 255]))
def test_counted_moments_equal_scipys(seed, t, dtype, spread):
    x = series_batch(seed, t, 4, dtype, spread)
    m = SeriesCounts.of(x, max_bins_per_value=np.inf).moments()
    f = np.moveaxis(x.astype(np.float64), 1, -1).reshape(-1, t)  # series in SeriesCounts' order
    const = f.max(axis=1) == f.min(axis=1)
    assert_array_equal(m["sum"], f.sum(axis=1))
    assert_array_equal(m["min"], f.min(axis=1))
    assert_array_equal(m["max"], f.max(axis=1))
    assert_allclose(m["mean"], f.mean(axis=1), rtol=1e-12)
    assert_allclose(m["var"], f.var(axis=1, ddof=1) if t > 1 else 0.0, rtol=1e-9, atol=1e-9)
    skew, kurt = np.zeros(len(f)), np.full(len(f), 3.0)  # the limits of a constant series
    skew[~const] = stats.skew(f[~const], axis=1, bias=True)
    kurt[~const] = stats.kurtosis(f[~const], axis=1, fisher=False, bias=True)
    assert_allclose(m["skew"], skew, rtol=1e-9, atol=1e-9)
    assert_allclose(m["kurt"], kurt, rtol=1e-9, atol=1e-9)


def test_counts_decline_fractions_and_wide_ranges():
    assert SeriesCounts.of(np.full((1, 4, 2), 0.5)) is None
    assert SeriesCounts.of(np.full((1, 4, 2), 2.0**31)) is None
    whole = SeriesCounts.of(np.array([[[3.0], [1.0], [2.0]]], dtype=np.float32))  # whole numbers: counted
    assert {k: v.tolist() for k, v in whole.order_stats([0, 1, 2]).items()} == {0: [1], 1: [2], 2: [3]}
    wide = np.array([[[0], [60000]]], dtype=np.uint16)  # 60001 bins for 2 readings
    assert SeriesCounts.of(wide) is None
    assert SeriesCounts.of(wide, max_bins_per_value=np.inf) is not None


def test_hazen_points_worked_by_hand():
    # 432 readings: the quartiles lie half way between the 108th and 109th smallest (0-based 107, 108)
    assert hazen_points(432, 0.25) == (107, 108, 0.5)
    assert hazen_points(432, 0.5) == (215, 216, 0.5)
    assert hazen_points(1, 0.75) == (0, 0, 0.0)
    assert hazen_points(4, 0.0) == (0, 1, 0.0)  # below the first point: the minimum


@pytest.mark.parametrize("length", [1, 254, 255, 256, 600])
def test_count_true_counts_along_axis_one(length):
    a = np.random.default_rng(length).random((3, length, 5)) < 0.9
    assert_array_equal(count_true(a), a.sum(axis=1))


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, np.int32, np.float32, np.bool_])
@pytest.mark.parametrize("axis", [0, 1, -1])
def test_total_variation_along_any_axis(dtype, axis):
    x = np.random.default_rng(5).integers(0, 2, (6, 7, 3)) * np.array([0, 40000, 200])[np.random.default_rng(6).integers(0, 3, (6, 7, 3))]
    x = x.astype(dtype)
    expected = np.abs(np.diff(x.astype(np.float64), axis=axis)).sum(axis=axis)
    assert_array_equal(total_variation(x, axis=axis), expected)
    assert_array_equal(total_variation(x[:1], axis=0), np.zeros((7, 3)))


def runs_listed(seq: np.ndarray, max_len: int) -> np.ndarray:
    """The run-length histogram of one 0/1 sequence, its runs listed one by one."""
    hist = np.zeros(max_len)
    run = 0
    for v in list(seq) + [0]:
        if v:
            run += 1
        elif run:
            hist[min(run, max_len) - 1] += 1
            run = 0
    return hist


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), length=st.integers(1, 40), max_len=st.integers(1, 6), density=st.floats(0, 1))
def test_run_length_histogram_equals_runs_listed(seed, length, max_len, density):
    b = np.random.default_rng(seed).random((2, length, 3)) < density
    padded = np.zeros((2, length + max_len + 1, 3), dtype=bool)
    padded[:, 1:length + 1] = b
    got = run_length_histogram(padded, length, max_len)
    for r in range(2):
        for p in range(3):
            assert_array_equal(got[r, :, p], runs_listed(b[r, :, p], max_len))


def float_motion(stack: np.ndarray, shapes, thresholds, skip: int) -> np.ndarray:
    """Motion of every scale's pixels the slow way: float64 pooling, one scale at a time."""
    n, t = stack.shape[:2]
    v = stack.astype(np.float64)
    parts = []
    for k, thr in enumerate(thresholds):
        v = pool2(v) if k else v
        flat = v.reshape(n, t, -1)
        parts.append(np.abs(flat[:, skip:] - flat[:, :-skip]) > thr)
    return np.concatenate(parts, axis=2)


@pytest.mark.parametrize("thresholds", [(3.0, 3.0, 3.0, 3.0), (0.5, 0.3, 2.75, 0.126), (-1.0, 0.0, 1e12, 7.0)])
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16])
def test_integer_pyramid_gives_the_float_pyramids_motion(thresholds, dtype):
    rng = np.random.default_rng(11)
    info = np.iinfo(dtype)
    stack = rng.integers(max(int(info.min), -500), min(int(info.max), 1023) + 1, (2, 12, 8, 8)).astype(dtype)
    stack[:, 5:] = stack[:, 4:5]  # still frames: changes of exactly 0
    shapes = pyramid_shapes((8, 8), 4)
    video, thr = pyramid_video(stack, shapes, list(thresholds))
    assert video.dtype == np.int32  # the integer path is the one under test
    for skip in (1, 2, 5):
        got = np.abs(video[:, skip:] - video[:, :-skip]) > thr
        assert_array_equal(got, float_motion(stack, shapes, thresholds, skip))


def test_odd_grids_and_floats_keep_the_float_pyramid():
    stack = np.arange(2 * 5 * 5 * 6, dtype=np.uint16).reshape(2, 5, 5, 6)
    video, _ = pyramid_video(stack, pyramid_shapes((5, 6), 4), [1.0] * 4)
    assert video.dtype == np.float64
    video, _ = pyramid_video(stack.astype(np.float32).reshape(2, 5, 5, 6)[:, :, :4, :4], pyramid_shapes((4, 4), 3), [1.0] * 3)
    assert video.dtype == np.float64


def test_countable_decides_block_by_block():
    # block 0: readings 0..3 in each of 2 cells over 4 frames: 4 + 4 = 8 bins <= 2 * 8 readings
    # block 1: one cell spans 0..99 (100 bins) > 2 * 8 readings; block 2: a fraction
    x = np.zeros((3, 4, 2))
    x[0] = [[0, 3], [1, 2], [2, 1], [3, 0]]
    x[1, :, 0] = [0, 99, 5, 7]
    x[2, 0, 1] = 0.5
    assert_array_equal(SeriesCounts.countable(x), [True, False, False])
    assert_array_equal(SeriesCounts.countable(x[:2].astype(np.int16)), [True, False])
    assert_array_equal(SeriesCounts.countable(x[:1].astype(np.int64)), [False])


def test_numpy_msd_row_does_not_depend_on_its_batch(monkeypatch):
    from touchbench.core import compiled
    from touchbench.features.gaus_msd import MotionStatisticalDistribution
    monkeypatch.setattr(compiled, "COMPILED", False)
    rng = np.random.default_rng(3)
    narrow = rng.integers(0, 20, (40, 4, 4)).astype(np.float64)  # counted on its own
    wide = rng.integers(0, 1024, (40, 4, 4)).astype(np.float64)  # sorted on its own (range >> readings)
    fraction = narrow + 0.25
    msd = MotionStatisticalDistribution()
    alone = np.vstack([msd.fit_transform([c]) for c in (narrow, wide, fraction)])
    assert_array_equal(msd.fit_transform([narrow, wide, fraction]), alone)
    # and each alone is what an independent computation gives (mean, hazen median, scipy's skewness)
    cells = narrow.reshape(40, -1)
    assert_allclose(alone[0, 32:48], cells.mean(axis=0), rtol=1e-12)
    assert_allclose(alone[0, 64:80], np.quantile(cells, 0.5, axis=0, method="hazen"), rtol=1e-12)
    assert_allclose(alone[1, 160:176], stats.skew(wide.reshape(40, -1), axis=0), rtol=1e-9)
