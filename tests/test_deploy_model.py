"""``touchbench train`` / ``predict`` / ``stream`` on a small dataset built here.

Checks: the manifest against values computed independently (content hash
of the training captures, scikit-learn's version), a saved model predicting
like the run engine's fold (same seed, same data), sensor refusal, method
choice errors, frames from standard input and from a replayed file.
"""

from __future__ import annotations

import json

import joblib
import numpy as np
import pandas as pd
import pytest
import sklearn
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.deploy.model import TrainedModel, fit_model
from touchbench.methods.base import MethodSpec
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset

PROTOCOL = """\
name: deploy-small
dataset: {data}
scheme: loso
features:
  - [msd]
  - [msd, {{name: bmh, params: {{preset: haart}}}}]   # the test sensor is neither HAART nor CoST: the preset is named
classifiers:
  - {{name: gaus-rf, params: {{n_estimators: 15}}, label: rf15}}
seed: 3
"""


@pytest.fixture()
def setup(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    ds = random_dataset(subjects=("s1", "s2", "s3"), gestures=("pat", "rub", "stroke"), per_cell=3, frames=(20, 24))
    data = tmp_path / "data.parquet"
    ds.to_parquet(data)
    proto = tmp_path / "small.yaml"
    proto.write_text(PROTOCOL.format(data=data))
    return ds, data, proto


def invoke(*args, input=None):
    res = CliRunner().invoke(cli, [str(a) for a in args], input=input, catch_exceptions=False)
    return res


def test_train_writes_model_and_manifest(setup, tmp_path):
    ds, data, proto = setup
    out = tmp_path / "m.joblib"
    res = invoke("train", proto, "--method", "msd/rf15", "--exclude", "subject=s3", "--out", out)
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "m.joblib.json").read_text())
    kept = np.flatnonzero(ds.meta["subject"].to_numpy() != "s3")
    assert manifest["dataset"]["content_hash"] == ds.subset(kept).content_hash
    assert manifest["dataset"]["n_captures"] == len(kept) == 18
    assert manifest["versions"]["scikit-learn"] == sklearn.__version__
    assert manifest["features"]["sets"] == [{"name": "msd", "params": {}}]
    assert manifest["classifier"]["name"] == "gaus-rf" and manifest["classifier"]["params"] == {"n_estimators": 15}
    assert manifest["classes"] == ["pat", "rub", "stroke"]
    assert manifest["sensor"] == ds.sensor.to_dict()
    m = TrainedModel.load(out)
    assert m.manifest == manifest and m.method == "msd/rf15"
    assert len(m.estimator.estimators_) == 15
    assert manifest["features"]["n_columns"] == m.transform(ds.captures[:2]).shape[1] == m.estimator.n_features_in_


def test_fold_model_predicts_like_the_engine(setup, tmp_path):
    ds, data, proto = setup
    run = run_protocol(proto, tmp_path / "results")
    assert run.n_failed == 0
    preds = pd.read_parquet(tmp_path / "results" / "predictions.parquet")
    res = invoke("train", proto, "--method", "msd+bmh/rf15", "--fold", "s2", "--out", tmp_path / "f.joblib")
    assert res.exit_code == 0, res.output
    test = ds.subset(np.flatnonzero(ds.meta["subject"].to_numpy() == "s2"))
    test.to_parquet(tmp_path / "s2.parquet")
    res = invoke("predict", tmp_path / "f.joblib", tmp_path / "s2.parquet", "--out", tmp_path / "p.csv")
    assert res.exit_code == 0, res.output
    ours = pd.read_csv(tmp_path / "p.csv").set_index("capture_id")
    theirs = preds[(preds["fold"] == "subject=s2") & (preds["features"] == "msd+bmh")].set_index("capture_id")
    assert len(ours) == len(theirs) == 9
    assert (ours.loc[theirs.index, "predicted_label"] == theirs["predicted_label"]).all()
    for c in ("pat", "rub", "stroke"):
        np.testing.assert_allclose(ours.loc[theirs.index, f"proba_{c}"], theirs[f"proba_{c}"], rtol=0, atol=1e-12)


def _table_csv(ds, path):
    """The dataset's captures in the table format, one row per frame (values as written, read back as float64)."""
    rows = []
    for cid, subj, g, cap in zip(ds.meta["capture_id"], ds.meta["subject"], ds.meta["gesture"], ds.captures):
        for t, frame in enumerate(cap):
            rows.append({"capture_id": cid, "frame": t + 1, "subject": subj, "gesture": g,
                         **{f"cell{i + 1}": int(v) for i, v in enumerate(frame.reshape(-1))}})
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_predict_refuses_another_sensor_and_reads_the_table_format(setup, tmp_path):
    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib").exit_code == 0
    other = TouchDataset("other", ds.captures, ds.meta, SensorSpec("test-4x4", (4, 4), 20.0, (0.0, 255.0)))
    other.to_parquet(tmp_path / "other.parquet")
    res = CliRunner().invoke(cli, ["predict", str(tmp_path / "m.joblib"), str(tmp_path / "other.parquet")])
    assert res.exit_code == 3
    assert "does not match the model's sensor" in res.output and "frame_rate: model 10.0, data 20.0" in res.output
    # the same captures in the table format, one row per frame, read with the model's grid; the frame rate is the recording's
    _table_csv(ds, tmp_path / "long.csv")
    unsaid = invoke("predict", tmp_path / "m.joblib", tmp_path / "long.csv", "--format", "table")
    assert unsaid.exit_code == 3 and "give --frame-rate" in unsaid.output and "trained at 10" in unsaid.output
    fast = invoke("predict", tmp_path / "m.joblib", tmp_path / "long.csv", "--format", "table", "--frame-rate", "20")
    assert fast.exit_code == 3 and "frame_rate: model 10.0, data 20.0" in fast.output  # a 20 Hz recording
    near = invoke("predict", tmp_path / "m.joblib", tmp_path / "long.csv", "--format", "table", "--frame-rate", "10.05")
    assert near.exit_code == 0  # within the 1 % tolerance
    a = invoke("predict", tmp_path / "m.joblib", tmp_path / "long.csv", "--format", "table", "--frame-rate", "10")
    b = invoke("predict", tmp_path / "m.joblib", data)
    assert a.exit_code == 0 and b.exit_code == 0
    # table CSV values come back as float64, the Parquet as uint8: same features, same labels
    assert a.stdout == b.stdout
    assert "no unseen captures of the model's classes to score; 27 captures the model was trained on" in b.stderr


def test_method_choice_and_bad_model_file(setup, tmp_path):
    ds, data, proto = setup
    res = CliRunner().invoke(cli, ["train", str(proto), "-o", str(tmp_path / "m.joblib")])
    assert res.exit_code == 3 and "choose one with --method" in res.output and "msd+bmh/rf15" in res.output
    res = CliRunner().invoke(cli, ["train", str(proto), "-m", "msd/rf51", "-o", str(tmp_path / "m.joblib")])
    assert res.exit_code == 3 and "did you mean 'msd/rf15'" in res.output
    res = CliRunner().invoke(cli, ["train", str(proto), "-m", "msd/rf15", "--fold", "s9", "-o", str(tmp_path / "m.joblib")])
    assert res.exit_code == 3 and "no fold 's9'" in res.output
    (tmp_path / "junk.joblib").write_bytes(b"not a model")
    res = CliRunner().invoke(cli, ["predict", str(tmp_path / "junk.joblib"), str(data)])
    assert res.exit_code == 3 and "junk.joblib: not a touchbench model file" in res.output
    assert not (tmp_path / "m.joblib").exists()


def test_run_and_train_read_a_method_name_the_same_way(setup, tmp_path):
    ds, data, proto = setup
    # FEATURES/LABEL names one of the two methods (msd/rf15, msd+bmh/rf15): run runs its 3 folds only
    res = invoke("run", proto, "--method", "msd+bmh/rf15", "--out", tmp_path / "res", "--no-progress")
    assert res.exit_code == 0, res.output
    scores = pd.read_parquet(tmp_path / "res" / "scores.parquet")
    assert sorted(scores["fold"]) == ["subject=s1", "subject=s2", "subject=s3"]
    assert set(scores["features"]) == {"msd+bmh"}
    assert invoke("train", proto, "-m", "msd+bmh/rf15", "-o", tmp_path / "m.joblib").exit_code == 0
    assert TrainedModel.load(tmp_path / "m.joblib").method == "msd+bmh/rf15"
    # a label alone: run runs every method with it; train needs it to name one
    res = invoke("run", proto, "--method", "rf15", "--out", tmp_path / "res2", "--no-progress")
    assert res.exit_code == 0, res.output
    assert set(pd.read_parquet(tmp_path / "res2" / "scores.parquet")["features"]) == {"msd", "msd+bmh"}
    res = invoke("train", proto, "-m", "rf15", "-o", tmp_path / "m2.joblib")
    assert res.exit_code == 3 and "'rf15' names 2 methods" in res.output
    # a misspelling: both refuse it with the same nearest name
    for args in (["run", proto, "--method", "msd/rf51", "--out", tmp_path / "res3"],
                 ["train", proto, "-m", "msd/rf51", "-o", tmp_path / "m3.joblib"]):
        res = CliRunner().invoke(cli, [str(a) for a in args])
        assert res.exit_code in (2, 3) and "did you mean 'msd/rf15'" in res.output, res.output


def test_stream_from_stdin_and_from_a_replayed_file(setup, tmp_path):
    ds, data, proto = setup
    res = invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib", "--window", "1", "--train-hop", "0.5")
    assert res.exit_code == 0, res.output
    cap = ds.captures[0]  # 4 x 4 frames at 10 Hz
    lines = "\n".join(",".join(str(int(v)) for v in f.reshape(-1)) for f in cap[:20]) + "\n"
    res = invoke("stream", tmp_path / "m.joblib", "-", "--hop", "0.5", "--threshold", "0", "--jsonl",
                 "--summary-json", tmp_path / "s.json", input=lines)
    assert res.exit_code == 0, res.output
    decisions = [json.loads(x) for x in res.stdout.splitlines()]
    # 1-s window = 10 frames, hop 5 frames, 20 frames: decisions at frames 10, 15, 20
    assert [d["frame"] for d in decisions] == [10, 15, 20]
    assert all(d["label"] in ("pat", "rub", "stroke") and 0 <= d["probability"] <= 1 for d in decisions)
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["decisions"] == 3 and summary["latency_ms_p99"] >= summary["latency_ms_p50"] >= 0
    assert "p50" in res.stderr and "p99" in res.stderr
    # the same frames replayed from the dataset file give the same decisions
    res2 = invoke("stream", tmp_path / "m.joblib", data, "--capture", ds.meta["capture_id"][0], "--hop", "0.5",
                  "--threshold", "0", "--jsonl", "--speed", "50")
    assert res2.exit_code == 0, res2.output
    again = [json.loads(x) for x in res2.stdout.splitlines()][:3]
    assert [(d["label"], d["probability"]) for d in again] == [(d["label"], d["probability"]) for d in decisions]
    # a malformed line is reported with its line number and skipped: the stream goes on
    glitch = lines.splitlines()
    glitch[2] = glitch[2].rsplit(",", 1)[0]  # a frame cut short
    glitch[5] = glitch[5].replace(",", ",1_0,", 1).rsplit(",", 1)[0]  # 1_0 is no number here
    res3 = invoke("stream", tmp_path / "m.joblib", "-", "--hop", "0.5", "--threshold", "0", "--jsonl",
                  input="\n".join(glitch) + "\n")
    assert res3.exit_code == 0, res3.output
    assert "skipped: <stdin>:3: a frame has 15 values" in res3.stderr and "skipped: <stdin>:6: not a number: '1_0'" in res3.stderr
    assert "2 malformed lines skipped" in res3.stderr
    # 18 frames received: decisions at frames 10 and 15 (counted as received, the skipped lines are no frames)
    assert [json.loads(x)["frame"] for x in res3.stdout.splitlines()] == [10, 15]


def test_predict_scores_unseen_captures_and_counts_the_seen_apart(setup, tmp_path):
    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "--exclude", "subject=s3", "-o", tmp_path / "m.joblib").exit_code == 0
    res = invoke("predict", tmp_path / "m.joblib", data, "--out", tmp_path / "p.csv")
    assert res.exit_code == 0, res.output
    table = pd.read_csv(tmp_path / "p.csv")
    unseen = (table["subject"] == "s3").to_numpy()  # 9 captures of s3; the 18 others were trained on
    assert table["trained_on"].tolist() == (~unseen).tolist()
    acc = 100 * np.mean(table["true_label"].to_numpy()[unseen] == table["predicted_label"].to_numpy()[unseen])
    assert (f"accuracy {acc:.1f} % on 9 captures of unseen subjects; 18 captures the model was trained on are not "
            "scored") in res.stderr
    # the same recordings through another reader (float64 values from a CSV) are recognised as seen
    csv = _table_csv(ds, tmp_path / "t.csv")
    res = invoke("predict", tmp_path / "m.joblib", csv, "--format", "table", "--frame-rate", "10", "--out", tmp_path / "q.csv")
    assert res.exit_code == 0 and "on 9 captures of unseen subjects; 18 captures the model" in res.stderr
    # only captures it was trained on: nothing to score, said so
    seen_only = ds.subset(np.flatnonzero(ds.meta["subject"].to_numpy() != "s3"))
    seen_only.to_parquet(tmp_path / "seen.parquet")
    res = invoke("predict", tmp_path / "m.joblib", tmp_path / "seen.parquet")
    assert "no unseen captures of the model's classes to score; 18 captures the model was trained on" in res.stderr
    assert "accuracy" not in res.stderr


def test_captures_of_training_subjects_with_other_frames_are_not_called_unseen(setup, tmp_path):
    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "--exclude", "subject=s3", "-o", tmp_path / "m.joblib").exit_code == 0
    manifest = json.loads((tmp_path / "m.joblib.json").read_text())
    kept = ds.meta[ds.meta["subject"] != "s3"]
    assert manifest["dataset"]["subjects"] == ["s1", "s2"]
    assert manifest["dataset"]["recordings"] == sorted(f"{s}/{c}" for s, c in zip(kept["subject"], kept["capture_id"]))
    # every capture cut one frame shorter (another window), and one value changed in s1's first capture:
    # no frames the model saw, 18 captures of its training subjects (their very recordings), 9 of s3
    captures = [c[1:].copy() for c in ds.captures]
    captures[0][0, 0, 0] += 1
    TouchDataset(ds.name, captures, ds.meta, ds.sensor).to_parquet(tmp_path / "cut.parquet")
    res = invoke("predict", tmp_path / "m.joblib", tmp_path / "cut.parquet", "--out", tmp_path / "p.csv")
    assert res.exit_code == 0, res.output
    table = pd.read_csv(tmp_path / "p.csv")
    s3 = (table["subject"] == "s3").to_numpy()
    assert not table["trained_on"].any()
    assert table["trained_on_subject"].tolist() == table["trained_on_recording"].tolist() == (~s3).tolist()
    ok = table["true_label"].to_numpy() == table["predicted_label"].to_numpy()
    assert (f"accuracy {100 * ok[s3].mean():.1f} % on 9 captures of unseen subjects; accuracy "
            f"{100 * ok[~s3].mean():.1f} % on 18 captures of subjects the model was trained on (18 of them "
            "recordings it was trained on, with other frames): this accuracy is not on unseen people") in res.stderr
    assert "unseen captures" not in res.stderr
    # only the training subjects, under other capture ids: their people, not their recordings
    renamed = ds.meta.assign(capture_id=[f"x{i}" for i in range(len(ds))])
    keep = np.flatnonzero(~s3)
    TouchDataset(ds.name, captures, renamed, ds.sensor).subset(keep).to_parquet(tmp_path / "renamed.parquet")
    res = invoke("predict", tmp_path / "m.joblib", tmp_path / "renamed.parquet")
    assert (f"accuracy {100 * ok[~s3].mean():.1f} % on 18 captures of subjects the model was trained on (0 of them "
            "recordings it was trained on, with other frames): this accuracy is not on unseen people") in res.stderr
    assert "unseen subjects" not in res.stderr and "unseen captures" not in res.stderr


def test_sessions_are_recorded_and_compared(tmp_path):
    ds = random_dataset(subjects=("s1", "s2"), gestures=("pat", "rub"), per_cell=2, extra={"session": [1, 2]},
                        frames=(20, 24))
    train = ds.subset(np.flatnonzero(ds.meta["session"].to_numpy() == 1))
    model = fit_model(train, MethodSpec("lda", (("msd", {}),), "zhou-lda"))
    assert model.manifest["dataset"]["sessions"] == ["s1/1", "s2/1"]
    seen = model.seen_people(ds.meta)
    assert seen["session"].tolist() == (ds.meta["session"] == 1).tolist()
    assert seen["subject"].all()


def _rewrite(path, edit_header):
    """The model file at ``path`` with its JSON header line changed by ``edit_header`` (the pickle kept)."""
    raw = path.read_bytes()
    first = raw.index(b"\n") + 1
    end = raw.index(b"\n", first)
    header = json.loads(raw[first:end])
    edit_header(header)
    path.write_bytes(raw[:first] + json.dumps(header).encode() + raw[end:])


def test_an_edited_manifest_is_refused_and_an_older_file_still_loads(setup, tmp_path):
    import hashlib

    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib").exit_code == 0
    _rewrite(tmp_path / "m.joblib", lambda h: h["manifest"]["classifier"].update(random_state=99))
    res = CliRunner().invoke(cli, ["predict", str(tmp_path / "m.joblib"), str(data)])
    assert res.exit_code == 3 and "does not match the checksum" in res.output and "nothing was loaded" in res.output
    # a file of format 2: a joblib pickle, its checksum of the pickle only, no training capture checksums
    assert invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "old.joblib").exit_code == 0
    m = TrainedModel.load(tmp_path / "old.joblib")
    buf = __import__("io").BytesIO()
    joblib.dump({"feature_sets": m.feature_sets, "estimator": m.estimator, "classes": list(m.classes)}, buf)
    body = buf.getvalue()
    raw = (tmp_path / "old.joblib").read_bytes()
    (tmp_path / "old.joblib").write_bytes(raw[:raw.index(b"\n", raw.index(b"\n") + 1) + 1] + body)

    def as_older(h):
        h.update(version=2, sha256=hashlib.sha256(body).hexdigest(), size=len(body))
        del h["manifest"]["dataset"]["capture_checksums"]

    _rewrite(tmp_path / "old.joblib", as_older)
    res = invoke("predict", tmp_path / "old.joblib", data, "--trust")  # a pickle: read only when trusted
    assert res.exit_code == 0, res.output
    assert "warning:" in res.stderr and "checksum does not cover its manifest" in res.stderr
    assert "on 27 captures of known classes" in res.stderr and "cannot be separated" in res.stderr
    assert "trained_on" not in pd.read_csv(__import__("io").StringIO(res.stdout)).columns


def test_stream_replays_a_table_without_frame_rate_at_the_models(setup, tmp_path):
    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib", "--window", "1").exit_code == 0
    csv = _table_csv(ds.subset([0]), tmp_path / "t.csv")
    args = ["--hop", "0.5", "--threshold", "0", "--jsonl", "--no-realtime"]
    res = invoke("stream", tmp_path / "m.joblib", csv, "--format", "table", *args)
    assert res.exit_code == 0, res.output
    assert "does not say its frame rate: the model's, 10 Hz" in res.stderr
    auto = invoke("stream", tmp_path / "m.joblib", csv, *args)
    key = [(d["frame"], d["t"], d["label"], d["probability"]) for d in map(json.loads, res.stdout.splitlines())]
    assert key == [(d["frame"], d["t"], d["label"], d["probability"]) for d in map(json.loads, auto.stdout.splitlines())]
    assert [k[:2] for k in key] == [(10, 1.0), (15, 1.5), (20, 2.0)]  # 1-s windows of 10 frames at 10 Hz, hop 5
    # a frame rate given is the recording's: 20 Hz is not the model's sensor
    fast = invoke("stream", tmp_path / "m.joblib", csv, "--format", "table", "--frame-rate", "20", *args)
    assert fast.exit_code == 3 and "frame_rate: model 10.0, data 20.0" in fast.output


def test_help_and_model_description_say_what_the_options_do(setup, tmp_path):
    ds, data, proto = setup
    res = invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib", "--window", "0.5,1")
    assert res.exit_code == 0, res.output
    # at 10 Hz: 0.5 s = 5 frames, hop half of it rounded down, 2 frames = 0.2 s; 1 s = 10 frames, hop 5 = 0.5 s
    assert "windows       0.5 s (hop 0.2 s), 1 s (hop 0.5 s)" in res.stdout
    text = " ".join(invoke("stream", "--help").output.split())
    assert "format haart-raw: Frames per second (default 54, the HAART sensor's); format table: Frames per second (default: estimated from the time column" in text
    assert "frame (the number of frames received when the decision was made, counting from 1)" in text


def test_stream_refuses_a_bad_rule_or_speed_and_caps_the_skipped_lines(setup, tmp_path):
    ds, data, proto = setup
    assert invoke("train", proto, "-m", "msd/rf15", "-o", tmp_path / "m.joblib", "--window", "1").exit_code == 0
    model = tmp_path / "m.joblib"
    res = CliRunner().invoke(cli, ["stream", str(model), "-", "--rule", "[1, 2]"], input="")
    assert res.exit_code == 2 and "Invalid value for --rule" in res.output and "Traceback" not in res.output
    for speed in ("nan", "inf", "0", "-2"):
        res = CliRunner().invoke(cli, ["stream", str(model), str(data), "--speed", speed])
        assert res.exit_code == 2 and "Invalid value for --speed" in res.output, speed
    # a model trained outside a stream protocol holds no fitted gate: one error saying what to do
    res = CliRunner().invoke(cli, ["stream", str(model), "-", "--rule", "gate"], input="")
    assert res.exit_code == 3 and res.output.count("\n") == 1
    assert "needs a level fitted on training captures" in res.output and "train the model on a stream protocol" in res.output
    # 25 lines of garbage: the first 10 reported, the other 15 counted in one line; no decision is an error
    res = CliRunner().invoke(cli, ["stream", str(model), "-"], input="garbage\n" * 25)
    assert res.exit_code == 3
    assert [line for line in res.stderr.splitlines() if line.startswith("skipped: <stdin>:")] == \
        [f"skipped: <stdin>:{n}: a frame has 1 values, the model's 4 x 4 sensor needs 16" for n in range(1, 11)]
    assert "skipped: 15 more malformed lines, not shown" in res.stderr
    assert "error: no decision: 0 frames read from standard input (25 malformed lines skipped)" in res.stderr
