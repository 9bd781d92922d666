"""A stream evaluation runs through the engine, and its decisions are `touchbench stream`'s."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.datasets.model import TouchDataset
from touchbench.engine.planning import prepare_evaluation
from touchbench.protocols.loading import load_protocol
from touchbench.streams.replay import LiveSpec
from touchbench.streams.timeline import decisions_per_frame, stream_frames

PROTOCOL = """\
name: live-sample
dataset: haart-sample
target: gesture
scheme:
  name: stream
  base: loso
  idle: notouch
  gap_s: [0.5, 1.5]
  per_stream: 3
  windows_s: [0.5, 1.0]
  hop_s: 0.2
  rules: [{name: max, threshold: 0.4}, {name: majority, n: 3, threshold: 0.4}, {name: hmm, switch: 0.01}]
methods: [touch-et-fast]
seed: 3
"""


def _expand(runs, n):
    """Run-length decisions back to one label per frame."""
    out = np.empty(n, dtype=object)
    for k, (a, label) in enumerate(runs):
        b = runs[k + 1][0] if k + 1 < len(runs) else n
        out[a:b] = label
    return out


@pytest.fixture(scope="module")
def live_run(tmp_path_factory):
    root = tmp_path_factory.mktemp("live")
    (root / "p.yaml").write_text(PROTOCOL)
    res = CliRunner().invoke(cli, ["run", str(root / "p.yaml"), "--out", str(root / "res"), "--jobs", "1",
                                   "--no-progress"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return root, pd.read_parquet(root / "res" / "scores.parquet")


def test_the_stream_evaluation_scores_every_stream_and_rule(live_run):
    _, scores = live_run
    assert (scores["status"] == "ok").all() and sorted(scores["fold"]) == ["subject=s01", "subject=s04"]
    for _, row in scores.iterrows():
        live = json.loads(row["live"])
        assert [r["name"] for r in live["rules"]] == ["max", "majority", "hmm"]
        (stream,) = live["streams"]
        # a forest's probabilities are graded, and no rule here skips the classifier
        assert live["probabilities"] is True
        assert stream["source"] == "spliced" and row["fold"].endswith(stream["subject"])
        # three gestures of 8 s (432 frames at 54 Hz) and four idle stretches of 27..81 frames
        assert 3 * 432 + 4 * 27 <= stream["frames"] <= 3 * 432 + 4 * 81
        for r in stream["results"]:
            s = r["scores"]
            assert 0.0 <= s["frame_accuracy"] <= 1.0 and "frame_idle_baseline_accuracy" in s
            # every hop of 0.2 s (11 frames) from the first full 0.5 s window (27 frames)
            assert r["n_decisions"] == (stream["frames"] - 27) // 11 + 1
            assert r["classified_fraction"] == 1.0 and r["live_classified_fraction"] == 1.0


def test_the_evaluation_decides_what_touchbench_stream_prints(live_run, tmp_path):
    root, scores = live_run
    proto = load_protocol(root / "p.yaml")
    prepared = prepare_evaluation(proto)
    fold = next(f for f in prepared.folds[0] if f.name == "subject=s04")
    (stream,) = fold.extra(LiveSpec).streams
    ds = prepared.dataset
    y = ds.meta["gesture"].astype(str).to_numpy()
    frames, truth = stream_frames(ds.captures, y, stream, "notouch", 0)
    recording = TouchDataset("rec", [frames], pd.DataFrame({"capture_id": ["rec"], "subject": ["s04"],
                                                              "gesture": ["mixed"]}), ds.sensor)
    recording.to_parquet(tmp_path / "rec.parquet")
    model = tmp_path / "m.joblib"
    res = CliRunner().invoke(cli, ["train", str(root / "p.yaml"), "--fold", "s04", "--out", str(model)],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    live = json.loads(scores.set_index("fold").loc["subject=s04", "live"])["streams"][0]["results"]
    # the model file records stream's default rule (an HMM, switch 0.01), which the third rule is
    assert json.loads((tmp_path / "m.joblib.json").read_text())["stream_rule"] == {"name": "hmm", "switch": 0.01}
    for k, rule in enumerate([["--rule", "{name: max, threshold: 0.4}"],
                              ["--rule", "{name: majority, n: 3, threshold: 0.4}"], []]):
        res = CliRunner().invoke(cli, ["stream", str(model), str(tmp_path / "rec.parquet"), "--hop", "0.2",
                                       *rule, "--no-realtime", "--jsonl"], catch_exceptions=False)
        assert res.exit_code == 0, res.output
        printed = [json.loads(line) for line in res.stdout.splitlines() if line.startswith("{")]
        cli_frames = decisions_per_frame([d["frame"] for d in printed], [d["label"] for d in printed], len(truth),
                                         "undecided")
        assert len(printed) == live[k]["n_decisions"]
        assert cli_frames.tolist() == _expand(live[k]["decisions"], len(truth)).tolist()


def _recordings_csv(path):
    """Three people, one recording each, labelled frame by frame at 10 Hz on a 4 x 4 grid: 10 frames
    idle, 10 press (every cell high), 10 idle, 10 tap (high, low, alternating by two frames), 10 idle:
    30 of 50 frames idle, so answering idle at every frame scores 60.0 %."""
    rng = np.random.default_rng(0)
    labels = ["idle"] * 10 + ["press"] * 10 + ["idle"] * 10 + ["tap"] * 10 + ["idle"] * 10
    rows = []
    for subject in ("p1", "p2", "p3"):
        for f, lab in enumerate(labels):
            if lab == "idle":
                v = rng.integers(0, 6, 16)
            elif lab == "press":
                v = rng.integers(80, 91, 16)
            else:
                v = np.full(16, 90 if (f // 2) % 2 == 0 else 0)
            rows.append({"recording": f"rec-{subject}", "subject": subject, "frame": f, "label": lab,
                         **{f"cell{i}": int(x) for i, x in enumerate(v)}})
    pd.DataFrame(rows).to_csv(path, index=False)


RECORDED = """\
name: live-recorded
dataset: {data}
target: gesture
scheme:
  name: stream
  base: loso
  source: recorded
  idle: idle
  windows_s: [0.5, 1.0]
  hop_s: 0.2
  rules: [max]
methods: [touch-et-fast]
seed: 0
"""


def test_a_per_frame_labelled_table_is_evaluated_as_streams_and_shown_in_a_stream_table(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    _recordings_csv(tmp_path / "rec.csv")
    res = CliRunner().invoke(cli, ["data", "convert", str(tmp_path / "rec.csv"), str(tmp_path / "rec.parquet"),
                                   "--format", "table", "--capture-columns", "recording", "--frame-labels", "label",
                                   "--grid", "4x4", "--frame-rate", "10", "--value-range", "0..100"],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    ds = TouchDataset.from_parquet(tmp_path / "rec.parquet")
    # each recording cut into its five runs of one label, in order
    assert len(ds) == 15 and ds.meta["recording"].nunique() == 3
    assert ds.meta[ds.meta["recording"] == "rec-p1"].sort_values("start_frame")["gesture"].tolist() == \
        ["idle", "press", "idle", "tap", "idle"]
    info = CliRunner().invoke(cli, ["data", "info", str(tmp_path / "rec.parquet")], catch_exceptions=False)
    assert "streams       recorded: 3 recordings labelled frame by frame (15 s)" in info.output  # 3 x 50 frames at 10 Hz
    (tmp_path / "p.yaml").write_text(RECORDED.format(data=tmp_path / "rec.parquet"))
    res = CliRunner().invoke(cli, ["run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "res"), "--jobs", "1",
                                   "--no-progress"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["leaderboard", str(tmp_path / "res"), "--format", "md", "--out",
                                   str(tmp_path / "lb")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    md = (tmp_path / "lb" / "leaderboard.md").read_text()
    assert "recorded streams" in md and "idle-only %" in md
    row = next(line for line in md.splitlines() if line.startswith("| touch-et-fast"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    header = [c.strip() for c in next(line for line in md.splitlines() if line.startswith("| method")).strip("|")
              .split("|")]
    got = dict(zip(header, cells))
    assert got["rule"] == "max" and got["streams"] == "3" and got["idle-only %"] == "60.0"
    assert 0.0 <= float(got["frame %"]) <= 100.0


#: a protocol on ``_recordings_csv``'s table (format with ``{data}``), its name, scheme lines and methods
#: filled in by :func:`_recorded_protocol`
RECORDED_TABLE = """\
name: {name}
dataset:
  name: {{data}}
  format: table
  options: {{{{capture_columns: [recording], frame_labels: label, grid: [4, 4], frame_rate: 10, value_range: [0, 100]}}}}
target: gesture
scheme:
  name: stream
  base: loso
  source: recorded
  idle: idle
  windows_s: [0.5, 1.0]
  hop_s: 0.2
{scheme}
methods: {methods}
seed: 0
"""


def _recorded_protocol(name: str, scheme: str, methods: str) -> str:
    return RECORDED_TABLE.format(name=name, scheme=scheme, methods=methods)


ALL_RULES = _recorded_protocol(
    "live-recorded-rules", "  rules: [{{name: max, threshold: 0.4}}, {{name: majority, n: 3}}, {{name: hmm, switch: 0.05}},\n"
    "          {{name: gate, idle: idle}}, {{name: onset, idle: idle}}]", "[touch-et-fast]")


def test_stream_by_recording_name_decides_what_the_evaluation_decided_with_every_rule(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    _recordings_csv(tmp_path / "rec.csv")
    (tmp_path / "p.yaml").write_text(ALL_RULES.format(data=tmp_path / "rec.csv"))
    res = CliRunner().invoke(cli, ["run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "res"), "--jobs", "1",
                                   "--no-progress"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    live = json.loads(pd.read_parquet(tmp_path / "res" / "scores.parquet").set_index("fold").loc["subject=p2", "live"])
    (stream,) = live["streams"]
    assert stream["name"] == "rec-p2" and stream["frames"] == 50
    model = tmp_path / "m.joblib"
    res = CliRunner().invoke(cli, ["train", str(tmp_path / "p.yaml"), "--fold", "p2", "--out", str(model)],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "m.joblib.json").read_text())
    # every declared rule, in order; the gate's and onset's level the one the evaluation fitted on fold p2
    stored = manifest["stream_rules"]
    assert [r["name"] for r in stored] == ["max", "majority", "hmm", "gate", "onset"]
    for r, fitted in zip(stored[3:], live["rules"][3:]):
        assert r == {"name": r["name"], "idle": "idle", "level": fitted["fitted_level"]}
    assert manifest["stream_rule"] == {"name": "hmm", "switch": 0.01}
    assert manifest["stream_rule_source"] == "the toolkit's default rule"
    table = ["--format", "table", "--capture-columns", "recording", "--frame-labels", "label", "--grid", "4x4",
             "--frame-rate", "10", "--value-range", "0..100"]
    for k, rule in enumerate(["max", "majority", "{name: hmm, switch: 0.05}", "gate", "onset"]):
        res = CliRunner().invoke(cli, ["stream", str(model), str(tmp_path / "rec.csv"), *table, "--recording",
                                       "rec-p2", "--rule", rule, "--hop", "0.2", "--no-realtime", "--jsonl"],
                                 catch_exceptions=False)
        assert res.exit_code == 0, res.output
        assert "the model file's fitted rule of that name" in res.stderr
        printed = [json.loads(line) for line in res.stdout.splitlines() if line.startswith("{")]
        decided = decisions_per_frame([d["frame"] for d in printed], [d["label"] for d in printed], 50, "undecided")
        result = stream["results"][k]
        assert len(printed) == result["n_decisions"], rule
        assert decided.tolist() == _expand(result["decisions"], 50).tolist(), rule
    res = CliRunner().invoke(cli, ["stream", str(model), str(tmp_path / "rec.csv"), *table, "--recording", "rec-p9"])
    assert res.exit_code == 3 and "no recording 'rec-p9'; did you mean" in res.output and "rec-p2" in res.output
    res = CliRunner().invoke(cli, ["stream", str(model), str(tmp_path / "rec.csv"), *table, "--recording", "rec-p2",
                                   "--no-realtime"], catch_exceptions=False)
    assert "the model file's default rule (the toolkit's default rule)" in res.stderr


CHOSEN = _recorded_protocol(
    "live-recorded-chosen", "  train_on: streams\n  choose_rule: true\n"
    "  rules: [{{name: max, threshold: 0.9}}, {{name: touch, idle: idle, begin: 0.6, end: 0.4}}]",
    "\n  - {{name: touch-live-fast, params: {{params: {{n_estimators: 10}}}}}}")


def test_a_live_method_trained_on_streams_keeps_the_rule_its_inner_folds_chose(tmp_path, monkeypatch):
    """The rule chosen inside a fold (on its training subjects) is the one `train --fold` writes into the
    model file, and `stream` with that default decides what the evaluation decided with it."""
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    _recordings_csv(tmp_path / "rec.csv")
    (tmp_path / "p.yaml").write_text(CHOSEN.format(data=tmp_path / "rec.csv"))
    res = CliRunner().invoke(cli, ["run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "res"), "--jobs", "1",
                                   "--no-progress"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    assert "inner choice (default)" in res.output
    live = json.loads(pd.read_parquet(tmp_path / "res" / "scores.parquet").set_index("fold").loc["subject=p2", "live"])
    choice = live["choice"]
    assert choice["inner_folds"] == 2 and len(choice["frame_accuracy"]) == 2  # p1 and p3 left out in turn
    assert live["train_on"] == "streams"
    k = choice["rule"]
    res = CliRunner().invoke(cli, ["train", str(tmp_path / "p.yaml"), "--fold", "p2", "--out", str(tmp_path / "m.joblib")],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "m.joblib.json").read_text())
    assert manifest["stream_rule"]["name"] == live["rules"][k]["name"]
    assert manifest["stream_rule_source"].startswith("chosen by 2 inner folds over the model's training subjects")
    assert manifest["classifier"]["params"]["idle"] == "idle"  # the scheme's idle class, given to two-stage
    table = ["--format", "table", "--capture-columns", "recording", "--frame-labels", "label", "--grid", "4x4",
             "--frame-rate", "10", "--value-range", "0..100"]
    res = CliRunner().invoke(cli, ["stream", str(tmp_path / "m.joblib"), str(tmp_path / "rec.csv"), *table,
                                   "--recording", "rec-p2", "--hop", "0.2", "--no-realtime", "--jsonl"],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    assert "chosen by 2 inner folds" in res.stderr
    printed = [json.loads(line) for line in res.stdout.splitlines() if line.startswith("{")]
    decided = decisions_per_frame([d["frame"] for d in printed], [d["label"] for d in printed], 50, "undecided")
    assert decided.tolist() == _expand(live["streams"][0]["results"][k]["decisions"], 50).tolist()
