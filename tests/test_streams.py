"""Streams as data, decision rules and the recogniser's gate (touchbench.streams), by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.streams.recognizer import WindowRecognizer
from touchbench.streams.rules import GateRule, HmmRule, MajorityRule, MaxRule, best_level, make_rule, peak_contact
from touchbench.streams.timeline import (
    REST, Stream, decisions_per_frame, label_runs, recorded_streams, spliced_streams, stream_frames,
)

SENSOR = SensorSpec(name="t", grid=(1, 1), frame_rate=10.0, value_range=(0, 100))


def _meta(rows):
    return pd.DataFrame(rows, columns=["capture_id", "subject", "gesture"])


# ----------------------------------------------------------------- timeline
def test_decisions_per_frame_hold_each_decision_until_the_next():
    # decisions after frames 2 and 4 (1-based counts) of a 6-frame stream:
    # frame 1 undecided; frames 2-3 "a"; frames 4-6 "b"
    got = decisions_per_frame([2, 4], ["a", "b"], 6, "u")
    assert got.tolist() == ["u", "a", "a", "b", "b", "b"]
    assert decisions_per_frame([], [], 3, "u").tolist() == ["u", "u", "u"]
    assert decisions_per_frame([], [], 0, "u").tolist() == []


def test_label_runs_by_hand():
    assert label_runs(["x", "x", "y", "x"]) == [(0, "x"), (2, "y"), (3, "x")]
    assert label_runs([]) == []


def test_stream_frames_concatenate_segments_and_label_each_frame():
    caps = [np.full((4, 1, 1), 7, np.uint16), np.full((3, 1, 1), 9, np.uint16)]
    s = Stream("s", "p", "p", "spliced", ((1, 0, 3), (REST, 0, 2), (0, 1, 3)))
    frames, truth = stream_frames(caps, ["g", "idle"], s, "idle", rest_value=0)
    # capture 1 whole (3 frames of 9, label idle), 2 rest frames (0, idle), frames 1..2 of capture 0 (7, g)
    assert frames[:, 0, 0].tolist() == [9, 9, 9, 0, 0, 7, 7]
    assert truth.tolist() == ["idle"] * 5 + ["g", "g"]
    assert frames.dtype == np.uint16 and s.n_frames == 7 and s.captures.tolist() == [0, 1]


def test_spliced_streams_one_per_subject_gestures_between_idle_stretches():
    meta = _meta([("c0", "p1", "tap"), ("c1", "p1", "rest"), ("c2", "p1", "rub"), ("c3", "p2", "tap"),
                  ("c4", "p2", "rub")])
    n = np.array([10, 50, 10, 10, 10])
    rows = np.array([0, 1, 2, 3, 4])
    streams = spliced_streams(meta, n, rows, "gesture", "rest", (5, 5), np.random.default_rng(0))
    assert [s.subject for s in streams] == ["p1", "p2"]
    p1, p2 = streams
    # p1: idle, gesture, idle, gesture, idle: the gestures c0 and c2 in some order, each whole
    kinds = [i for i, _, _ in p1.segments]
    assert kinds[0::2] == [1, 1, 1] and sorted(kinds[1::2]) == [0, 2]
    assert all(b - a == 5 and 0 <= a and b <= 50 for i, a, b in p1.segments[0::2])  # 5 frames of the idle capture
    assert all((a, b) == (0, 10) for _, a, b in p1.segments[1::2])
    # p2 has no idle capture: its stretches are the sensor's rest
    assert [i for i, _, _ in p2.segments[0::2]] == [REST, REST, REST]
    assert {i for i, _, _ in p2.segments[1::2]} == {3, 4}
    # seeded: the same generator seed gives the same streams; another seed another order or offsets
    again = spliced_streams(meta, n, rows, "gesture", "rest", (5, 5), np.random.default_rng(0))
    assert again == streams


def test_spliced_streams_never_use_a_capture_outside_the_rows_given():
    meta = _meta([("c0", "p1", "tap"), ("c1", "p1", "rest"), ("c2", "p2", "rest"), ("c3", "p2", "tap")])
    streams = spliced_streams(meta, np.array([10] * 4), np.array([2, 3]), "gesture", "rest", (2, 4),
                              np.random.default_rng(1), per_stream=1)
    assert len(streams) == 1 and set(streams[0].captures.tolist()) <= {2, 3}
    with pytest.raises(TouchbenchError, match="at least one frame"):
        spliced_streams(meta, np.array([10] * 4), np.array([0]), "gesture", "rest", (0, 2), np.random.default_rng(0))


def test_recorded_streams_put_segments_back_in_order_and_refuse_a_gap():
    meta = pd.DataFrame({"capture_id": ["r#2", "r#1", "q#1"], "subject": ["p", "p", "q"],
                         "gesture": ["tap", "idle", "idle"], "recording": ["r", "r", "q"],
                         "start_frame": [4, 0, 0]})
    streams = recorded_streams(meta, np.array([3, 4, 5]), np.array([0, 1, 2]))
    assert [(s.name, s.segments) for s in streams] == [("q", ((2, 0, 5),)), ("r", ((1, 0, 4), (0, 0, 3)))]
    assert all(s.source == "recorded" for s in streams)
    meta.loc[0, "start_frame"] = 5  # frame 4 of r is in no segment
    with pytest.raises(TouchbenchError, match="recording 'r'.*gap or an overlap"):
        recorded_streams(meta, np.array([3, 4, 5]), np.array([0, 1, 2]))


# ----------------------------------------------------------------- rules
CLASSES = np.array(["a", "b", "idle"], dtype=object)


def _started(rule):
    rule.start(CLASSES, "none", 10.0, SENSOR)
    return rule


def test_max_rule_gives_none_under_its_threshold():
    r = _started(MaxRule(threshold=0.6))
    assert r.decide(np.array([0.7, 0.2, 0.1])) == "a"
    assert r.decide(np.array([0.5, 0.3, 0.2])) == "none"


def test_majority_rule_by_hand():
    r = _started(MajorityRule(n=3, threshold=0.0))
    a, b = np.array([0.9, 0.1, 0.0]), np.array([0.1, 0.9, 0.0])
    # decisions of max: a, b, b, a, a -> last-3 windows: [a] a, [a b] tie -> most recent b,
    # [a b b] b, [b b a] b, [b a a] a
    assert [r.decide(p) for p in (a, b, b, a, a)] == ["a", "b", "b", "b", "a"]


def test_hmm_rule_forward_filter_by_hand():
    r = _started(HmmRule(switch=0.2, threshold=0.0))
    # step 1: prior 1/3 each, emissions (0.6, 0.3, 0.1) -> posterior (0.6, 0.3, 0.1): a
    assert r.decide(np.array([0.6, 0.3, 0.1])) == "a"
    # step 2: prior_j = 0.8 post_j + 0.1 (1 - post_j): (0.52, 0.31, 0.17); emissions (0.2, 0.7, 0.1)
    # -> unnormalised (0.104, 0.217, 0.017), sum 0.338: b
    assert r.decide(np.array([0.2, 0.7, 0.1])) == "b"
    np.testing.assert_allclose(r._post, np.array([0.104, 0.217, 0.017]) / 0.338)


def test_best_level_separates_idle_peaks_by_hand():
    # idle peaks 0.1, 0.2; gesture peaks 0.25, 0.6: any level in (0.2, 0.25] separates them all;
    # the first candidate that does is the midpoint 0.225
    peaks = np.array([0.1, 0.2, 0.25, 0.6])
    assert best_level(peaks, np.array([True, True, False, False])) == pytest.approx(0.225)
    assert peak_contact(np.array([[[20.0]], [[60.0]]]), (0, 100)) == pytest.approx(0.6)
    assert peak_contact(np.array([[[20.0]]]), (0, 100), higher_is_more=False) == pytest.approx(0.8)


def test_gate_decides_idle_without_the_classifier_and_needs_its_level():
    calls = []

    def proba(windows):
        calls.append(len(windows))
        return np.tile([0.2, 0.5, 0.3], (len(windows), 1))

    gate = GateRule(idle="idle", level=0.3, gate_s=0.2)
    rec = WindowRecognizer(proba, CLASSES, SENSOR, [0.2], hop_s=0.1, rule=gate)
    d1 = rec.push(np.array([[10.0]]))  # 1 frame: no decision (the window is 2 frames)
    d2 = rec.push(np.array([[10.0]]))  # peak 0.1 < 0.3: idle, no classifier call
    d3 = rec.push(np.array([[80.0]]))  # peak 0.8: the best non-idle class, b
    assert d1 is None and d2.label == "idle" and d3.label == "b" and calls == [1]
    # the decision says whether the classifier ran for it (a stream table's CPU note reads it)
    assert d2.classified is False and d3.classified is True
    auto = GateRule(idle="idle")
    with pytest.raises(TouchbenchError, match="fit the rule first"):
        WindowRecognizer(proba, CLASSES, SENSOR, [0.2], rule=auto)
    with pytest.raises(TouchbenchError, match="not one of the classes"):
        WindowRecognizer(proba, CLASSES[:2], SENSOR, [0.2], rule=GateRule(idle="idle", level=0.1))


def test_rules_are_declared_by_name_and_refuse_bad_values():
    assert isinstance(make_rule("majority"), MajorityRule)
    assert make_rule({"name": "hmm", "switch": 0.1}).describe() == {"name": "hmm", "switch": 0.1, "threshold": 0.5}
    with pytest.raises(TouchbenchError, match="decision rule 'max'"):
        make_rule({"name": "max", "n": 3})
    with pytest.raises(TouchbenchError, match="decision rule 'majority': n: Input should be greater than or equal to 1"):
        make_rule({"name": "majority", "n": 0})
    with pytest.raises(TouchbenchError, match="needs a name"):
        make_rule({"threshold": 0.5})


# ----------------------------------------------------------------- onset-aligned windows
def test_contact_run_bridges_short_gaps_by_hand():
    from touchbench.streams.onset import contact_run

    T, F = True, False
    assert contact_run([F, F, T, T, T], bridge=2) == 3  # a gap of 2 frames is not bridged
    assert contact_run([T, T, F, T, T], bridge=2) == 5  # a gap of 1 frame is: one touch since frame 0
    assert contact_run([T, F, F, T], bridge=2) == 1
    assert contact_run([T, T, F], bridge=5) == 0  # the newest frame is not in contact
    assert contact_run([], bridge=1) == 0


def test_onset_rule_classifies_the_window_from_the_onset():
    from touchbench.streams.onset import OnsetRule

    seen = []

    def proba(windows):
        seen.append([len(w) for w in windows])
        return np.tile([0.2, 0.5, 0.3], (len(windows), 1))

    # 10 Hz, windows 0.2 s (2 frames) and 0.4 s (4 frames), hop 0.1 s; contact from the 4th frame on
    rule = OnsetRule(idle="idle", level=0.3, gate_s=0.1, bridge_s=0.0)
    rec = WindowRecognizer(proba, CLASSES, SENSOR, [0.2, 0.4], hop_s=0.1, rule=rule)
    labels = [None if (d := rec.push(np.array([[v]]))) is None else d.label for v in (0, 0, 0, 80, 80, 80, 80, 80)]
    # frame 2: no contact in the newest 0.1 s -> idle (no classifier); frame 3 likewise;
    # frame 4: 1 frame of contact, under the shortest window (2) -> none; frame 5: 2 frames -> window [2];
    # frame 6: 3 -> [3]; frame 7: 4 frames, the whole kept window in contact -> the sliding windows [2, 4]
    assert labels == [None, "idle", "idle", "none", "b", "b", "b", "b"]
    assert seen[:3] == [[2], [3], [2, 4]]


def test_gate_level_auto_is_fitted_on_stretches_of_gate_s_by_hand():
    # 10 Hz, gate_s 0.2 s: stretches of 2 frames. Idle capture 1, 1, 3, 3 -> peaks 0.01, 0.03; the gesture
    # capture 0, 50, 0, 0 -> 0.5, 0.0. Candidates 0.005, 0.02, 0.265, just above 0.5; balanced accuracy
    # 0.25, 0.5, 0.75, 0.5: the level is 0.265 (a capture's own peak, 0.5, would have missed the gesture's
    # second stretch)
    idle = np.array([1, 1, 3, 3], dtype=float).reshape(4, 1, 1)
    touch = np.array([0, 50, 0, 0], dtype=float).reshape(4, 1, 1)
    rule = GateRule(idle="idle", gate_s=0.2).fit([idle, touch], ["idle", "tap"], SENSOR)
    assert rule.fitted_level == pytest.approx(0.265)
    with pytest.raises(TouchbenchError, match="needs training captures of 'idle'"):
        GateRule(idle="idle").fit([touch], ["tap"], SENSOR)


def test_a_batched_replay_decides_what_stepping_frame_by_frame_decides():
    from touchbench.streams.onset import OnsetRule

    def proba(windows):  # a deterministic function of each window alone
        m = np.array([[w.mean(), w.max(), len(w)] for w in windows], dtype=np.float64)
        e = np.exp(m / 40.0 - (m / 40.0).max(axis=1, keepdims=True))
        return e / e.sum(axis=1, keepdims=True)

    rng = np.random.default_rng(0)
    frames = np.concatenate([np.full((7, 1, 1), 2.0), rng.uniform(0, 100, (30, 1, 1)), np.full((9, 1, 1), 1.0),
                             rng.uniform(40, 100, (25, 1, 1))])

    def rules():
        return [MaxRule(0.4), MajorityRule(3), HmmRule(0.1), GateRule("idle", level=0.3, gate_s=0.2),
                OnsetRule("idle", level=0.3, gate_s=0.1, bridge_s=0.2)]

    stepped = WindowRecognizer(proba, CLASSES, SENSOR, [0.3, 0.6], hop_s=0.2, rule=rules())
    by_frame = [out for f in frames if (out := stepped.step(f)) is not None]
    batched = WindowRecognizer(proba, CLASSES, SENSOR, [0.3, 0.6], hop_s=0.2, rule=rules()).replay(frames, batch=4)
    for k in range(5):
        assert [(d.frame, d.label, d.classified) for d in batched[k]] == \
            [(o[k].frame, o[k].label, o[k].classified) for o in by_frame]
    assert all(d.classified for d in batched[0])  # max never skips the classifier
    assert len(batched[0]) == (len(frames) - 3) // 2 + 1  # every 2 frames from the first 3-frame window
