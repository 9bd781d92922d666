"""The live pieces built for recorded streams: the touch rule's hysteresis and evidence, the
two-stage estimator's probabilities, training windows cut from streams, the rule chosen inside a
fold. Every expected value is worked out by hand in the comments."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.engine.live import pick_rule
from touchbench.streams.hysteresis import TouchRule
from touchbench.streams.recognizer import WindowRecognizer
from touchbench.streams.replay import LiveSpec, stream_samples
from touchbench.streams.rules import make_rule

CLASSES = np.array(["a", "b", "idle"], dtype=object)
SENSOR = SensorSpec("toy", (1, 1), 10.0, (0, 100))


def _touch(**kw):
    r = TouchRule("idle", **kw)
    r.start(CLASSES, "none", 10.0, SENSOR)
    r.set_hop(1)  # a decision per frame at 10 Hz: 0.2 s = 2 decisions, 0.3 s = 3
    return r


def _p(a, b, idle):
    return np.array([a, b, idle], dtype=np.float64)


def test_a_touch_begins_after_begin_s_above_begin_and_ends_after_end_s_under_end():
    r = _touch(begin=0.6, end=0.4, begin_s=0.2, end_s=0.3)
    # P(touch) = 1 - P(idle): 0.7 (run 1: idle), 0.7 (run 2: touch begins) -> evidence of both: a
    seq = [_p(.5, .2, .3), _p(.5, .2, .3)]
    assert [r.decide(p) for p in seq] == ["idle", "a"]
    # in touch: P(touch) 0.5 is not under end 0.4 (stays), then 0.3, 0.3 (runs 1, 2: stays), 0.3 (run 3: ends)
    seq = [_p(.1, .4, .5), _p(.1, .2, .7), _p(.1, .2, .7), _p(.1, .2, .7)]
    assert [r.decide(p) for p in seq][-1] == "idle"
    # after the end, one decision above begin is not enough (begin_s = 2 decisions)
    assert r.decide(_p(.1, .8, .1)) == "idle"
    assert r.decide(_p(.1, .8, .1)) == "b"


def test_a_touch_wavering_between_end_and_begin_neither_begins_nor_ends():
    r = _touch(begin=0.6, end=0.4, begin_s=0.1, end_s=0.1)
    assert r.decide(_p(.3, .2, .5)) == "idle"  # P(touch) 0.5 < begin: never begins
    assert r.decide(_p(.5, .2, .3)) == "a"      # 0.7: begins (one decision)
    assert r.decide(_p(.3, .2, .5)) == "a"      # 0.5 >= end: holds


def test_the_gesture_is_the_one_most_probable_over_the_touch_so_far():
    r = _touch(begin=0.5, end=0.5, begin_s=0.1, end_s=0.1)
    # renormalised over a, b: (0.8, 0.2), then (0.4, 0.6), (0.4, 0.6):
    # log sums: a = log .8 + 2 log .4 = -2.056; b = log .2 + 2 log .6 = -2.631 -> a, though b won twice
    out = [r.decide(p) for p in (_p(.8, .2, 0), _p(.4, .6, 0), _p(.4, .6, 0))]
    assert out == ["a", "a", "a"]
    # a fourth (0.4, 0.6): a = -2.972, b = -3.142 -> still a; a fifth: a = -3.888, b = -3.653 -> b
    assert r.decide(_p(.4, .6, 0)) == "a"
    assert r.decide(_p(.4, .6, 0)) == "b"


def test_memory_keeps_only_the_recent_evidence():
    r = _touch(begin=0.5, end=0.5, begin_s=0.1, end_s=0.1, memory=0.2)  # the last 2 decisions
    r.decide(_p(.8, .2, 0))
    assert r.decide(_p(.4, .6, 0)) == "a"  # (.8, .2), (.4, .6): a = log .32, b = log .12
    assert r.decide(_p(.4, .6, 0)) == "b"  # (.4, .6) twice


def test_the_hop_converts_seconds_into_decisions():
    r = TouchRule("idle", begin=0.5, end=0.5, begin_s=0.4, end_s=0.4)
    rec = WindowRecognizer(lambda w: np.tile(_p(.9, .1, 0), (len(w), 1)), CLASSES, SENSOR, [0.2], hop_s=0.2,
                           rule=r)
    # hop 2 frames at 10 Hz: 5 decisions a second, 0.4 s -> 2 decisions
    assert r._begin == 2 and r._end == 2
    labels = [d.label for d in rec.replay(np.zeros((8, 1, 1)))[0]]
    assert labels == ["idle", "a", "a", "a"]  # decisions at frames 2, 4, 6, 8


@pytest.mark.parametrize("spec, field", [({"name": "touch"}, "idle"),
                                         ({"name": "touch", "idle": "idle", "begin": 1.5}, "begin"),
                                         ({"name": "touch", "idle": "idle", "end": True}, "end"),
                                         ({"name": "touch", "idle": "idle", "begin": 0.4, "end": 0.6}, "end"),
                                         ({"name": "touch", "idle": "idle", "end_s": -1}, "end_s")])
def test_the_touch_rule_refuses_bad_values_naming_them(spec, field):
    with pytest.raises(TouchbenchError, match=field):
        make_rule(spec)


def test_the_touch_rule_refuses_an_idle_class_the_model_lacks():
    with pytest.raises(TouchbenchError, match="'rest' is not one of the classes"):
        TouchRule("rest").start(CLASSES, "none", 10.0, SENSOR)


def test_pick_rule_takes_the_best_accuracy_within_the_false_activation_limit():
    acc = np.array([0.9, 0.8, 0.7, np.nan])
    fa = np.array([9.0, 4.0, 1.0, 0.0])
    assert pick_rule(acc, fa, 5.0) == 1  # 0.9 breaks the limit; of 0.8, 0.7 and NaN: 0.8
    assert pick_rule(acc, fa, 10.0) == 0
    assert pick_rule(acc, np.array([9.0, 8.0, 7.0, 7.0]), 5.0) == 2  # none within: the fewest, the first of ties


def _spec(**kw):
    base = dict(streams=(), idle="idle", windows_s=(0.2, 0.4), hop_s=0.1, train_on="streams", train_hop_s=None,
                rules=(), none_label="none")
    return LiveSpec(**{**base, **kw})


def test_stream_samples_are_every_window_labelled_by_its_last_frame():
    frames = np.arange(6, dtype=np.float64).reshape(6, 1, 1)
    truth = np.array(["idle", "idle", "a", "a", "a", "idle"], dtype=object)
    X, y, g = stream_samples([(frames, truth, "p1")], _spec(), 10.0)
    # windows of 2 frames end at frames 2..6 (5 windows), of 4 frames at 4..6 (3), every frame (hop 0.1 s)
    assert [len(w) for w in X] == [2] * 5 + [4] * 3
    assert [int(w[-1, 0, 0]) for w in X] == [1, 2, 3, 4, 5, 3, 4, 5]
    assert list(y) == ["idle", "a", "a", "a", "idle", "a", "a", "idle"]
    assert set(g) == {"p1"}
    X, y, _ = stream_samples([(frames, truth, "p1")], _spec(train_hop_s=0.2), 10.0)
    assert [int(w[-1, 0, 0]) for w in X] == [1, 3, 5, 3, 5]  # ends at 2, 4, 6 and 4, 6


def _meta():
    rows = []
    for subject in ("s1", "s2", "s3"):
        for k, g in enumerate(["idle", "a", "idle", "b", "idle"]):
            rows.append({"capture_id": f"{subject}-{k}", "subject": subject, "gesture": g,
                         "recording": f"{subject}-rec", "start_frame": 4 * k})
    return pd.DataFrame(rows)


def test_the_rule_is_chosen_on_inner_folds_of_the_training_subjects_alone():
    from touchbench.protocols.schemes.base import make_splitter
    from touchbench.protocols.schemes.stream import FRAME_RATE, N_FRAMES

    meta = _meta().assign(**{N_FRAMES: 4, FRAME_RATE: 10.0})
    sp = make_splitter("stream", base="loso", source="recorded", idle="idle", train_on="streams",
                       choose_rule=True, rules=["max"])
    subjects = meta["subject"].to_numpy()
    for fold in sp.folds(meta):
        test_subject = set(subjects[fold.test])
        inner = fold.extra(LiveSpec).inner
        assert len(inner) == 2  # the two training subjects, each left out once
        for f in inner:
            held = {s.subject for s in f.streams}
            trained = set(subjects[list(f.train)])
            assert not (held | trained) & test_subject  # the test subject is never looked at
            assert held and not held & trained
            assert {s.subject for s in f.train_streams} == trained
        assert {s.subject for s in fold.extra(LiveSpec).train_streams} == set(subjects[fold.train])


def _captures(seed=0):
    """8 captures of each of three classes, 30 frames of 4 x 4 cells: rest (readings 0..2), a press (rest,
    then a ramp up to 200 held) and a pat (rest, then 200 on and off every 2 frames), on 2 x 2 cells."""
    rng = np.random.default_rng(seed)
    ones = np.zeros((1, 4, 4), np.float32)
    ones[:, 1:3, 1:3] = 1.0
    press = np.r_[np.zeros(10), np.minimum(np.arange(1, 21) * 25, 200)].astype(np.float32)
    pat = np.r_[np.zeros(10), np.tile([0, 0, 200, 200], 5)].astype(np.float32)
    out = [rng.integers(0, 3, (30, 4, 4)).astype(np.float32) for _ in range(8)]
    out += [press[:, None, None] * ones + rng.integers(0, 3, (30, 4, 4)) for _ in range(8)]
    out += [pat[:, None, None] * ones + rng.integers(0, 3, (30, 4, 4)) for _ in range(8)]
    return out, np.array(["rest"] * 8 + ["press"] * 8 + ["pat"] * 8, dtype=object)


def test_two_stage_probabilities_are_p_touch_times_the_gesture_classifiers():
    from touchbench.classifiers.fitting import fit_pipeline

    caps, y = _captures()
    sensor = SensorSpec("toy", (4, 4), 20.0, (0, 255))
    # through the run engine's fit path: the estimator gets codes and the class names
    fm = fit_pipeline([], "two-stage", {"features": ["touch-rhythm"], "params": {"n_estimators": 20}, "idle": "rest"},
                      0, caps, y, None, sensor)
    est = fm.estimator
    test, _ = _captures(seed=1)
    P = fm.window_proba(test)
    assert list(fm.classes) == ["pat", "press", "rest"]
    F = est.detector_.transform(test)
    t = est.touch_proba(F)
    np.testing.assert_allclose(P[:, 2], 1.0 - t)  # P(idle) = 1 - P(touch)
    G = est.method_.proba_rows(F)  # the gesture classifier's, over its own classes (pat, press)
    np.testing.assert_allclose(P[:, :2], t[:, None] * G)
    np.testing.assert_allclose(P.sum(axis=1), 1.0)
    assert (P.argmax(axis=1) == np.repeat([2, 1, 0], 8)).mean() >= 0.9  # the toy classes are easy


def test_two_stage_finds_the_class_without_contact_or_refuses_a_named_one_it_lacks():
    from touchbench.classifiers.fitting import fit_pipeline

    caps, y = _captures()
    sensor = SensorSpec("toy", (4, 4), 20.0, (0, 255))
    # no idle named: 'rest' (readings 0..2, never 10 noise floors above rest) is the one class without contact
    fm = fit_pipeline([], "two-stage", {"features": ["touch-rhythm"], "params": {"n_estimators": 5}}, 0, caps, y,
                      None, sensor)
    assert fm.estimator.selection_note_ == "two-stage: idle class 'rest' found from the data (the one class without contact)"
    assert fm.estimator.detector_ is not None
    # the touches alone: no class without contact, the pipeline alone (P(touch) = 1)
    fm = fit_pipeline([], "two-stage", {"features": ["touch-rhythm"], "params": {"n_estimators": 5}}, 0, caps[8:],
                      y[8:], None, sensor)
    assert fm.estimator.detector_ is None and "the pipeline alone" in fm.estimator.selection_note_
    np.testing.assert_allclose(fm.window_proba(caps[8:10]).sum(axis=1), 1.0)
    with pytest.raises(TouchbenchError, match="the idle class 'idle' is not among the training samples' classes"):
        fit_pipeline([], "two-stage", {"features": ["touch-rhythm"], "idle": "idle"}, 0, caps, y, None, sensor)
