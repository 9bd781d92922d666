"""Zhou, Flagg and raw-window feature sets on hand-made captures (expected
values worked out by hand in the comments)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from helpers import make_set, synthetic_captures
from numpy.testing import assert_allclose, assert_array_equal

from touchbench.datasets.model import SensorSpec
from touchbench.features import FEATURES
from touchbench.engine.cache import FeatureCache
from touchbench.features import base as base_module
from touchbench.features import zhou
from touchbench.features.base import SharedPrep
from touchbench.features.zhou import bicubic_matrix, cutoff_slice, frame_descriptors

# 2 x 2 grid, three frames
#   f0 [[0, 0], [0, 4]]: D1 1, D2 4, D3 = std(0,0,0,4; ddof 1) = sqrt(12/3) = 2,
#      D4 = D5 = |(1, 1) - (0.5, 0.5)| = sqrt(0.5), D6 = #(> 1 + 2) = 1
#   f1 [[2, 2], [2, 2]]: D1 2, D2 2, D3 0, D4 0 (centred), D5 0 (all pixels are the max), D6 0
#   f2 zeros: D1 = D2 = D3 = 0, D4 0 (empty frame: centroid = centre), D5 0, D6 0
CAP = np.array([[[0, 0], [0, 4]], [[2, 2], [2, 2]], [[0, 0], [0, 0]]], dtype=np.float64)
DESC = np.array([[1, 4, 2, np.sqrt(0.5), np.sqrt(0.5), 1], [2, 2, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]])


def test_bicubic_weights_are_matlabs():
    # Keys cubic (a = -0.5): k(0.25) = 0.8671875, k(0.75) = 0.2265625, k(1.25) = -0.0703125, k(1.75) = -0.0234375
    # output 0 of a 4-sample axis doubled sits at u = -0.25: taps -2, -1, 0, 1 at distances 1.75, 0.75, 0.25, 1.25;
    # reflected, -1 -> 0 and -2 -> 1: w0 = 0.2265625 + 0.8671875, w1 = -0.0703125 - 0.0234375
    a = bicubic_matrix(4, 2.0)
    assert_allclose(a[0], [1.09375, -0.09375, 0, 0], atol=1e-15)
    # output 1 at u = 0.25: taps -1, 0, 1, 2 at 1.25, 0.25, 0.75, 1.75
    assert_allclose(a[1], [-0.0703125 + 0.8671875, 0.2265625, -0.0234375, 0], atol=1e-15)
    assert_allclose(a[7], a[0][::-1], atol=1e-15)
    assert_allclose(bicubic_matrix(3, 1.0), np.eye(3), atol=1e-15)


def test_frame_descriptors_by_hand():
    assert_allclose(frame_descriptors(CAP[None], 1.0, 0.0)[0], DESC, atol=1e-12)
    # a constant frame stays exactly constant when up-sampled: D3 = D6 = 0
    d = frame_descriptors(np.full((1, 2, 3, 3), 0.1), 2.0, 0.0)[0]
    assert_allclose(d[:, 0], 0.1, rtol=1e-15)
    assert (d[:, [2, 3, 4, 5]] == 0).all()


def test_zhou_basic_by_hand():
    fs = FEATURES.create("zhou-basic", upsample=1, trim=False)
    out = fs.fit_transform([CAP])[0].reshape(6, 5)  # mean, std, range, kurt, skew
    # D1 = 1, 2, 0: mean 1, deviations 0, 1, -1, std (ddof 1) 1, range 2, m4 = 2/3 -> kurt 2/3, skew 0
    assert_allclose(out[0], [1, 1, 2, 2 / 3, 0], atol=1e-12)
    # D2 = 4, 2, 0: mean 2, std 2, range 4, m4 = 32/3 -> kurt 32/3 / 16
    assert_allclose(out[1], [2, 2, 4, 2 / 3, 0], atol=1e-12)
    # D3 = 2, 0, 0: mean 2/3, deviations 4/3, -2/3, -2/3, var 4/3,
    # m3 = 16/27, m4 = 96/81 -> skew = (16/27) / (4/3)**1.5, kurt = (96/81) / (16/9)
    assert_allclose(out[2], [2 / 3, np.sqrt(4 / 3), 2, (96 / 81) / (16 / 9), (16 / 27) / (4 / 3) ** 1.5], atol=1e-12)
    # D6 = 1, 0, 0: same shape as D3 halved: mean 1/3, std sqrt(1/3)
    assert_allclose(out[5, :3], [1 / 3, np.sqrt(1 / 3), 1], atol=1e-12)
    names = fs.get_feature_names_out()
    assert names[0] == "zhou_basic_D1_mean" and names[-1] == "zhou_basic_D6_skew" and len(names) == 30


def test_zhou_basic_sum_reading_by_hand():
    # the formula as printed (no 1/T): D1 = 1, 2, 0 sums to 3, D2 = 4, 2, 0 to 6;
    # the other four statistics are those of the average reading
    avg = FEATURES.create("zhou-basic", upsample=1, trim=False).fit_transform([CAP])[0].reshape(6, 5)
    fs = FEATURES.create("zhou-basic", upsample=1, trim=False, mean="sum")
    out = fs.fit_transform([CAP])[0].reshape(6, 5)
    assert_allclose(out[:2, 0], [3, 6], atol=1e-12)
    assert_allclose(out[:, 1:], avg[:, 1:], atol=0)
    assert fs.get_feature_names_out()[0] == "zhou_basic_D1_sum"
    with pytest.raises(ValueError, match=r"The 'mean' parameter of zhou-basic must be a str among .*Got 'total' instead"):
        FEATURES.create("zhou-basic", mean="total").fit([CAP])


def test_zhou_cutoff():
    # min 0, max 10: threshold 1; samples 2..4 exceed it
    assert cutoff_slice(np.array([0, 0.5, 5, 10, 5, 0])) == slice(2, 5)
    assert cutoff_slice(np.array([3.0, 3.0, 3.0])) == slice(0, 3)  # constant: nothing removed
    # trimming changes the capture: 1 x 1 grid, D1 = value
    c = np.array([0, 0, 4, 8, 4, 0], dtype=float).reshape(6, 1, 1)
    out = FEATURES.create("zhou-basic", upsample=1, descriptors=("D1",)).fit_transform([c])[0]
    assert_allclose(out[:3], [16 / 3, 4 / np.sqrt(3), 4], atol=1e-12)  # D1 kept: 4, 8, 4


def test_zhou_descriptor_subset():
    fs = FEATURES.create("zhou-basic", descriptors=("D1", "D4"))
    assert fs.n_features((8, 8)) == 10 and fs.feature_names((8, 8))[5] == "zhou_basic_D4_mean"
    assert FEATURES.create("zhou-basic", descriptors=[1, 4]).feature_names((8, 8)) == fs.feature_names((8, 8))
    with pytest.raises(ValueError, match="unknown descriptor"):
        FEATURES.create("zhou-basic", descriptors=("D7",)).fit([CAP])


def test_zhou_wavelet_counts():
    assert FEATURES.create("zhou-wavelet", levels=5, descriptors=("D1",)).n_features((8, 8)) == 14  # paper: J = 5
    assert FEATURES.create("zhou-wavelet", levels=10, descriptors=("D1",)).n_features((8, 8)) == 39  # J = 10
    assert [FEATURES.create("zhou-wavelet", levels=j).n_features((8, 8)) for j in (4, 6, 8, 10)] == [54, 114, 174, 234]


def _haar_4_levels_features(x):
    """The 9 zhou-wavelet features of a 16-sample signal with J = 4, by the orthonormal Haar transform:
    the means of a4, d4, d3, d2, then d1's mean, range, sd (ddof 1), kurtosis and skewness."""

    def haar(v):  # one level of the orthonormal Haar transform
        return (v[0::2] + v[1::2]) / np.sqrt(2), (v[0::2] - v[1::2]) / np.sqrt(2)

    a1, d1 = haar(x)
    a2, d2 = haar(a1)
    a3, d3 = haar(a2)
    a4, d4 = haar(a3)
    dev = d1 - d1.mean()
    sd = np.sqrt((dev**2).sum() / (len(d1) - 1))
    return [a4.mean(), d4.mean(), d3.mean(), d2.mean(),
            d1.mean(), d1.max() - d1.min(), sd, (dev**4).mean() / sd**4, (dev**3).mean() / sd**3]


def test_zhou_wavelet_haar_by_hand():
    # 1 x 1 grid so D1 is the value; signal 1..8, padded with 4 copies of each end -> 16 samples
    s = np.arange(1.0, 9.0)
    padded = np.concatenate([[1.0] * 4, s, [8.0] * 4])
    t = np.arange(16)
    x = padded * (0.54 - 0.46 * np.cos(2 * np.pi * t / 15))  # symmetric Hamming window
    expected = _haar_4_levels_features(x)
    c = s.reshape(8, 1, 1)
    fs = FEATURES.create("zhou-wavelet", levels=4, wavelet="haar", upsample=1, trim=False, descriptors=("D1",))
    assert_allclose(fs.fit_transform([c])[0], expected, rtol=1e-10, atol=1e-12)
    assert list(fs.get_feature_names_out()[[0, 4, 8]]) == ["zhou_wavelet_D1_a4_mean", "zhou_wavelet_D1_d1_mean", "zhou_wavelet_D1_d1_skew"]


def test_zhou_wavelet_zero_pads_to_ltfat_length_by_hand():
    # LTFAT's fwt ('per') zero-pads the signal at its end to a multiple of 2^J before the transform.
    # 1 x 1 grid, signal 1..5, padded with 2 copies of each end -> 9 samples, windowed, then 7 zeros -> 16
    s = np.arange(1.0, 6.0)
    padded = np.concatenate([[1.0] * 2, s, [5.0] * 2])
    t = np.arange(9)
    x = np.concatenate([padded * (0.54 - 0.46 * np.cos(2 * np.pi * t / 8)), np.zeros(7)])
    expected = _haar_4_levels_features(x)
    fs = FEATURES.create("zhou-wavelet", levels=4, wavelet="haar", upsample=1, trim=False, descriptors=("D1",))
    assert_allclose(fs.fit_transform([s.reshape(5, 1, 1)])[0], expected, rtol=1e-10, atol=1e-12)


def test_zhou_wavelet_db8_approximation_keeps_the_padded_sum():
    # An orthogonal filter bank's low-pass taps sum to sqrt(2), so each level divides the sum of the
    # approximation by sqrt(2): with the signal zero-padded to L = 64 = 2^6, a_6 is one coefficient,
    # sum(windowed signal) / 2^3. Without the zero padding (60 samples) the odd lengths on the way break this.
    s = np.random.default_rng(3).uniform(0, 100, size=30)
    padded = np.concatenate([[s[0]] * 15, s, [s[-1]] * 15])  # 60 samples
    windowed = padded * (0.54 - 0.46 * np.cos(2 * np.pi * np.arange(60) / 59))
    fs = FEATURES.create("zhou-wavelet", levels=6, upsample=1, trim=False, descriptors=("D1",))
    a6_mean = fs.fit_transform([s.reshape(30, 1, 1)])[0][0]
    assert fs.get_feature_names_out()[0] == "zhou_wavelet_D1_a6_mean"
    assert_allclose(a6_mean, windowed.sum() / 8, rtol=1e-10)


def test_zhou_wavelet_deeper_than_signal():
    # 10 frames padded to 20 samples, then zero-padded to 1024 for 10 db8 levels: fixed length, finite
    c = np.random.default_rng(1).integers(0, 1024, size=(10, 8, 8)).astype(np.uint16)
    out = FEATURES.create("zhou-wavelet", levels=10).fit_transform([c, c[:1]])
    assert out.shape == (2, 234) and np.isfinite(out).all()


# ------------------------------------------------------------------- flagg
def test_flagg_grid_channels_by_hand():
    fs = make_set("flagg-stats", contact_threshold=1.5)
    out = fs.fit_transform([CAP])[0].reshape(7, 4)  # stats x (total, contact, x, y)
    # total pressure 4, 8, 0: max 8, min 0, mean 4, median 4, area 12, var (0+16+16)/2, tv 4 + 8
    assert_allclose(out[:, 0], [8, 0, 4, 4, 12, 16, 12])
    # contact area (> 1.5): 1, 4, 0: mean 5/3, median 1, area 5, var 78/9 / 2, tv 3 + 4
    assert_allclose(out[:, 1], [4, 0, 5 / 3, 1, 5, 39 / 9, 7])
    # centroid x: 1 (the 4 at column 1), 0.5 (uniform), 0.5 (empty frame = grid centre)
    # mean 2/3, median 0.5, area 2, var (1/9 + 1/36 + 1/36) / 2 = 1/12, tv 0.5
    assert_allclose(out[:, 2], [1, 0.5, 2 / 3, 0.5, 2, 1 / 12, 0.5])
    assert_allclose(out[:, 3], out[:, 2])  # y is the same by symmetry of this capture
    assert fs.get_feature_names_out()[0] == "flagg_max_total_pressure" and fs.n_features((8, 8)) == 28


def test_flagg_default_threshold_and_channel_sensor():
    # default contact threshold: 1.5 % of 0..1023 = 15.345: 15 is no contact, 16 is
    c = np.array([[[15, 16]]], dtype=float)
    out = make_set("flagg-stats").fit_transform([c])[0].reshape(7, 4)
    assert out[0, 1] == 1
    fur = SensorSpec(name="fur", grid=(1, 4), frame_rate=50, value_range=(0, 1023), channels=("x", "y", "pressure", "fur"))
    c = np.array([[[1, 2, 3, 4]], [[3, 2, 1, 0]]], dtype=float)
    fs = FEATURES.create("flagg-stats", sensor=fur)
    out = fs.fit_transform([c])[0].reshape(7, 4)
    # x = 1, 3: max 3, min 1, mean 2, median 2, area 4, var 2, tv 2
    assert_allclose(out[:, 0], [3, 1, 2, 2, 4, 2, 2])
    assert fs.get_feature_names_out()[3] == "flagg_max_fur"


# --------------------------------------------------------------- raw-window
def test_raw_window_pads_with_last_frame():
    c = np.array([[[1, 2]], [[3, 4]], [[5, 6]]], dtype=np.uint16)
    fs = FEATURES.create("raw-window", frames=5, offset=1, shorter="pad")
    out = fs.fit_transform([c])
    assert out.dtype == np.float64
    assert_array_equal(out[0], [3, 4, 5, 6, 5, 6, 5, 6, 5, 6])  # frames 1, 2, then frame 2 repeated
    assert list(fs.get_feature_names_out()[:3]) == ["f0_r0_c0", "f0_r0_c1", "f1_r0_c0"]
    assert_array_equal(FEATURES.create("raw-window", frames=2, offset=10, shorter="pad").fit_transform([c])[0], [5, 6, 5, 6])
    assert make_set("raw-window").n_features((8, 8)) == 432 * 64
    big = np.arange(432 * 64, dtype=np.uint16).reshape(432, 8, 8)
    assert_array_equal(make_set("raw-window").fit_transform([big])[0].reshape(432, 8, 8), big)


# --------------------------------------------------------------- sets computed together
def test_zhou_sets_computed_together_share_the_descriptors_and_give_each_sets_own_rows(tmp_path, monkeypatch):
    caps = synthetic_captures(3, 40, (4, 5), np.uint16) + synthetic_captures(4, 25, (4, 5), np.uint16)
    specs = [("zhou-basic", {}), ("zhou-wavelet", {"levels": 4}), ("zhou-basic", {"descriptors": ["D3"]})]
    alone = [make_set(n, **p).fit(caps).transform(caps) for n, p in specs]
    calls = []
    original = zhou.frame_descriptors
    monkeypatch.setattr(zhou, "frame_descriptors", lambda *a: calls.append(1) or original(*a))
    make_set("zhou-basic").fit(caps).transform(caps)
    per_pass = len(calls)  # one per batch of captures of one length
    assert per_pass >= 2  # two lengths: at least two batches
    calls.clear()
    entries = [(f"key{i}", partial(make_set, n, **p), {}) for i, (n, p) in enumerate(specs)]
    got = FeatureCache(tmp_path).compute(entries, caps)
    assert len(calls) == per_pass  # the three sets read one computation of the descriptors
    for a, (b, info) in zip(alone, got):
        assert a.tobytes() == np.asarray(b).tobytes()  # each set's rows as it gives them alone, bit for bit
        assert info["seconds_per_capture"] > 0
    # D3's statistics are the third block of five of the full set's (independent of the sharing)
    assert_array_equal(np.asarray(got[2][0]), np.asarray(got[0][0])[:, 10:15])
    assert got[2][1]["columns"] == [f"zhou_basic_D3_{s}" for s in ("mean", "std", "range", "kurt", "skew")]


def test_a_shared_preprocessing_is_made_once_and_charged_to_every_reader(monkeypatch):
    clock = iter([10.0, 12.5])  # making the value takes 2.5 s of the fake clock
    monkeypatch.setattr(base_module.time, "perf_counter", lambda: next(clock))
    shared = SharedPrep()
    shared.start()
    assert shared.get("k", lambda: [1, 2]) == [1, 2]
    assert (shared.made, shared.read) == (2.5, 2.5)  # the first reader made it
    shared.start()
    assert shared.get("k", lambda: pytest.fail("made twice")) == [1, 2]
    assert (shared.made, shared.read) == (0.0, 2.5)  # the second reader is charged what it read
