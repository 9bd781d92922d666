"""The stream table and the stream-trade figure do not mislead: rules that cannot differ for a method
without graded probabilities are shown once, the default rule is marked, CPU mostly made of skipped
decisions is said so, a hop or window longer than the gestures is said so, and the figure keeps each
rule's colour and marker apart with its legend outside the panels. Results are built by hand."""

from __future__ import annotations

import io
import json
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from helpers import fake_loso
from rich.console import Console

from touchbench.engine.live import graded_probabilities
from touchbench.scoring.streams import score_stream
from touchbench.reports.figures.stream_trade import stream_trade_figure
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import print_terminal, to_csv, to_json, to_markdown
from touchbench.reports.results import load_results
from touchbench.reports.stream_table import default_rule_index
from touchbench.reports.testing import FakeMethod, write_fake_run
from touchbench.streams.recognizer import Decision

RATE = 10.0
CAPS, FOLDS, _ = fake_loso(["s1", "s2"])
# stream of s1: idle 10, press 6 (0.6 s), idle 10, tap 4 (0.4 s), idle 10; stream of s2: idle 10, press 30
# (3.0 s), idle 10. Gesture events 0.6, 0.4 and 3.0 s: median 0.6 s.
TRUTH = {"subject=s1": ["idle"] * 10 + ["press"] * 6 + ["idle"] * 10 + ["tap"] * 4 + ["idle"] * 10,
         "subject=s2": ["idle"] * 10 + ["press"] * 30 + ["idle"] * 10}
MAX, MAX4 = {"name": "max", "threshold": 0.5}, {"name": "max", "threshold": 0.4}
HMM = {"name": "hmm", "switch": 0.01, "threshold": 0.5}
MAJ = {"name": "majority", "n": 3, "threshold": 0.5}
GATE = {"name": "gate", "idle": "idle", "level": "auto", "gate_s": 0.25, "threshold": 0.0, "fitted_level": 0.3}


def _runs(labels):
    return [[k, lab] for k, lab in enumerate(labels) if k == 0 or labels[k - 1] != lab]


def _result(truth, decided, p50=0.1, p99=0.2, **extra):
    return {"scores": score_stream(truth, decided, "idle", RATE).to_dict(), "decisions": _runs(decided),
            "n_decisions": 10, "cpu_s": 0.01, "wall_s": 0.01, "decision_cpu_ms_p50": p50,
            "decision_cpu_ms_p99": p99, **extra}


def _payload(fold, rules, deciders, *, hop_s=0.5, windows_s=(1.0, 2.0), **keys):
    """One task's payload: ``deciders[k](truth)`` gives rule k's decision per frame (a dict of the
    result's extra keys beside it, or not)."""
    truth = TRUTH[fold]
    results = []
    for decide in deciders:
        out = decide(truth)
        decided, extra = out if isinstance(out, tuple) else (out, {})
        results.append(_result(truth, decided, **extra))
    return {"rules": rules, "idle": "idle", "frame_rate": RATE, "windows_s": list(windows_s), "hop_s": hop_s,
            "train_on": "windows", **keys,
            "streams": [{"name": fold, "subject": fold[-2:], "session": "", "source": "spliced",
                         "frames": len(truth), "truth": _runs(truth), "results": results}]}


def right(truth):
    return list(truth)


def late(truth):  # every gesture decided two frames late
    return ["idle", "idle"] + list(truth[:-2])


def idle(truth):
    return ["idle"] * len(truth)


def _lb(tmp_path, methods):
    write_fake_run(tmp_path / "run", CAPS, FOLDS, methods, scheme={"name": "stream"}, frame_rate=RATE)
    [lb] = build_leaderboards(load_results([tmp_path / "run"]))
    return lb


def _method(name, rules, deciders, **keys):
    return FakeMethod("captures", name, live={f: _payload(f, rules, deciders, **keys) for f in FOLDS})


def test_rules_that_cannot_differ_without_graded_probabilities_are_shown_once_with_a_note(tmp_path):
    rules = [MAX, MAX4, HMM, MAJ]
    lb = _lb(tmp_path, [_method("minirocket", rules, [right, right, right, late], probabilities=False),
                        _method("forest", rules, [right, right, right, late], probabilities=True)])
    mini = lb.live[lb.live["method"] == "minirocket"]
    # hmm shown for the three that decided alike (it is the default rule), majority on its own
    assert sorted(mini["rule"]) == ["hmm switch=0.01", "majority n=3"]
    assert mini.set_index("rule").loc["hmm switch=0.01", "same_as"] == ["max", "max threshold=0.4"]
    # a method with graded probabilities keeps every rule, even ones that decided alike
    assert len(lb.live[lb.live["method"] == "forest"]) == 4
    note = next(n for n in lb.notes if "graded probabilities" in n)
    assert note.startswith("minirocket ") and "max, max threshold=0.4 as hmm switch=0.01" in note
    assert "forest" not in note


def test_older_results_without_the_new_keys_read_as_before(tmp_path):
    lb = _lb(tmp_path, [_method("minirocket", [MAX, MAX4], [right, right])])  # no probabilities key
    assert sorted(lb.live["rule"]) == ["max", "max threshold=0.4"]
    assert lb.live["classified_fraction"].isna().all()
    # the default (hmm switch 0.01) is not among the rules: said so
    assert any("default rule (hmm switch=0.01)" in n and "not among the rules" in n for n in lb.notes)
    assert not lb.live["default"].any()


def test_the_default_rule_is_marked_in_every_output(tmp_path):
    lb = _lb(tmp_path, [_method("forest", [MAX, MAX4, MAJ], [right, late, idle], default_rule=MAX4)])
    assert lb.live.set_index("rule")["default"].to_dict() == {"max": False, "max threshold=0.4": True,
                                                             "majority n=3": False}
    md = to_markdown([lb])
    assert "| forest | max threshold=0.4 (default) |" in md and "| forest | max |" in md
    assert "(default): the rule touchbench stream decides with" in md
    csv = pd.read_csv(io.StringIO(to_csv([lb])))
    assert csv.set_index("rule")["default"].to_dict() == {"max": False, "max threshold=0.4": True,
                                                         "majority n=3": False}
    live = json.loads(to_json([lb]))["tables"][0]["live"]
    assert [r["rule"] for r in live if r["default"]] == ["max threshold=0.4"]
    console = Console(width=250, record=True, file=io.StringIO())
    print_terminal([lb], console)
    assert "max threshold=0.4 (default)" in console.export_text()


def test_the_default_gate_matches_the_evaluations_gate_by_its_fitted_level():
    payload = {"idle": "idle", "rules": [MAX, GATE], "default_rule": {"name": "gate", "idle": "idle", "level": 0.3}}
    assert default_rule_index(payload) == 1
    # without default_rule: the DEFAULT_RULE (hmm, switch 0.01), its threshold the default 0.5
    assert default_rule_index({"idle": "idle", "rules": [MAX, {"name": "hmm", "switch": 0.01}]}) == 1
    assert default_rule_index({"idle": "idle", "rules": [MAX, {"name": "hmm", "switch": 0.05}]}) is None


def test_cpu_mostly_of_skipped_decisions_is_marked_and_noted(tmp_path):
    gated = (lambda t: (right(t), {"p50": 0.02, "p99": 3.5, "classified_fraction": 0.3,
                                   "live_classified_fraction": 0.25}))
    full = (lambda t: (right(t), {"p50": 2.0, "p99": 3.0, "classified_fraction": 1.0,
                                  "live_classified_fraction": 1.0}))
    lb = _lb(tmp_path, [_method("forest", [MAX, GATE], [full, gated])])
    md = to_markdown([lb])
    gate_row = next(line for line in md.splitlines() if line.startswith("| forest | gate"))
    max_row = next(line for line in md.splitlines() if line.startswith("| forest | max"))
    assert "| 0.02 ‡ |" in gate_row and "‡" not in max_row
    note = next(n for n in lb.notes if n.startswith("CPU ms of forest · gate"))
    # the timed decisions' share (25 %), the median and the 99th percentile over the two streams
    assert "25.0 % of the timed decisions ran the classifier" in note
    assert "median 0.02 ms, 99th percentile 3.50 ms" in note


def test_a_hop_or_window_longer_than_the_gestures_is_noted(tmp_path):
    lb = _lb(tmp_path, [_method("forest", [MAX], [right], hop_s=0.5, windows_s=(1.0, 2.0))])
    notes = [n for n in lb.notes if "median gesture event" in n]
    # events 0.6, 0.4 and 3.0 s: median 0.6 s; the hop 0.5 s is not longer, the 1 s window is
    assert len(notes) == 1 and notes[0].startswith("the shortest window (1 s)")
    assert "(0.60 s; 2 of 3 events are shorter than 1 s)" in notes[0]
    lb = _lb(tmp_path / "b", [_method("forest", [MAX], [right], hop_s=0.8, windows_s=(0.5,))])
    notes = [n for n in lb.notes if "median gesture event" in n]
    assert len(notes) == 1 and "the hop (0.8 s)" in notes[0] and "2 of 3 events are shorter than 0.8 s" in notes[0]


def _decision(classified, *probabilities):
    return Decision(frame=1, t=0.1, label="a", probability=max(probabilities or (1.0,)), best="a", window_s=1.0,
                    latency_ms=0.0, windows=[{"window_s": 1.0, "label": "a", "probability": p} for p in probabilities],
                    classified=classified)


def test_graded_probabilities_are_read_from_the_windows_classified():
    one_hot = SimpleNamespace(decisions=[_decision(True, 1.0, 1.0), _decision(False, 1.0)])
    graded = SimpleNamespace(decisions=[_decision(True, 1.0), _decision(True, 0.7)])
    gated = SimpleNamespace(decisions=[_decision(False, 1.0)])
    assert graded_probabilities([one_hot]) is False
    assert graded_probabilities([one_hot, graded]) is True
    assert graded_probabilities([gated]) is None


@pytest.mark.parametrize("size", ["text", "column"])
def test_stream_trade_keeps_rules_apart_and_its_legend_outside_the_panels(tmp_path, size):
    pytest.importorskip("matplotlib")
    rules = [MAX, MAX4, HMM, MAJ, GATE, {"name": "majority", "n": 5, "threshold": 0.5},
             {"name": "hmm", "switch": 0.05, "threshold": 0.5}, {"name": "max", "threshold": 0.7}]
    deciders = [right, late, right, late, idle, right, late, idle]
    methods = [_method(m, rules, deciders, probabilities=True) for m in ("forest", "svm", "knn", "lda")]
    lb = _lb(tmp_path, methods)
    assert len(lb.live) == 32
    fig = stream_trade_figure(SimpleNamespace(live=lb.live, title="fake — spliced streams"), size)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    axes = fig.get_axes()
    assert len(axes) == 8  # one row of two panels per method
    for ax in axes:
        pairs = [(tuple(np.round(line.get_color() if not isinstance(line.get_color(), str) else (0, 0, 0, 0), 6)),
                  line.get_marker()) for line in ax.get_lines() if line.get_marker() not in ("None", None, "")]
        assert len(pairs) == 8 and len(set(pairs)) == 8
    (legend,) = fig.legends
    box = legend.get_window_extent(renderer)
    assert len(legend.get_texts()) == 8
    for ax in axes:
        a = ax.get_window_extent(renderer)
        assert box.y1 <= a.y0 or box.y0 >= a.y1 or box.x1 <= a.x0 or box.x0 >= a.x1
    # the two panels' axis labels apart
    a, b = (ax.xaxis.label.get_window_extent(renderer) for ax in axes[-2:])
    assert a.x1 <= b.x0
    assert "max (default)" not in [t.get_text() for t in legend.get_texts()]
    assert "hmm switch=0.01 (default)" in [t.get_text() for t in legend.get_texts()]
    fig.savefig(tmp_path / f"trade-{size}.png", dpi=100)


STREAM_SCHEME = {"name": "stream", "choose_rule": True, "hop_s": 0.1, "windows_s": [1.0, 2.0], "train_on": "streams"}


def test_stream_figures_are_named_by_the_results_folder(tmp_path):
    """File names come from the results folders (one plot call over two of one name stays unique),
    never from the scheme's parameters."""
    pytest.importorskip("matplotlib")
    from click.testing import CliRunner

    from touchbench.cli.main import cli

    for where, data_hash in (("a", "d"), ("b", "e")):
        write_fake_run(tmp_path / where / "stream-skin", CAPS, FOLDS, [_method("forest", [MAX, MAJ], [right, late])],
                       scheme=STREAM_SCHEME, frame_rate=RATE, dataset=f"skin-{where}", dataset_hash=data_hash * 64)
    r = CliRunner().invoke(cli, ["plot", str(tmp_path / "a" / "stream-skin"), str(tmp_path / "b" / "stream-skin"),
                                 "--kind", "stream-trade", "--format", "png", "--out", str(tmp_path / "pl")])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "pl").iterdir()) == ["stream-skin-2-stream-trade.png",
                                                                   "stream-skin-stream-trade.png"]


def test_results_of_two_machines_without_latencies_name_no_machine_none(tmp_path):
    other = {"platform": "Linux-other-x86_64", "machine": "x86_64", "processor": "other", "python": "3.11",
             "cpu_count": 4, "cpu_model": "Other CPU"}
    for name, platform in (("one", None), ("two", other)):
        write_fake_run(tmp_path / name, CAPS, FOLDS,
                       [FakeMethod("captures", name, latency_ms=float("nan"),
                                   live={f: _payload(f, [MAX], [right]) for f in FOLDS})],
                       scheme={"name": "stream"}, frame_rate=RATE, platform=platform, run_id=name)
    [lb] = build_leaderboards(load_results([tmp_path / "one", tmp_path / "two"]))
    [note] = [n for n in lb.notes if n.startswith("results from several machines")]
    assert "None" not in note and "No method of this table has a latency per capture" in note
