"""Scores of a live recognition stream, on sequences worked by hand.

Notation: one character per frame; ``_`` is the idle class, ``a``, ``b`` gesture classes, ``u``
the undecided label. Frame rate 10 Hz unless said, so one frame is 0.1 s. The expected numbers in
the comments were worked out on paper from Ward, Lukowicz & Gellersen (2011) and the module's
stated reading of them, not from the code's output.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from touchbench.core.errors import DataError
from touchbench.scoring.streams import SEGMENT_KINDS, score_stream

RATE = 10.0
ERRORS = [k for k in SEGMENT_KINDS if k not in ("correct", "correct_idle")]


def score(truth: str, decided: str, **kw):
    return score_stream(list(truth), list(decided), "_", kw.pop("rate", RATE), **kw)


def frames(s) -> dict[str, int]:
    """The non-zero frame totals per segment kind."""
    return {k: v for k, v in s.segments.frames.items() if v}


def nonzero(d: dict[str, int]) -> dict[str, int]:
    return {k: v for k, v in d.items() if v}


# ---- Ward's segment and event kinds, one small case each -------------------------------------

def test_insertion():
    s = score("______", "__aa__")
    # frames 2-3: decision a over idle truth, neither neighbour a correct a-segment: insertion
    assert frames(s) == {"correct_idle": 4, "insertion": 2}
    assert s.segments.counts["insertion"] == 1 and s.segments.counts["correct_idle"] == 2
    assert nonzero(s.events.returned) == {"inserted": 1}
    assert nonzero(s.events.truth) == {}


def test_deletion():
    s = score("__aa__", "______")
    assert frames(s) == {"correct_idle": 4, "deletion": 2}
    assert nonzero(s.events.truth) == {"deleted": 1}
    assert nonzero(s.events.returned) == {}


def test_merge():
    s = score("_aa_aa_", "_aaaaa_")
    # frame 3: decision a over idle, correct a on both sides: merge; both true events merged by
    # the one return, which is merging
    assert frames(s) == {"correct_idle": 2, "correct": 4, "merge": 1}
    assert nonzero(s.events.truth) == {"merged": 2}
    assert nonzero(s.events.returned) == {"merging": 1}


def test_fragmentation():
    s = score("_aaaaa_", "_aa_aa_")
    # frame 3: true a decided idle between two correct a stretches: fragmentation; one event
    # fragmented, two returns fragmenting
    assert frames(s) == {"correct_idle": 2, "correct": 4, "fragmentation": 1}
    assert nonzero(s.events.truth) == {"fragmented": 1}
    assert nonzero(s.events.returned) == {"fragmenting": 2}


def test_overfill_at_start_and_end():
    s = score("__aaa__", "_aaaaa_")
    # frame 1: a decided before the event (next segment correct a): overfill at the start (Oα);
    # frame 5: after it (previous one correct a): overfill at the end (Oω); the event is correct
    assert frames(s) == {"correct_idle": 2, "correct": 3, "overfill_start": 1, "overfill_end": 1}
    assert nonzero(s.events.truth) == {"correct": 1}
    assert nonzero(s.events.returned) == {"correct": 1}
    assert s.false_activations == 0  # starts in idle, but runs into its event: not a false activation


def test_underfill_at_start_and_end():
    s = score("_aaaaa_", "__aaa__")
    assert frames(s) == {"correct_idle": 2, "correct": 3, "underfill_start": 1, "underfill_end": 1}
    assert nonzero(s.events.truth) == {"correct": 1}
    assert s.timing.median_s == pytest.approx(0.1)  # onset frame 1, first a decision frame 2


def test_substitution():
    s = score("_aaa_", "_bbb_")
    # frames 1-3: a gesture decided as another gesture: substitution (one segment, 3 frames);
    # the a event matches no a return (deleted), the b return matches no b event (inserted);
    # it starts inside a gesture, not in idle: no false activation
    assert frames(s) == {"correct_idle": 2, "substitution": 3}
    assert s.segments.counts["substitution"] == 1
    assert nonzero(s.events.truth) == {"deleted": 1}
    assert nonzero(s.events.returned) == {"inserted": 1}
    assert s.false_activations == 0


def test_fragmented_and_merged():
    s = score("_aaa_aa_", "_a_aaaa_")
    # true events A1 = frames 1-3, A2 = 5-6; returns R1 = frame 1, R2 = frames 3-6.
    # A1 is matched by R1 and R2 (fragmented) and R2 also matches A2 (merged): FM.
    # A2 is matched by R2 only, which is merging: M.
    # R1 matches the fragmented A1: F'. R2 matches two events and the fragmented A1: FM'.
    # frames: 2 fragmentation (a between correct a's), 4 merge (idle between correct a's)
    assert nonzero(s.events.truth) == {"fragmented_merged": 1, "merged": 1}
    assert nonzero(s.events.returned) == {"fragmenting": 1, "fragmenting_merging": 1}
    assert frames(s) == {"correct_idle": 2, "correct": 4, "fragmentation": 1, "merge": 1}


def test_decision_straddling_two_events_of_different_classes():
    s = score("_aaa_bbb_", "__aaaaa__")
    # frame 1: a missed before the correct a: underfill at the start; 2-3 correct;
    # frame 4: a over idle after correct a, before b-decided-a (not correct a): overfill at the end;
    # 5-6: b decided a: substitution; 7: b decided idle, no correct b beside it: deletion.
    assert frames(s) == {"correct_idle": 2, "underfill_start": 1, "correct": 2, "overfill_end": 1,
                         "substitution": 2, "deletion": 1}
    # events match by class: the a event is matched by the return alone (correct), the b event by
    # nothing (deleted); the return matches only the a event: correct
    assert nonzero(s.events.truth) == {"correct": 1, "deleted": 1}
    assert nonzero(s.events.returned) == {"correct": 1}
    assert s.frame.accuracy == pytest.approx(4 / 9)  # frames 0, 2, 3, 8


def test_decision_straddling_two_events_of_the_same_class():
    s = score("_aaa_aaa_", "__aaaaa__")
    # 1 underfill start, 2-3 correct, 4 merge, 5-6 correct, 7 underfill end
    assert frames(s) == {"correct_idle": 2, "underfill_start": 1, "correct": 4, "merge": 1,
                         "underfill_end": 1}
    assert nonzero(s.events.truth) == {"merged": 2}
    assert nonzero(s.events.returned) == {"merging": 1}


# ---- frame scores ------------------------------------------------------------------------------

def test_frame_scores_beside_the_idle_baseline():
    s = score("__aab", "_aaa_")
    # frames right: 0, 2, 3 -> 3/5; recalls: idle 1/2, a 2/2, b 0/1 -> balanced 1.5/3
    # idle everywhere: right on frames 0, 1 -> 2/5; recalls 1, 0, 0 -> 1/3
    # gesture frames 2, 3, 4: right on 2 -> 2/3; idle frames 0, 1: idle decided on 0 -> 1/2
    f = s.frame
    assert f.accuracy == pytest.approx(0.6)
    assert f.balanced_accuracy == pytest.approx(0.5)
    assert f.idle_baseline_accuracy == pytest.approx(0.4)
    assert f.idle_baseline_balanced_accuracy == pytest.approx(1 / 3)
    assert f.gesture_recall == pytest.approx(2 / 3)
    assert f.idle_recall == pytest.approx(0.5)


def test_undecided_frames_count_as_idle():
    s = score("__aaa", "uuuaa", undecided="u")
    # frames 0, 1: undecided over idle -> right; 2: a, undecided -> underfill at the start
    assert s.frame.accuracy == pytest.approx(4 / 5)
    assert frames(s) == {"correct_idle": 2, "underfill_start": 1, "correct": 2}
    assert s.false_activations == 0


# ---- edges of the stream, degenerate streams ---------------------------------------------------

def test_gestures_at_the_first_and_last_frame():
    s = score("aa___bb", "aa____b", times=(0.0, 0.1, 0.3))
    # A = frames 0-1 decided at once (0 s); B = frames 5-6 first decided at frame 6 (0.1 s);
    # frame 5: b missed before the correct b: underfill at the start (the stream's end does not
    # make it a deletion)
    assert frames(s) == {"correct": 3, "correct_idle": 3, "underfill_start": 1}
    assert nonzero(s.events.truth) == {"correct": 2}
    t = s.timing
    assert (t.events, t.decided, t.never) == (2, 2, 0)
    assert t.median_s == pytest.approx(0.05)
    assert t.p90_s == pytest.approx(0.09)  # 0 + 0.9 * (0.1 - 0)
    # at 0 s: A frame 0 a (right), B frame 5 idle (wrong); at 0.1 s: frames 1 and 6, both right;
    # at 0.3 s both events are over (last frames 1 and 6, both right)
    assert t.accuracy_at == pytest.approx({0.0: 0.5, 0.1: 1.0, 0.3: 1.0})
    assert t.ended_before == {0.0: 0, 0.1: 0, 0.3: 2}


def test_all_idle_stream():
    s = score("____", "____")
    d = s.to_dict()
    assert d["frame_accuracy"] == 1.0 and d["frame_balanced_accuracy"] == 1.0
    assert d["frame_idle_baseline_accuracy"] == 1.0
    assert math.isnan(d["frame_gesture_recall"]) and d["frame_idle_recall"] == 1.0
    assert d["event_total"] == 0 and d["return_total"] == 0
    assert d["decision_events"] == 0 and d["decision_never"] == 0
    assert math.isnan(d["time_to_decision_median_s"]) and math.isnan(d["accuracy_at_1s"])
    assert d["false_activations"] == 0 and d["false_activations_per_idle_minute"] == 0.0
    assert d["segment_correct_idle_frames"] == 4 and d["seconds"] == pytest.approx(0.4)


def test_empty_stream():
    d = score_stream([], [], "_", RATE).to_dict()
    assert d["frames"] == 0 and d["seconds"] == 0.0
    for key in ("frame_accuracy", "frame_balanced_accuracy", "frame_idle_baseline_accuracy",
                "time_to_decision_median_s", "accuracy_at_0.3s", "false_activations_per_idle_minute",
                "decision_fraction_decided"):
        assert math.isnan(d[key]), key
    counts = [k for k in d if k.endswith(("_count", "_frames")) or k.startswith(("event_", "return_"))]
    assert counts and all(d[k] == 0 for k in counts)


def test_flat_dict_has_only_numbers():
    d = score("_aaa_bb_", "_abb_b__").to_dict()
    assert all(type(v) in (int, float) for v in d.values())


# ---- time to decision, accuracy at t, false activations ----------------------------------------

def test_time_to_decision_and_accuracy_at_t():
    # E1: a on frames 5-29, first decided a at frame 9 (0.4 s); E2: b on 35-44, never decided;
    # E3: a on 50-57, decided a from frame 51 (0.1 s)
    truth = "_" * 5 + "a" * 25 + "_" * 5 + "b" * 10 + "_" * 5 + "a" * 8 + "_" * 2
    decided = "_" * 9 + "a" * 23 + "_" * 19 + "a" * 7 + "_" * 2
    assert len(truth) == len(decided) == 60
    t = score(truth, decided).timing
    assert (t.events, t.decided, t.never) == (3, 2, 1)
    assert t.fraction_decided == pytest.approx(2 / 3)
    assert t.median_s == pytest.approx(0.25)  # decided ones only: 0.1 and 0.4
    assert t.p90_s == pytest.approx(0.37)  # 0.1 + 0.9 * 0.3
    # 0.3 s: frames 8 (idle), 38 (idle), 53 (a) -> 1/3
    # 1 s: frames 15 (a), 45 -> E2 over, its last frame 44 (idle), 60 -> E3 over, frame 57 (a) -> 2/3
    # 2 s: frames 25 (a), E2 last frame (idle), E3 last frame (a) -> 2/3
    assert t.accuracy_at == pytest.approx({0.3: 1 / 3, 1.0: 2 / 3, 2.0: 2 / 3})
    assert t.ended_before == {0.3: 0, 1.0: 2, 2.0: 2}


def test_accuracy_at_t_on_a_frame_boundary():
    # 100 Hz: onset at frame 1, first a decision at frame 30 = onset + 29 frames = onset + 0.29 s
    # (0.29 * 100 is 28.999999999999996 in floating point: still frame 30); 0.28 s is frame 29
    s = score("_" + "a" * 50, "_" * 30 + "a" * 21, rate=100.0, times=(0.28, 0.29))
    assert s.timing.accuracy_at == {0.28: 0.0, 0.29: 1.0}
    assert s.timing.median_s == pytest.approx(0.29)


def test_false_activations_per_idle_minute():
    decided = ["_"] * 1200
    for a, b, c in ((100, 105, "a"), (500, 503, "b"), (900, 910, "a")):
        decided[a:b] = [c] * (b - a)
    s = score_stream(["_"] * 1200, decided, "_", RATE)
    # 1200 idle frames at 10 Hz = 2 minutes, three returns over idle -> 1.5 per minute
    assert s.false_activations == 3
    assert s.false_activations_per_idle_minute == pytest.approx(1.5)


def test_early_onset_is_not_a_false_activation():
    truth = ["_"] * 600 + ["a"] * 100 + ["_"] * 500
    decided = ["_"] * 590 + ["a"] * 110 + ["_"] * 100 + ["b"] * 6 + ["_"] * 394
    s = score_stream(truth, decided, "_", RATE)
    # the a return starts 10 frames early but matches the a event; the b return matches nothing:
    # one false activation over 1100 idle frames = 110 s = 11/6 minutes
    assert s.false_activations == 1
    assert s.false_activations_per_idle_minute == pytest.approx(6 / 11)
    assert s.segments.frames["overfill_start"] == 10


# ---- bad input ---------------------------------------------------------------------------------

@pytest.mark.parametrize("kw, match", [
    (dict(truth=list("__"), decided=list("___"), frame_rate=RATE), "one decision per frame"),
    (dict(truth=list("__"), decided=list("__"), frame_rate=0), "positive frame rate"),
    (dict(truth=list("__"), decided=list("__"), frame_rate=float("nan")), "positive frame rate"),
    (dict(truth=list("__"), decided=list("__"), frame_rate=RATE, times=(-1,)), "not negative"),
    (dict(truth=list("_u"), decided=list("__"), frame_rate=RATE, undecided="u"), "undecided label 'u'"),
])
def test_bad_input_is_one_clear_error(kw, match):
    with pytest.raises(DataError, match=match):
        score_stream(idle="_", **kw)


# ---- properties --------------------------------------------------------------------------------

streams = st.integers(0, 40).flatmap(lambda n: st.tuples(
    st.text("_ab", min_size=n, max_size=n), st.text("_ab", min_size=n, max_size=n)))
binary = st.integers(0, 40).flatmap(lambda n: st.tuples(
    st.text("_a", min_size=n, max_size=n), st.text("_a", min_size=n, max_size=n)))


def n_events(labels: str) -> int:
    """Maximal runs of one non-idle label, counted by hand."""
    return sum(1 for i, c in enumerate(labels) if c != "_" and (i == 0 or labels[i - 1] != c))


@settings(max_examples=150, deadline=None)
@given(streams)
def test_kinds_partition_frames_and_events(pair):
    truth, decided = pair
    s = score(truth, decided)
    assert sum(s.segments.frames.values()) == len(truth)
    assert sum(s.events.truth.values()) == n_events(truth)
    assert sum(s.events.returned.values()) == n_events(decided)
    assert s.events.truth["correct"] == s.events.returned["correct"]
    fp = sum(t == "_" and d != "_" for t, d in zip(truth, decided))
    fn = sum(t != "_" and d == "_" for t, d in zip(truth, decided))
    sub = sum(t != "_" and d != "_" and t != d for t, d in zip(truth, decided))
    seg = s.segments.frames
    assert seg["insertion"] + seg["merge"] + seg["overfill_start"] + seg["overfill_end"] == fp
    assert seg["deletion"] + seg["fragmentation"] + seg["underfill_start"] + seg["underfill_end"] == fn
    assert seg["substitution"] == sub
    if truth:
        assert (seg["correct"] + seg["correct_idle"]) / len(truth) == pytest.approx(s.frame.accuracy)


@settings(max_examples=150, deadline=None)
@given(streams)
def test_swapping_truth_and_decisions_swaps_the_error_kinds(pair):
    truth, decided = pair
    s, w = score(truth, decided), score(decided, truth)
    for a, b in (("insertion", "deletion"), ("merge", "fragmentation"),
                 ("overfill_start", "underfill_start"), ("overfill_end", "underfill_end")):
        assert s.segments.frames[a] == w.segments.frames[b]
        assert s.segments.counts[b] == w.segments.counts[a]
    for a, b in (("deleted", "inserted"), ("fragmented", "merging"), ("merged", "fragmenting"),
                 ("fragmented_merged", "fragmenting_merging"), ("correct", "correct")):
        assert s.events.truth[a] == w.events.returned[b]


@settings(max_examples=150, deadline=None)
@given(binary)
def test_two_class_segments_agree_with_events(pair):
    # Ward's two-class case: a deletion segment is a whole event no return touches, an insertion
    # segment a whole return that touches no event; an event is fragmented exactly when it holds
    # a fragmentation segment, a return merging exactly when it holds a merge segment
    s = score(*pair)
    assert s.segments.counts["deletion"] == s.events.truth["deleted"]
    assert s.segments.counts["insertion"] == s.events.returned["inserted"]
    assert (s.segments.counts["fragmentation"] > 0) == (
        s.events.truth["fragmented"] + s.events.truth["fragmented_merged"] > 0)
    assert (s.segments.counts["merge"] > 0) == (
        s.events.returned["merging"] + s.events.returned["fragmenting_merging"] > 0)


@settings(max_examples=100, deadline=None)
@given(st.text("_ab", max_size=40))
def test_perfect_decisions(truth):
    s = score(truth, truth)
    if truth:
        assert s.frame.accuracy == 1.0 and s.frame.balanced_accuracy == 1.0
    assert all(s.segments.frames[k] == 0 for k in ERRORS)
    assert s.events.truth["correct"] == n_events(truth) == s.events.returned["correct"]
    assert s.timing.never == 0 and s.false_activations == 0
    if n_events(truth):
        assert s.timing.median_s == 0.0 and s.timing.p90_s == 0.0
        assert all(v == 1.0 for v in s.timing.accuracy_at.values())

