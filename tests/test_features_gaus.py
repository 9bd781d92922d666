"""Gaus et al. 2015 feature sets on hand-made captures; every expected value
is worked out by hand in the comments (or by scipy/numpy as a second
implementation), never taken from the code under test."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import make_set
from numpy.testing import assert_allclose, assert_array_equal

from touchbench.features import FEATURES
from touchbench.features.gaus_sd import histcounts_edges


def cap(frames) -> np.ndarray:
    return np.asarray(frames, dtype=np.float64)


# ---------------------------------------------------------------------- sd
# 2 x 2 grid, three frames; 12 values sorted 0,0,0,0,0,1,2,3,5,5,9,9:
# instance min 0, max 9, median (1 + 2) / 2 = 1.5.
SD_CAPTURE = cap([[[0, 0], [0, 0]], [[0, 5], [5, 9]], [[1, 2], [3, 9]]])
# per-frame counts:
#   notouch frame   (== frame min 0, 0, 1): 4, 1, 1
#   notouch instance (== 0):                4, 1, 0
#   touched (>= 1.5):                       0, 3, 3
#   high frame (== frame max 0, 9, 9):      4, 1, 1
#   high instance (== 9):                   0, 1, 1
SD_BINS = {"notouch": (1, -0.5, 4.5), "touched": (2, -0.5, 4.5), "high": (1, -0.5, 4.5)}
# notouch/high edges -0.5, 0.5, ..., 4.5 (one bin per count 0..4);
# touched edges -0.5, 1.5, 3.5, 4.5 (last bin narrower, MATLAB's rule).


def test_sd_hand_made_haart_rules():
    fs = make_set("sd", preset="haart", bins=SD_BINS)
    out = fs.fit_transform([SD_CAPTURE])[0]
    expected = (
        [0, 2, 0, 0, 1]  # notouch frame: counts 4, 1, 1
        + [1, 1, 0, 0, 1]  # notouch instance: 4, 1, 0
        + [1, 2, 0]  # touched: 0 -> [-0.5, 1.5); 3, 3 -> [1.5, 3.5)
        + [0, 2, 0, 0, 1]  # high frame: 4, 1, 1
        + [1, 2, 0, 0, 0]  # high instance: 0, 1, 1
    )
    assert_array_equal(out, expected)
    names = fs.get_feature_names_out()
    assert len(names) == 23 and names[0] == "sd_notouch_frame_b00" and names[10] == "sd_touched_median_b00"


def test_sd_cost_rules():
    # 1 x 2 grid: frames [0, 150], [120, 300]; instance max 300, median (120 + 150) / 2 = 135
    c = cap([[[0, 150]], [[120, 300]]])
    bins = {k: (1, -0.5, 2.5) for k in ("notouch", "touched", "high")}  # a bin per count 0, 1, 2
    fs = make_set("sd", preset="cost", bins=bins)
    out = fs.fit_transform([c])[0]
    expected = (
        [0, 2, 0]  # notouch frame (== 0, == 120): 1, 1
        + [1, 1, 0]  # notouch instance (== 0): 1, 0
        + [0, 2, 0]  # touched >= 135: 1 (150), 1 (300)
        + [0, 1, 1]  # touched >= 100: 1 (150), 2 (120, 300)
        + [0, 2, 0]  # high frame >= max - 100 (50, 200): 1, 1
        + [1, 1, 0]  # high instance >= 200: 0, 1
    )
    assert_array_equal(out, expected)
    assert "sd_touched_ge100_b00" in list(fs.get_feature_names_out())


def test_sd_table4_edges_and_sizes():
    # HAART no touch: width 5 from -0.5; 56 / 5 is not whole, last bin [54.5, 55.5]
    assert_allclose(histcounts_edges(5, -0.5, 55.5), [-0.5, 4.5, 9.5, 14.5, 19.5, 24.5, 29.5, 34.5, 39.5, 44.5, 49.5, 54.5, 55.5])
    assert_allclose(histcounts_edges(1, -0.5, 11.5), np.arange(13) - 0.5)  # CoST no touch: 12 bins
    assert len(histcounts_edges(5, -0.5, 65.5)) - 1 == 14
    assert len(histcounts_edges(10, -0.5, 80.5)) - 1 == 9
    assert len(histcounts_edges(10, -0.5, 100.5)) - 1 == 11
    assert make_set("sd").n_features((8, 8)) == 12 + 12 + 14 + 12 + 12
    assert make_set("sd", preset="cost").n_features((8, 8)) == 12 + 12 + 9 + 9 + 11 + 11
    # with the paper's edges every count 0..4 of a 2 x 2 grid is in bin 0: 3 frames
    out = make_set("sd").fit_transform([SD_CAPTURE])[0]
    assert out[0] == 3 and out[:12].sum() == 3


def test_sd_value_on_edge_and_clip():
    # a count exactly on an inner edge goes right; on the last edge, into the last bin
    bins = {k: (2, 0, 4) for k in ("notouch", "touched", "high")}  # edges 0, 2, 4
    c = cap([[[1, 1]], [[1, 2]]])  # notouch frame counts 2, 1
    out = make_set("sd", bins=bins).fit_transform([c])[0]
    assert_array_equal(out[:2], [1, 1])  # 1 -> [0, 2); 2 -> [2, 4]
    # 72 cells all equal: every count is 72, beyond HAART's 55.5
    c = np.zeros((2, 8, 9))
    clipped = make_set("sd").fit_transform([c])[0]
    assert clipped[11] == 2 and clipped[:11].sum() == 0  # both frames in the last no-touch bin
    dropped = make_set("sd", clip=False).fit_transform([c])[0]
    assert dropped[:12].sum() == 0
    norm = make_set("sd", normalize=True).fit_transform([c])[0]
    assert norm[11] == 1.0


def test_sd_unknown_preset_is_clear():
    with pytest.raises(ValueError, match=r"'preset' parameter of sd .*Got 'coast' instead; did you mean 'cost'\?"):
        make_set("sd", preset="coast").fit_transform([SD_CAPTURE])


# --------------------------------------------------------------------- bmh
def test_bmh_hand_made():
    # 1 x 3 grid. Instance max 100, HAART: >= 95 -> cells 1 (100) and 2 (96)
    c = cap([[[0, 10, 96]], [[0, 100, 50]], [[18, 20, 0]]])
    assert_array_equal(make_set("bmh").fit_transform([c])[0], [0, 1, 1])
    # frame maxima 96, 100, 20 -> thresholds 91, 95, 15: frame 2 sets cells 0 and 1
    assert_array_equal(make_set("bmh", level="frame").fit_transform([c])[0], [1, 1, 1])
    # CoST: >= 100 - 100 = 0: every cell
    assert_array_equal(make_set("bmh", preset="cost").fit_transform([c])[0], [1, 1, 1])
    assert_array_equal(make_set("bmh", offset=3).fit_transform([c])[0], [0, 1, 0])  # >= 97
    assert make_set("bmh").n_features((8, 8)) == 64


# --------------------------------------------------------------------- msd
def test_msd_hand_made():
    # 1 x 2 grid, 4 frames: cell A = 1, 3, 2, 6; cell B = 5, 5, 5, 5
    c = cap([[[1, 5]], [[3, 5]], [[2, 5]], [[6, 5]]])
    out = FEATURES.create("msd").fit_transform([c])[0].reshape(12, 2)
    a, b = out[:, 0], out[:, 1]
    # A sorted 1, 2, 3, 6; MATLAB quantile: p at (i - 0.5) / 4 -> Q1 = 1.5, median 2.5, Q3 = 4.5
    # deviations from mean 3: -2, 0, -1, 3 -> sum sq 14: var 14/3, m2 = 3.5, m3 = 18/4, m4 = 98/4
    expected_a = [1, 6, 3, 1.5, 2.5, 4.5, 12, 2 + 1 + 4, 3, 14 / 3, 4.5 / 3.5**1.5, 24.5 / 3.5**2]
    assert_allclose(a, expected_a, rtol=1e-12)
    # constant cell: spread 0, skewness 0, kurtosis 3 (the documented limits)
    assert_allclose(b, [5, 5, 5, 5, 5, 5, 20, 0, 0, 0, 0, 3], rtol=1e-12)
    names = FEATURES.create("msd").feature_names((1, 2))
    assert names[:2] == ["msd_min_r0_c0", "msd_min_r0_c1"] and names[-1] == "msd_kurt_r0_c1"
    assert FEATURES.create("msd").n_features((8, 8)) == 768


def test_msd_matches_scipy_and_numpy():
    scipy_stats = pytest.importorskip("scipy.stats")
    rng = np.random.default_rng(0)
    c = rng.integers(0, 1024, size=(57, 3, 4)).astype(np.uint16)
    out = FEATURES.create("msd").fit_transform([c])[0].reshape(12, 12)
    s = c.reshape(57, 12).astype(np.float64)
    q1, med, q3 = np.quantile(s, [0.25, 0.5, 0.75], axis=0, method="hazen")
    expected = [s.min(0), s.max(0), s.mean(0), q1, med, q3, s.sum(0), np.abs(np.diff(s, axis=0)).sum(0), q3 - q1,
                s.var(0, ddof=1), scipy_stats.skew(s, axis=0), scipy_stats.kurtosis(s, axis=0, fisher=False)]
    assert_allclose(out, np.array(expected), rtol=1e-10)


def test_msd_single_frame_and_tiny_spread():
    out = FEATURES.create("msd").fit_transform([cap([[[7.0]]])])[0]
    assert_allclose(out, [7, 7, 7, 7, 7, 7, 7, 0, 0, 0, 0, 3])
    # a subnormal spread is still a spread: finite skewness and kurtosis
    c = np.array([0.0, 5e-324, 0.0, 0.0]).reshape(4, 1, 1)
    out = FEATURES.create("msd").fit_transform([c])[0]
    assert np.isfinite(out).all()
    # scale-free, this is 0, 1, 0, 0: mean 1/4, deviations -1/4, 3/4, -1/4, -1/4,
    # m2 = 3/16, m3 = 6/64, m4 = 21/256 -> skew = (6/64) / (3/16)**1.5 = 2/sqrt(3), kurt = 7/3
    assert_allclose(out[10:], [2 / np.sqrt(3), 7 / 3], rtol=1e-9)


# ------------------------------------------------------------------- smmhh
def test_smmhh_run_lengths_by_hand():
    # 1 x 1 grid, one scale, skip 2, threshold 0.5
    v = [0, 1, 0, 0, 3, 3, 3, 3, 3, 0]
    # |v(t+2) - v(t)|, t = 0..7: 0, 1, 3, 3, 0, 0, 0, 3 -> motion 0 1 1 1 0 0 0 1
    # runs: 3 (t = 1..3) and 1 (t = 7, touching the end)
    c = cap(np.array(v, dtype=float).reshape(10, 1, 1))
    fs = make_set("smmhh", skips=(2,), max_len=3, n_scales=1, threshold=0.5)
    assert_array_equal(fs.fit_transform([c])[0], [1, 0, 1])
    # M = 2: the run of 3 counts as "2 or more"
    fs = make_set("smmhh", skips=(2,), max_len=2, n_scales=1, threshold=0.5)
    assert_array_equal(fs.fit_transform([c])[0], [1, 1])


def test_smmhh_pooling_and_per_scale_threshold():
    # 2 x 2 grid: frame 1 has 4 in the top-left cell; pooled 1 x 1 video is 0, 1, 0
    c = np.zeros((3, 2, 2))
    c[1, 0, 0] = 4
    fs = make_set("smmhh", skips=(1,), max_len=2, n_scales=2, threshold=0.5)
    # scale 0: top-left diffs 4, 4 -> one run of 2; scale 1: diffs 1, 1 -> one run of 2
    # order: k0 s1 m1 (4 px), k0 s1 m2 (4 px), k1 s1 m1, k1 s1 m2
    assert_array_equal(fs.fit_transform([c])[0], [0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
    names = fs.get_feature_names_out()
    assert names[4] == "smmhh_k0_s1_m2_r0_c0" and names[-1] == "smmhh_k1_s1_m2_r0_c0"
    fs = make_set("smmhh", skips=(1,), max_len=2, n_scales=2, threshold=(0.5, 1.0))
    assert_array_equal(fs.fit_transform([c])[0], [0, 0, 0, 0, 1, 0, 0, 0, 0, 0])  # 1 is not > 1


def test_smmhh_sizes_and_odd_pooling():
    from touchbench.features.gaus_smmhh import pool2

    assert make_set("smmhh").n_features((8, 8)) == 2125  # equation 1
    # 3 x 3 -> 2 x 2: means of (1,2,4,5), (3,6), (7,8), (9)
    assert_allclose(pool2(np.arange(1.0, 10.0).reshape(3, 3)), [[3, 4.5], [7.5, 9]])
    # pooled down to one cell, the paper's 8x8..1x1 rule on any grid: 20, 10, 5, 3, 2, 1
    assert make_set("smmhh").n_features((20, 20)) == 25 * (400 + 100 + 25 + 9 + 4 + 1)
    assert make_set("smmhh", n_scales=4).n_features((20, 20)) == 25 * (400 + 100 + 25 + 9)
    # shorter than every skip: no frame pairs, all zero
    assert make_set("smmhh").fit_transform([np.ones((2, 8, 8))]).sum() == 0


# ------------------------------------------------------------------ lbptop
def test_lbptop_single_voxel_by_hand():
    # 3 x 3 grid, 3 frames: one interior voxel (t=1, y=1, x=1) of value 5
    c = np.zeros((3, 3, 3))
    c[1] = [[9, 1, 9], [1, 5, 9], [1, 1, 1]]
    out = FEATURES.create("lbptop").fit_transform([c])[0]
    # neighbours counter-clockwise from "right": p0 (0,+1), p1 (-1,+1), p2 (-1,0), p3 (-1,-1),
    # p4 (0,-1), p5 (+1,-1), p6 (+1,0), p7 (+1,+1); bit p = neighbour >= 5
    # XY: right 9, up-right 9, up 1, up-left 9, left 1, down-left 1, down 1, down-right 1
    #     -> bits 1,1,0,1,0,0,0,0: 4 transitions, non-uniform -> bin 58
    # XT (row 1; first axis time): (t1,x2)=9 -> 1, frame 0 and 2 zeros -> 0, (t1,x0)=1 -> 0: code 1 -> bin 1
    # YT (column 1): (t1,y2)=1, (t1,y0)=1, zeros elsewhere: code 0 -> bin 0
    expected = np.zeros(177)
    expected[58] = expected[59 + 1] = expected[118 + 0] = 1
    assert_array_equal(out, expected)


def test_lbptop_uniform_mapping_and_limits():
    from touchbench.features.gaus_lbptop import uniform_mapping

    table, nb = uniform_mapping(8)
    assert nb == 59
    # uniform codes in order 0, 1, 2, 3, 4, 6, 7, 8, ... (5 = 00000101 has 4 transitions)
    assert [table[k] for k in (0, 1, 2, 3, 4, 6, 7)] == [0, 1, 2, 3, 4, 5, 6]
    assert table[5] == 58 and table[255] == 57
    # constant capture: every code is 255 in every plane
    out = FEATURES.create("lbptop").fit_transform([np.full((5, 8, 8), 1023.0)])[0]
    assert out[57] == out[59 + 57] == out[118 + 57] == 1 and out.sum() == 3
    # two frames: no interior voxel, all zero (not 0/0)
    assert FEATURES.create("lbptop").fit_transform([np.ones((2, 8, 8))]).sum() == 0
