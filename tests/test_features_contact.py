"""``contact-evidence``: level and contact relative to the sensor's full scale and noise floor.

Values worked out by hand on tiny captures (range 0..100, ``min_noise``
0.01, so the noise floor is at least 1 unit):

- a constant capture (every reading 10): level 0.1 everywhere, rest level
  10, noise floor the minimum (1), nothing above it;
- a single pulse: one reading of 50 in a 4-frame 2 x 2 capture of zeros;
- a ramp in the quietest cell: the noise floor is 1.4826 x its MAD.

Two synthetic recording sessions that differ in noise shape (white vs
slowly wandering), gain and cell offsets: a classifier trained on session
A's captures with this set recognises session B's captures without touch.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sklearn.ensemble import ExtraTreesClassifier

from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES, make_feature_set

NAME = "contact-evidence"
SMALL = SensorSpec("small", (2, 2), 50.0, (0, 100))
HAART_LIKE = SensorSpec("haart-like", (8, 8), 54.0, (0, 1023))


def features(capture, sensor=SMALL, **params):
    fs = make_feature_set(NAME, {"min_noise": 0.01, **params}, sensor).fit([capture])
    return dict(zip(fs.get_feature_names_out(), fs.transform([capture])[0]))


def test_registered_cheap_and_learns_nothing():
    e = FEATURES.entry(NAME)
    assert e.tags["cost"] == "cheap" and e.obj.fold_dependent is False
    assert "Gaus et al. 2015" in e.tags["paper"]


def test_constant_capture_by_hand():
    f = features(np.full((4, 2, 2), 10, dtype=np.uint16))
    for k in ("level_mean", "level_p50", "level_p95", "level_max", "cellmean_min", "cellmean_max"):
        assert f[k] == pytest.approx(0.1)  # 10 of a full scale of 100
    # rest level 10, noise floor the minimum 0.01 x 100 = 1: nothing above 10 + k
    assert all(v == 0 for k, v in f.items() if k.startswith("above"))
    assert f["peak_over_noise"] == 0 and f["cellmean_over_noise"] == 0
    assert f["tstd_mean_over_noise"] == 0 and f["tstd_max_over_noise"] == 0


def test_single_pulse_by_hand():
    c = np.zeros((4, 2, 2))
    c[1, 0, 1] = 50  # cell 1, frame 1
    f = features(c)
    assert f["level_mean"] == pytest.approx(50 / 16 / 100)
    # 16 readings sorted: 15 zeros and 50; ranks round(7.5) = 8 and round(14.25) = 14 are zeros
    assert f["level_p50"] == 0 and f["level_p95"] == 0 and f["level_max"] == pytest.approx(0.5)
    assert f["cellmean_min"] == 0 and f["cellmean_max"] == pytest.approx(12.5 / 100)
    # every cell's median is 0: quiet cell 0, rest 0, MAD 0 -> noise floor 1; thresholds 3, 10, 30
    for k in (3, 10, 30):
        assert f[f"above{k}_frac"] == pytest.approx(1 / 16)
        assert f[f"above{k}_frames"] == pytest.approx(1 / 4)
    assert f["above3_cells"] == pytest.approx(1 / 4) and f["above10_cells"] == pytest.approx(1 / 4)  # mean 12.5
    assert f["above30_cells"] == 0
    assert f["peak_over_noise"] == pytest.approx(50.0) and f["cellmean_over_noise"] == pytest.approx(12.5)
    # cell 1: (0, 50, 0, 0), mean 12.5, population sd sqrt((3 * 12.5^2 + 37.5^2) / 4) = 12.5 sqrt(3)
    assert f["tstd_max_over_noise"] == pytest.approx(12.5 * np.sqrt(3))
    assert f["tstd_mean_over_noise"] == pytest.approx(12.5 * np.sqrt(3) / 4)


def test_noise_floor_is_the_quiet_cells_mad():
    c = np.full((5, 2, 2), 50.0)
    c[:, 0, 0] = [0, 1, 2, 3, 4]  # the lowest median (2): the quiet cell; MAD of (2, 1, 0, 1, 2) = 1
    f = features(c)
    s = 1.4826  # above the minimum (1)
    assert f["peak_over_noise"] == pytest.approx((50 - 2) / s)
    assert f["above3_frac"] == pytest.approx(15 / 20)  # 2 + 3 s = 6.45: the 15 readings of 50 of 20
    assert f["above30_frac"] == pytest.approx(15 / 20)  # 2 + 30 s = 46.5 < 50
    assert f["above3_cells"] == pytest.approx(3 / 4)
    # the quiet cell's sd: sqrt(mean((-2, -1, 0, 1, 2)^2)) = sqrt(2); the others 0
    assert f["tstd_max_over_noise"] == pytest.approx(np.sqrt(2) / s)
    assert f["tstd_mean_over_noise"] == pytest.approx(np.sqrt(2) / s / 4)


def test_a_sensor_whose_higher_values_mean_less_pressure_is_read_from_its_top():
    c = np.zeros((4, 2, 2))
    c[1, 0, 1] = 50
    inverted = SensorSpec("inverted", (2, 2), 50.0, (0, 100), higher_is_more_pressure=False)
    assert features(100 - c, inverted) == features(c)


def test_refusals_name_the_reason():
    cap = np.zeros((4, 2, 2))
    with pytest.raises(TouchbenchError, match=r"contact-evidence: needs the sensor's value range"):
        make_feature_set(NAME, {}, None).fit_transform([cap])
    with pytest.raises(TouchbenchError, match=r"value_range must be \(low, high\)"):
        make_feature_set(NAME, {"value_range": (5, 5)}, None).fit_transform([cap])
    with pytest.raises(TouchbenchError, match=r"The 'min_noise' parameter of contact-evidence must be a float in the range \(0.0, 1.0\)"):
        make_feature_set(NAME, {"min_noise": 0}, SMALL).fit_transform([cap])
    fur = SensorSpec("fur", (1, 4), 50.0, (0, 1023), channels=("x", "y", "pressure", "fur"))
    problem = make_feature_set(NAME, {}, fur).check_sensor(fur)
    assert "is a channel sensor (x, y, pressure, fur)" in problem and "not cells of a pressure surface" in problem
    assert make_feature_set(NAME, {}, HAART_LIKE).check_sensor(HAART_LIKE) is None
    given_range = make_feature_set(NAME, {"value_range": (0, 100), "min_noise": 0.01}, None)
    assert given_range.fit_transform([cap]).shape == (1, 19)


# ------------------------------------------------------------ properties
def _noisy_batch(seed, n, t, grid):
    rng = np.random.default_rng(seed)
    caps = rng.normal(50.0, 3.0, size=(n, t, *grid))
    caps[:, :, 0, 0] += rng.uniform(0, 200, size=(n, 1))  # some contact in one cell
    return np.clip(caps, 0, None)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 5), t=st.integers(1, 30),
       grid=st.sampled_from([(1, 1), (2, 3), (4, 4)]), order=st.randoms(use_true_random=False))
def test_rows_follow_their_captures_whatever_the_order(seed, n, t, grid, order):
    caps = list(_noisy_batch(seed, n, t, grid))
    perm = list(range(n))
    order.shuffle(perm)
    fs = make_feature_set(NAME, {"value_range": (0, 1000)}, None)
    X = fs.fit_transform(caps)
    assert np.array_equal(fs.transform([caps[i] for i in perm]), X[perm])


@settings(max_examples=25, deadline=None)
@given(value=st.floats(0, 1023), t=st.integers(1, 50), grid=st.sampled_from([(1, 1), (3, 5), (8, 8)]))
def test_finite_on_constant_captures(value, t, grid):
    x = make_feature_set(NAME, {}, HAART_LIKE).fit_transform([np.full((t, *grid), value)])[0]
    assert np.isfinite(x).all()
    assert np.allclose(x[:6], value / 1023)  # every level is the value over the full scale
    assert not x[6:15].any()  # nothing above the rest level
    np.testing.assert_allclose(x[15:], 0, atol=1e-9)  # no peak, no spread (a float mean of copies may differ by an ulp)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), t=st.integers(2, 30), power=st.integers(-3, 3))
def test_levels_scale_with_gain_and_the_rest_does_not(seed, t, power):
    """Gains of powers of two multiply exactly; min_noise far below the noise (3 units of 1000)."""
    cap = _noisy_batch(seed, 1, t, (4, 4))[0]
    g = 2.0 ** power
    fs = make_feature_set(NAME, {"value_range": (0, 1000), "min_noise": 1e-9}, None)
    a, b = fs.fit_transform([cap])[0], fs.transform([g * cap])[0]
    np.testing.assert_allclose(b[:6], g * a[:6], rtol=1e-12)
    np.testing.assert_allclose(b[6:], a[6:], rtol=1e-12)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), t=st.integers(2, 30), offset=st.integers(1, 500))
def test_an_offset_moves_the_levels_only(seed, t, offset):
    """Integer readings and offsets: every sum is exact; the levels move by offset / full scale."""
    cap = np.rint(_noisy_batch(seed, 1, t, (4, 4))[0])
    fs = make_feature_set(NAME, {"value_range": (0, 1000), "min_noise": 1e-9}, None)
    a, b = fs.fit_transform([cap])[0], fs.transform([cap + offset])[0]
    np.testing.assert_allclose(b[:6], a[:6] + offset / 1000, rtol=1e-12)
    np.testing.assert_allclose(b[6:], a[6:], rtol=1e-12)


# ------------------------------------------------------------ two recording sessions
FRAMES = 108  # 2 s at 54 frames/s
GESTURES = ("constant", "pat", "stroke", "notouch")


def _noise(rng, white: bool, sd: float) -> np.ndarray:
    """(FRAMES, 8, 8) noise of standard deviation ``sd``: white, or an AR(1) with coefficient 0.95
    (a slow wander, most of its power below 1 Hz at 54 frames/s)."""
    e = rng.normal(0, sd, size=(FRAMES, 8, 8))
    if white:
        return e
    phi = 0.95
    out = np.empty_like(e)
    out[0] = e[0]
    for t in range(1, FRAMES):
        out[t] = phi * out[t - 1] + np.sqrt(1 - phi ** 2) * e[t]
    return out


def _touch(rng, gesture: str) -> np.ndarray:
    """(FRAMES, 8, 8) pressure of a gesture (HAART units), 0 for ``notouch``."""
    p = np.zeros((FRAMES, 8, 8))
    level = rng.uniform(30, 150)
    r, c = rng.integers(0, 6, size=2)
    t = np.arange(FRAMES)
    if gesture == "constant":
        p[:, r:r + 3, c:c + 3] = level * (1 + 0.05 * np.sin(2 * np.pi * t / FRAMES))[:, None, None]
    elif gesture == "pat":
        p[(t % 18) < 5, r:r + 3, c:c + 3] = level
    elif gesture == "stroke":
        for k in range(FRAMES):
            col = (k // 6) % 7
            p[k, r:r + 2, col:col + 2] = level
    return p


def session(seed: int, white: bool, gain: float, offset_hi: float, n_per_gesture: int = 15):
    """A recording session: per-cell offsets up to ``offset_hi``, the gesture's pressure and noise
    (sd 1 unit) both times ``gain``, rounded to integers in 0..1023."""
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(0, offset_hi, size=(8, 8))
    caps, labels = [], []
    for g in GESTURES:
        for _ in range(n_per_gesture):
            x = offsets + gain * (_touch(rng, g) + _noise(rng, white, 1.0))
            caps.append(np.clip(np.rint(x), 0, 1023).astype(np.uint16))
            labels.append(g)
    return caps, np.array(labels)


def _notouch_recall(sets, train, test):
    fitted = [make_feature_set(n, {}, HAART_LIKE).fit(train[0]) for n in sets]
    Xa = np.hstack([f.transform(train[0]) for f in fitted])
    Xb = np.hstack([f.transform(test[0]) for f in fitted])
    model = ExtraTreesClassifier(n_estimators=100, random_state=0, n_jobs=1).fit(Xa, train[1])
    pred = model.predict(Xb)
    return np.mean(pred[test[1] == "notouch"] == "notouch")


def test_no_touch_of_another_session_is_recognised():
    """Session A: white noise, gain 1, offsets up to 3 units; session B: slowly wandering noise,
    gain 0.6, offsets up to 5 units. B's captures without touch stay below 1 % of full scale and
    within a few noise units of their rest level, as A's do, so the only errors left are the
    forest's own: we ask for at least 14 of 15 (0.93). (The level-free sets touch-rhythm,
    cell-rhythm and contact-motion, under the same forest, recognised 8 to 12 of 15 over five
    pairs of seeds while writing this test: B's wandering noise reads as a held press.)"""
    a = session(1, white=True, gain=1.0, offset_hi=3.0)
    b = session(2, white=False, gain=0.6, offset_hi=5.0)
    assert _notouch_recall([NAME], a, b) >= 14 / 15


# ------------------------------------------------------------ the design proxies of touch-all
@pytest.mark.parametrize("name,column", [("design-substrate-out", "substrate"), ("design-cover-out", "cover")])
def test_the_design_proxies_leave_one_condition_out_inside_the_challenge_training_subjects(name, column, real_haart):
    """Every capture of the challenge's training subjects (HAART's ``split`` column says ``train``
    for s03-s08 and s10) and none of its test subjects; each value of the column tested once."""
    from touchbench.engine.planning import prepare_evaluation
    from touchbench.protocols.library import find_protocol
    from touchbench.protocols.loading import load_protocol

    (protocol,) = [p for p in load_protocol(find_protocol("touch-all")).evaluation_protocols() if p.evaluation == name]
    prepared = prepare_evaluation(protocol, real_haart)
    meta = real_haart.meta
    test_subjects = set(meta.loc[meta["split"] == "test", "subject"])
    assert test_subjects == {"s01", "s02", "s09"}
    training = meta[meta["subject"].isin({"s03", "s04", "s05", "s06", "s07", "s08", "s10"})]
    used = prepared.dataset.meta
    assert sorted(used["capture_id"]) == sorted(training["capture_id"]) and not set(used["subject"]) & test_subjects
    (folds,) = prepared.folds
    tested = [sorted(set(used[column].iloc[f.test])) for f in folds]
    assert sorted(v for t in tested for v in t) == sorted(set(training[column])) and all(len(t) == 1 for t in tested)
    for f in folds:
        assert not set(used[column].iloc[f.train]) & set(used[column].iloc[f.test])
        assert len(f.train) + len(f.test) == len(used)
