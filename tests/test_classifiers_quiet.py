"""Windows of the training length and the no-contact gate (``quiet-gated``, ``touch-et-quiet``).

The helpers are checked on tiny inputs with the values worked out by hand in each test; the classifier
on hand-made captures: a class of noise alone, classes pressed well above it, and what each part of the
classifier does with a capture longer than every training capture.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from touchbench.classifiers import make_classifier
from touchbench.classifiers.base import ParamError
from touchbench.classifiers.fitting import fit_pipeline, proba_over
from touchbench.classifiers.quiet import gate_decides, gated_proba, log_signed, quiet_class, window_starts
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.methods import FeaturePipeline, method_spec

SENSOR = SensorSpec("test-4x4", (4, 4), 20.0, (0, 1023))
FRAMES = 40


# ------------------------------------------------------------------ helpers, by hand
def test_window_starts_step_through_and_end_at_the_last_frame():
    assert window_starts(10, 4, 3) == [0, 3, 6]  # 6 + 4 = 10: the last window already ends at frame 10
    assert window_starts(11, 4, 3) == [0, 3, 6, 7]  # 7 = 11 - 4 added so the last frames are read
    assert window_starts(4, 4, 3) == [0]  # no longer than one window: whole
    assert window_starts(3, 4, 1) == [0]
    assert window_starts(6, 4, 0) == [0, 1, 2]  # a step below one frame is one frame


def test_the_quiet_class_is_the_one_whose_median_contact_share_is_at_most_the_bound():
    codes = np.array([0, 0, 1, 1, 2, 2])
    frames = np.array([0.0, 0.1, 0.5, 0.6, 0.02, 0.9])  # medians: 0.05, 0.55, 0.46
    assert quiet_class(codes, frames, 0.05) == 0
    assert quiet_class(codes, frames, 0.04) is None  # no class that quiet
    assert quiet_class(codes, frames, 0.5) is None  # two classes (0 and 2): no single one
    assert quiet_class(np.array([3, 3]), np.array([0.0, 0.0]), 0.05) is None  # one class only


def test_log_signed_is_sign_times_log_of_one_plus_the_magnitude():
    e1 = math.e - 1.0
    np.testing.assert_allclose(log_signed(np.array([[-e1, 0.0, e1]])), [[-1.0, 0.0, 1.0]])


def test_the_gate_gets_its_class_and_the_others_share_the_rest_in_the_pipelines_proportions():
    base = np.array([[0.2, 0.5, 0.3],   # others 0.5 and 0.3 of 0.8: 0.625 and 0.375, times 1 - 0.6
                     [1.0, 0.0, 0.0]])  # the pipeline gives the others nothing: an even share of 1 - 0.2
    got = gated_proba(base, np.array([0.6, 0.2]), 0)
    np.testing.assert_allclose(got, [[0.6, 0.25, 0.15], [0.2, 0.4, 0.4]])
    np.testing.assert_allclose(got.sum(axis=1), 1.0)


def test_the_gate_decides_only_above_one_half_where_no_touch_class_is_sure():
    base = np.array([[0.1, 0.6, 0.3],    # class 1 at 0.6 >= 0.5: the pipeline is sure of a touch
                     [0.2, 0.4, 0.4],    # no other class reaches 0.5
                     [0.0, 0.45, 0.55]])  # class 2 at 0.55: sure
    np.testing.assert_array_equal(gate_decides(base, np.array([0.9, 0.9, 0.9]), 0, 0.5), [False, True, False])
    np.testing.assert_array_equal(gate_decides(base, np.array([0.5, 0.5, 0.5]), 0, 0.5), [False, False, False])
    np.testing.assert_array_equal(gate_decides(base, np.array([0.9, 0.9, 0.9]), 0, 0.6), [False, True, True])


def test_probabilities_where_the_gate_decides_and_where_it_does_not():
    caps, y = _data()
    est = _gated().fit(caps, y)  # classes hold, none, tap: the quiet class is column 1
    base = np.array([[0.2, 0.2, 0.6], [0.3, 0.4, 0.3]])
    est._parts = lambda X: (base, np.array([0.8, 0.8]))
    # row 0: tap is sure (0.6): the others renormalised, none 0: hold 0.2 / 0.8, tap 0.6 / 0.8
    # row 1: the gate decides: none 0.8, hold and tap (1 - 0.8) x 0.3 / 0.6 each
    np.testing.assert_allclose(est.predict_proba([None, None]), [[0.25, 0.0, 0.75], [0.1, 0.8, 0.1]])
    assert list(est.predict([None, None])) == ["tap", "none"]


# ------------------------------------------------------------------ the classifier on hand-made captures
def _quiet(rng, frames=FRAMES):
    """Noise alone: every cell near 5, sd 0.7, rounded."""
    return np.clip(np.rint(rng.normal(5.0, 0.7, (frames, 4, 4))), 0, 1023).astype(np.uint16)


def _pressed(rng, kind, frames=FRAMES):
    x = _quiet(rng, frames)
    if kind == "hold":  # a 2 x 2 block held 200 above the rest
        x[:, 1:3, 1:3] += 200
    else:  # "tap": one cell 300 above the rest every other 5 frames
        on = (np.arange(frames) // 5) % 2 == 0
        x[on, 0, 0] += 300
    return x


def _data(seed=0, per=6):
    rng = np.random.default_rng(seed)
    caps, y = [], []
    for label in ("hold", "none", "tap"):
        for _ in range(per):
            caps.append(_quiet(rng) if label == "none" else _pressed(rng, label))
            y.append(label)
    return caps, np.array(y)


def _gated(**kw):
    return make_classifier("quiet-gated", random_state=0, sensor=SENSOR, features=["touch-rhythm"],
                           estimator="touch-extra-trees", params={"n_estimators": 20}, **kw)


def test_the_class_without_contact_is_found_and_gated():
    caps, y = _data()
    est = _gated().fit(caps, y)
    assert est.quiet_ == "none" and est.gate_ is not None
    rng = np.random.default_rng(9)
    test = [_quiet(rng), _pressed(rng, "hold"), _pressed(rng, "tap")]
    assert list(est.predict(test)) == ["none", "hold", "tap"]
    p = est.predict_proba(test)
    np.testing.assert_allclose(p.sum(axis=1), 1.0)
    assert p[0, 1] > 0.5 and p[1, 1] < 0.5 and p[2, 1] < 0.5  # column 1: "none" of the sorted classes


def test_without_a_class_of_no_contact_there_is_no_gate():
    caps, y = _data()
    keep = y != "none"
    est = _gated().fit([c for c, k in zip(caps, keep) if k], y[keep])
    assert est.quiet_ is None and est.gate_ is None


def test_captures_of_the_training_length_are_read_as_the_plain_pipeline_reads_them():
    caps, y = _data()
    est = _gated(gate=False).fit(caps, y)
    plain = fit_pipeline([("touch-rhythm", {})], "touch-extra-trees", {"n_estimators": 20}, 0, caps, y, sensor=SENSOR)
    rng = np.random.default_rng(3)
    test = [_pressed(rng, "hold"), _quiet(rng), _pressed(rng, "tap", frames=FRAMES - 7)]
    np.testing.assert_array_equal(est.predict_proba(test), proba_over(plain.fitted, plain.transform(test), est.classes_))


def test_a_longer_capture_is_the_mean_over_windows_of_the_training_length():
    caps, y = _data()
    est = _gated(gate=False, stride=0.5).fit(caps, y)  # windows of 40 frames, 20 apart
    long = _pressed(np.random.default_rng(4), "tap", frames=90)  # starts 0, 20, 40 and 50 (= 90 - 40)
    windows = [long[a:a + 40] for a in (0, 20, 40, 50)]
    each = proba_over(est.method_.fitted, est.method_.transform(windows), est.classes_)
    np.testing.assert_allclose(est.predict_proba([long])[0], each.mean(axis=0))
    shorter = long[:79]  # 79 < 2 x 40: read whole, as the plain pipeline reads it
    np.testing.assert_allclose(est.predict_proba([shorter])[0],
                               proba_over(est.method_.fitted, est.method_.transform([shorter]), est.classes_)[0])
    whole = _gated(gate=False, windows=False).fit(caps, y)
    np.testing.assert_allclose(whole.predict_proba([long])[0],
                               proba_over(whole.method_.fitted, whole.method_.transform([long]), whole.classes_)[0])


def test_the_gate_of_a_longer_capture_is_the_median_over_its_windows():
    caps, y = _data()
    est = _gated(stride=0.5).fit(caps, y)
    rng = np.random.default_rng(5)
    # 90 frames: windows at 0, 20, 40, 50; a tap in frames 0..9 only: the first window holds it, the
    # three others are noise alone; the capture's gate is the median of the four windows' gates
    long = _quiet(rng, 90)
    long[:10, 0, 0] += 300
    g = est.gate_.predict_proba(log_signed(est._evidence([long[a:a + 40] for a in (0, 20, 40, 50)])))[:, 1]
    _, got = est._parts([long])
    assert got[0] == pytest.approx(float(np.median(g)))


def test_no_sensor_and_bad_parameters_are_refused():
    caps, y = _data(per=2)
    with pytest.raises(TouchbenchError, match="needs the sensor"):
        make_classifier("quiet-gated", random_state=0, sensor=None).fit(caps, y)
    for params, message in (({"gate_c": 0}, r"'gate_c' parameter of QuietGated must be a float in the range \(0\.0, inf\)"),
                            ({"sure": 0}, r"'sure' parameter of QuietGated must be a float in the range \(0\.0, 1\.0\]"),
                            ({"quiet_frames": 1.0}, r"'quiet_frames' .* must be a float in the range \[0\.0, 1\.0\)"),
                            ({"stride": 0}, r"'stride' parameter of QuietGated must be a float in the range \(0\.0, 1\.0\]")):
        with pytest.raises(ParamError, match=message):
            _gated(**params).fit(caps, y)


def test_touch_et_quiet_round_trip_through_the_method_registry():
    caps, y = _data()
    spec = method_spec("touch-et-quiet", params={"n_estimators": 20})
    assert spec.estimator == "quiet-gated" and spec.takes_captures
    pipe = FeaturePipeline(spec, random_state=0, sensor=SENSOR).fit(caps, y)
    rng = np.random.default_rng(7)
    assert list(pipe.predict([_quiet(rng, 100), _pressed(rng, "hold", 100)])) == ["none", "hold"]


def test_the_gate_is_trained_on_the_windows_of_training_captures_longer_than_the_median():
    caps, y = _data()  # 18 captures of 40 frames: the window is 40 frames
    long = _quiet(np.random.default_rng(6), 90)  # 4 windows at stride 0.5: starts 0, 20, 40, 50
    est = _gated(stride=0.5).fit(caps + [long], np.append(y, "none"))
    assert (est.window_, est.longest_) == (40, 90)
    assert est.gate_[0].n_samples_seen_ == 18 + 4


def test_training_on_windows_cuts_the_captures_at_least_twice_the_window_long():
    caps, y = _data()  # 18 captures of 40 frames: the window is 40 frames
    rng = np.random.default_rng(8)
    more = [_pressed(rng, "tap", 90), _pressed(rng, "tap", 79)]  # 90 >= 80: 4 windows; 79 < 80: whole
    est = _gated(gate=False, stride=0.5, train_windows=True).fit(caps + more, np.append(y, ["tap", "tap"]))
    assert (est.window_, est.longest_, est.n_training_) == (40, 79, 18 + 4 + 1)
    plain = _gated(gate=False, stride=0.5).fit(caps + more, np.append(y, ["tap", "tap"]))
    assert (plain.window_, plain.longest_, plain.n_training_) == (40, 90, 20)


def test_touch_et_quiet_win_is_touch_et_quiet_trained_on_windows():
    quiet, win = method_spec("touch-et-quiet"), method_spec("touch-et-quiet-win")
    assert win.estimator_params == {**quiet.estimator_params, "train_windows": True}
    caps, y = _data()
    long = _pressed(np.random.default_rng(10), "hold", 100)  # 100 >= 2 x 40: cut into windows 10 frames apart
    pipe = FeaturePipeline(method_spec("touch-et-quiet-win", params={"n_estimators": 20}), random_state=0,
                           sensor=SENSOR).fit(caps + [long], np.append(y, "hold"))
    assert pipe.method_.estimator.n_training_ == 18 + 7  # windows of 40 frames at 0, 10, 20, ..., 60
