"""Training for shift (``shift-augmented``, ``touch-et-shift``): each sensor effect on small
hand-made captures, with the values worked out by hand in each test; determinism for a seed; the
training set's size; and a round trip through the method registry and ``FeaturePipeline``.

Most tests switch every effect off but the one under test (a range ``(v, v)`` draws ``v``).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from touchbench.classifiers import make_classifier
from touchbench.classifiers import augment
from touchbench.classifiers.augment import Shift, crop_window, shifted_copy
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.engine.testing import random_dataset
from touchbench.features.base import make_feature_set
from touchbench.methods import FeaturePipeline, method_spec

SENSOR = SensorSpec("test-4x4", (4, 4), 10.0, (0, 1000))  # full scale 1000
OFF = dict(gain=(1.0, 1.0), offset=(0.0, 0.0), noise=(0.0, 0.0), dead=(0.0, 0.0), crop=1.0)


def _augmenter(sensor=SENSOR, seed=0, copies=1, **effects):
    return make_classifier("shift-augmented", random_state=seed, sensor=sensor, features=["contact-evidence"],
                           estimator="zhou-tree", copies=copies, **{**OFF, **effects})


def _press(rest=10, touched=50, frames=8, dtype=np.uint16):
    """A capture resting at ``rest`` everywhere but a 2 x 2 block held at ``touched``: its quiet quarter
    (4 of 16 cells) rests at ``rest``, so its rest level is ``rest``."""
    x = np.full((frames, 4, 4), rest, dtype=dtype)
    x[:, 1:3, 1:3] = touched
    return x


# ------------------------------------------------------------------ each effect
def test_a_gain_of_two_doubles_the_height_above_the_rest_level():
    x = _press(rest=10, touched=50)
    (copy,) = _augmenter(gain=(2.0, 2.0)).augmented([x])[1:]
    want = _press(rest=10, touched=90)  # 10 + 2 * (50 - 10)
    np.testing.assert_array_equal(copy, want)


def test_an_offset_is_a_fraction_of_full_scale_in_the_direction_of_more_pressure():
    (copy,) = _augmenter(offset=(0.01, 0.01)).augmented([_press(rest=10, touched=50)])[1:]
    np.testing.assert_array_equal(copy, _press(rest=20, touched=60))  # 0.01 * (1000 - 0) = 10 counts
    flipped = SensorSpec("test-flipped", (4, 4), 10.0, (0, 1000), higher_is_more_pressure=False)
    (copy,) = _augmenter(sensor=flipped, offset=(0.01, 0.01)).augmented([_press(rest=990, touched=900)])[1:]
    np.testing.assert_array_equal(copy, _press(rest=980, touched=890))


def test_dead_cells_are_a_drawn_share_of_the_cells_held_at_the_rest_level():
    """Cell c (row-major) reads 100 + 10 c, plus 2 on odd frames: medians 101 + 10 c; the quiet quarter
    is cells 0-3 (medians 101, 111, 121, 131), whose median 116 is the rest level. A quarter of 16
    cells is 4 dead cells, constant at 116 (126 after an offset of 10 counts); every other cell still
    alternates by 2."""
    t = np.arange(8)[:, None, None]
    x = (100 + 10 * np.arange(16).reshape(1, 4, 4) + 2 * (t % 2)).astype(np.uint16)
    for offset, level in ((0.0, 116), (0.01, 126)):
        (copy,) = _augmenter(dead=(0.25, 0.25), offset=(offset, offset)).augmented([x])[1:]
        constant = (copy == copy[:1]).all(axis=0)
        assert constant.sum() == 4
        assert (copy[:, constant] == level).all()
        np.testing.assert_array_equal(copy[:, ~constant], x[:, ~constant] + (level - 116))


def test_dead_cells_round_the_drawn_share():
    rng = np.random.default_rng(0)
    assert [len(augment.dead_cells(64, f, rng)) for f in (0.0, 0.05, 0.5, 1.0)] == [0, 3, 32, 64]  # 3.2 -> 3
    cells = augment.dead_cells(64, 0.5, rng)
    assert len(set(cells.tolist())) == 32 and cells.min() >= 0 and cells.max() < 64


def test_added_read_noise_is_a_multiple_of_the_captures_noise_floor_white_or_wandering():
    """Every cell reads 100 -+ 2 on alternate frames: median 100, absolute deviation 2, so the noise
    floor is 1.4826 * 2 = 2.9652; a float capture is neither rounded nor clipped here, so the copy
    minus the capture is the added noise: its sd is the drawn multiple of 2.9652; white noise has no
    correlation between frames, the AR(1) its coefficient at lag 1."""
    frames = 2000
    x = 100.0 + 2.0 * (-1.0) ** np.arange(frames)[:, None, None] * np.ones((1, 4, 4))
    for k, ar in ((1.0, 0.0), (0.5, 0.0), (1.0, 0.9)):
        shift = Shift(start=0, length=frames, gain=1.0, offset=0.0, noise=k, ar=ar, dead=0.0)
        added = shifted_copy(x, SENSOR, shift, np.random.default_rng(1)) - x
        assert math.isclose(added.std(), k * 2.9652, rel_tol=0.06)
        lag1 = np.mean([np.corrcoef(added[1:, i, j], added[:-1, i, j])[0, 1] for i in range(4) for j in range(4)])
        assert abs(lag1 - ar) < 0.05


def test_a_share_of_the_copies_gets_wandering_noise():
    rng = np.random.default_rng(0)
    ranges = {"gain": (1, 1), "offset": (0, 0), "noise": (1, 1), "ar_coef": (0.8, 0.98), "dead": (0, 0)}
    ars = [augment.draw_shift(rng, ranges, 0.5, 1.0, 10, 1).ar for _ in range(400)]
    wandering = [a for a in ars if a > 0]
    assert 150 < len(wandering) < 250 and min(wandering) >= 0.8 and max(wandering) <= 0.98
    assert all(augment.draw_shift(rng, ranges, 0.0, 1.0, 10, 1).ar == 0 for _ in range(50))


def test_the_crop_is_a_contiguous_window_taken_anywhere_of_a_drawn_length():
    """8 frames, crop 0.75: windows of 6, 7 or 8 frames, starting anywhere they fit; each frame of
    the capture reads its index, so a copy is a window exactly when its frames count up by one."""
    x = (np.arange(8)[:, None, None] + np.zeros((1, 4, 4))).astype(np.uint16) + 10
    copies = _augmenter(crop=0.75, copies=60).augmented([x])[1:]
    seen = {(int(c[0, 0, 0]) - 10, len(c)) for c in copies}
    assert {n for _, n in seen} == {6, 7, 8}
    assert {s for s, n in seen if n == 6} == {0, 1, 2}  # every start a 6-frame window can take
    for c in copies:
        np.testing.assert_array_equal(c[:, 0, 0], np.arange(c[0, 0, 0], c[0, 0, 0] + len(c)))


def test_the_crop_is_never_shorter_than_the_feature_sets_need():
    """touch-windows takes 2-s windows: 20 frames at 10 frames/s, so no copy of a 24-frame capture is
    shorter than 20 frames, whatever ``crop`` allows (0.5 would allow 12)."""
    est = make_classifier("shift-augmented", random_state=0, sensor=SENSOR, features=["touch-windows"],
                          copies=40, **{**OFF, "crop": 0.5})
    assert est.frames_needed(24) == 20
    lengths = {len(c) for c in est.augmented([_press(frames=24)])[1:]}
    assert min(lengths) == 20 and lengths <= set(range(20, 25))


@settings(max_examples=60, deadline=None)
@given(frames=st.integers(1, 300), crop=st.floats(0.01, 1.0), need=st.integers(1, 400), seed=st.integers(0, 2**32 - 1))
def test_a_crop_window_lies_inside_the_capture(frames, crop, need, seed):
    start, length = crop_window(frames, crop, need, np.random.default_rng(seed))
    assert 0 <= start and start + length <= frames
    assert length >= min(frames, need) and length >= min(frames, math.ceil(crop * frames - 1e-9))


def test_copies_are_rounded_clipped_and_keep_the_dtype():
    byte = SensorSpec("test-byte", (4, 4), 10.0, (0, 255))
    (copy,) = _augmenter(sensor=byte, gain=(2.0, 2.0)).augmented([_press(rest=10, touched=200, dtype=np.uint8)])[1:]
    assert copy.dtype == np.uint8
    np.testing.assert_array_equal(copy, _press(rest=10, touched=255, dtype=np.uint8))  # 10 + 2 * 190 = 390 -> 255
    (copy,) = _augmenter(sensor=byte, gain=(1.5, 1.5)).augmented([_press(rest=10, touched=15, dtype=np.uint8)])[1:]
    np.testing.assert_array_equal(copy, _press(rest=10, touched=18, dtype=np.uint8))  # 17.5 rounds to 18
    unit = SensorSpec("test-unit", (4, 4), 10.0, (0, 1))
    x = _press(rest=0.1, touched=0.3, dtype=np.float32)
    (copy,) = _augmenter(sensor=unit, gain=(2.0, 2.0)).augmented([x])[1:]
    assert copy.dtype == np.float32  # a float sensor is clipped, not rounded
    np.testing.assert_allclose(copy, _press(rest=0.1, touched=0.5, dtype=np.float32), rtol=1e-6)


# ------------------------------------------------------------------ sensors and parameters
def test_a_channel_sensor_and_no_sensor_are_refused():
    strip = SensorSpec("strip-4", (1, 4), 25.0, (0, 1023), channels=("x", "y", "pressure", "fur"))
    est = make_classifier("shift-augmented", random_state=0, sensor=strip, features=["contact-evidence"])
    assert "is a channel sensor (x, y, pressure, fur)" in est.check_sensor(strip, 10)
    x = np.zeros((10, 1, 4), dtype=np.uint16)
    with pytest.raises(TouchbenchError, match="cannot serve sensor 'strip-4'.*not cells of a pressure surface"):
        est.fit([x, x], ["a", "b"])
    with pytest.raises(TouchbenchError, match=r"needs the sensor's value range.*pass sensor=SensorSpec"):
        make_classifier("shift-augmented", random_state=0, features=["contact-evidence"]).fit([_press()], ["a"])


@pytest.mark.parametrize("params,message", [
    ({"gain": (0.0, 1.2)}, "'gain' parameter of ShiftAugmented must be a list of 2 items, each a float in the range "
                           "(0.0, inf), low <= high. Got (0.0, 1.2)"),
    ({"offset": (0.01, 0.0)}, "'offset' parameter of ShiftAugmented must be a list of 2 items, each a float in the "
                              "range [-1.0, 1.0], low <= high. Got (0.01, 0.0)"),
    ({"ar_coef": (0.5, 1.0)}, "'ar_coef' parameter of ShiftAugmented must be a list of 2 items, each a float in the "
                              "range [0.0, 1.0), low <= high. Got (0.5, 1.0)"),
    ({"dead": 0.1}, "'dead' parameter of ShiftAugmented must be a list of 2 items"),
    ({"crop": 0.0}, "'crop' parameter of ShiftAugmented must be a float in the range (0.0, 1.0]. Got 0.0"),
    ({"copies": -1}, "'copies' parameter of ShiftAugmented must be an int in the range [0, 100]. Got -1"),
])
def test_bad_parameters_are_refused_with_the_rule(params, message):
    with pytest.raises(TouchbenchError, match=re.escape(message)) as e:
        _augmenter(**params).fit([_press(), _press()], ["a", "b"])
    assert e.value.field == (next(iter(params)),)


# ------------------------------------------------------------------ seeds and the training set
def _small():
    ds = random_dataset(subjects=("s1", "s2"), gestures=("pat", "rub"), per_cell=3, frames=(20, 30),
                        sensor=SENSOR, seed=4)
    return ds.captures, ds.meta["gesture"].to_numpy(), ds.meta["subject"].to_numpy()


def test_the_same_seed_gives_the_same_copies_and_another_seed_others():
    caps, y, _ = _small()
    defaults = {"features": ["contact-evidence"], "estimator": "zhou-tree"}
    a, b, c = (make_classifier("shift-augmented", random_state=s, sensor=SENSOR, **defaults).augmented(caps)
               for s in (7, 7, 8))
    assert len(a) == len(b) == len(c) == 3 * len(caps)  # two copies by default
    assert all(u.dtype == v.dtype and np.array_equal(u, v) for u, v in zip(a, b))
    assert all(np.array_equal(u, v) for u, v in zip(a[:len(caps)], c))  # the originals as given
    assert not any(u.shape == v.shape and np.array_equal(u, v) for u, v in zip(a[len(caps):], c[len(caps):]))


def test_the_estimator_is_trained_on_the_originals_and_the_copies(monkeypatch):
    """Naive Bayes counts its training rows per class: 3 copies + the original of 6 captures per class
    is 24 per class; the subjects given go with every copy."""
    caps, y, groups = _small()
    seen = {}
    original = augment.fit_pipeline

    def spy(*args, **kw):
        seen["y"], seen["groups"] = args[5], args[6]
        return original(*args, **kw)

    monkeypatch.setattr(augment, "fit_pipeline", spy)
    est = make_classifier("shift-augmented", random_state=0, sensor=SENSOR, features=["contact-evidence"],
                          estimator="jung-naive-bayes", copies=3).fit(caps, y, groups=groups)
    assert est.method_.estimator.class_count_.tolist() == [24.0, 24.0]
    assert list(seen["y"]) == list(y) * 4 and list(seen["groups"]) == list(groups) * 4


def test_fit_and_predict_are_bit_identical_for_a_seed():
    caps, y, groups = _small()
    probas = [make_classifier("shift-augmented", random_state=s, sensor=SENSOR, features=["contact-evidence"],
                              params={"n_estimators": 20}).fit(caps, y, groups).predict_proba(caps) for s in (3, 3)]
    assert np.array_equal(*probas)


# ------------------------------------------------------------------ the method
def test_touch_et_shift_round_trip_features_of_the_captures_as_given():
    """Trained through the method registry and FeaturePipeline; its probabilities are the forest's on
    touch-et-contact's four sets computed by hand on the test captures as given."""
    caps, y, groups = _small()
    test = random_dataset(subjects=("s3",), gestures=("pat", "rub"), per_cell=2, frames=(20, 30),
                          sensor=SENSOR, seed=5).captures
    spec = method_spec("touch-et-shift", copies=1, params={"n_estimators": 20})
    assert spec.estimator == "shift-augmented" and not spec.feature_sets
    pipe = FeaturePipeline(spec, random_state=2, sensor=SENSOR).fit(caps, y, groups)
    inner = pipe.fitted_.estimator
    assert inner.n_training_ == 2 * len(caps)
    names = ["touch-rhythm", "cell-rhythm", "contact-motion", "contact-evidence"]
    X = np.hstack([make_feature_set(n, {}, SENSOR).fit(test).transform(test) for n in names])
    forest = inner.method_.estimator
    P = pipe.predict_proba(test)
    np.testing.assert_array_equal(np.column_stack([P["pat"], P["rub"]]), forest.predict_proba(X))
    np.testing.assert_array_equal(pipe.predict(test), np.array(["pat", "rub"])[forest.predict(X)])


def test_without_copies_touch_et_shift_is_touch_et_contact():
    caps, y, groups = _small()
    shift = FeaturePipeline(method_spec("touch-et-shift", copies=0, params={"n_estimators": 20}), random_state=4,
                            sensor=SENSOR).fit(caps, y, groups)
    contact = FeaturePipeline(method_spec("touch-et-contact", n_estimators=20), random_state=4,
                              sensor=SENSOR).fit(caps, y, groups)
    a, b = shift.predict_proba(caps), contact.predict_proba(caps)
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_one_class_and_one_capture_are_served():
    x = _press(rest=10, touched=50, frames=20)
    est = _augmenter(copies=2, gain=(0.8, 1.25), noise=(0.0, 1.0)).fit([x], ["pat"])
    assert est.n_training_ == 3 and est.predict([x]).tolist() == ["pat"]
    assert est.predict_proba([x]).tolist() == [[1.0]]


def test_copies_that_would_not_fit_in_memory_are_refused_before_any_is_made(monkeypatch):
    # 3 captures of 8 x 4 x 4 uint16 values (256 bytes each); 2 copies of each, 128 bytes of array
    # header a copy: at most 2 x 3 x (256 + 128) = 2,304 bytes
    captures = [_press(), _press(rest=20), _press(touched=80)]
    made = []
    monkeypatch.setattr(augment, "shifted_copy", lambda c, *a: made.append(c) or c)
    monkeypatch.setattr(augment, "memory_limit", lambda: 2303)
    with pytest.raises(augment.ParamError, match=r"copies=2 would make 6 copies of 3 training captures, up to "
                                                 r"2,304 bytes, over the limit of 2,303 bytes") as e:
        _augmenter(copies=2).augmented(captures)
    assert e.value.field == ("copies",) and made == []
    monkeypatch.setattr(augment, "memory_limit", lambda: 2304)
    assert len(_augmenter(copies=2).augmented(captures)) == 9 and len(made) == 6
