"""Evaluation integrity: leaky schemes flagged everywhere, cross-dataset transfer that never tests a
training capture, several evaluations per protocol, design data, the ledger of test-set looks.

Expected values are worked out from the datasets built here (which captures each fold holds,
how many windows a capture gives), never read from the code's own output.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from helpers import SUBPROCESS_HANG_S, wait_for

from touchbench.cli.main import cli as main
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.adapt import AdapterError, adapt
from touchbench.datasets.model import SensorSpec, TouchDataset, frames_checksum
from touchbench.datasets.windows import window_dataset
from touchbench.engine import run_protocol
from touchbench.engine.planning import plan_run
from touchbench.engine.testing import SENSOR, random_dataset
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol
from touchbench.protocols.schemes import make_splitter
from touchbench.protocols.schemes.kfold import SUBJECTS_SHARED
from touchbench.reports.html import write_report
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import display_rows, to_markdown
from touchbench.reports.results import load_results
from touchbench.results.ledger import FinalRunError, Looks, looks, read_ledger, record_look

SUBJECTS = ("s1", "s2", "s3", "s4")


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _data(tmp_path: Path, name="data.parquet", **kw) -> Path:
    p = tmp_path / name
    random_dataset(subjects=kw.pop("subjects", SUBJECTS), per_cell=kw.pop("per_cell", 2), **kw).to_parquet(p)
    return p


def _protocol(tmp_path: Path, body: str, name="p") -> Path:
    p = tmp_path / f"{name}.yaml"
    p.write_text(f"name: {name}\n" + body)
    return p


# ----------------------------------------------------------------- leaky schemes
def test_kfold_ignoring_subjects_is_leaky_and_grouped_kfold_and_loso_are_not():
    assert make_splitter("kfold", k=3).leakage() == SUBJECTS_SHARED
    assert make_splitter("kfold", k=3, grouped=True).leakage() == ""
    assert make_splitter("kfold", k=3, target="subject").leakage() == ""  # person identification needs it
    assert make_splitter("loso").leakage() == ""
    assert make_splitter("early", base={"name": "kfold", "k": 3}, frames=[2]).leakage() == SUBJECTS_SHARED
    assert "windows of one capture" in make_splitter("window-kfold", k=3, frames=4).leakage()
    assert make_splitter("window-kfold", k=3, frames=4, group_by="subject").leakage() == ""


def test_window_dataset_cuts_every_capture_into_its_windows():
    ds = random_dataset(subjects=("s1",), gestures=("pat",), per_cell=2, frames=(10, 10))
    w = window_dataset(ds, frames=4)  # 10 frames: windows at 0 and 4 (8 would need 12 frames)
    assert len(w) == 4
    assert w.meta["source_capture"].tolist() == ["c0000", "c0000", "c0001", "c0001"]
    assert w.meta["capture_id"].tolist() == ["c0000#w0", "c0000#w1", "c0001#w0", "c0001#w1"]
    np.testing.assert_array_equal(w.captures[1], ds.captures[0][4:8])
    w2 = window_dataset(ds, frames=4, hop=2)  # starts 0, 2, 4, 6
    assert len(w2) == 8


def test_window_kfold_puts_windows_of_one_capture_on_both_sides_unless_grouped(tmp_path):
    data = _data(tmp_path, frames=(12, 12))
    for group_by, shared in (("none", True), ("capture", False)):
        proto = parse_protocol(f"name: w\ndataset: {data}\nscheme: {{name: window-kfold, k: 3, frames: 4, "
                               f"group_by: {group_by}}}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
        plan = plan_run(proto)
        assert len(plan.dataset) == 2 * len(SUBJECTS) * 3 * 3  # 48 captures x 3 windows of 4 frames
        src = plan.dataset.meta["source_capture"].to_numpy()
        both = [bool(set(src[t.fold.train]) & set(src[t.fold.test])) for t in plan.tasks]
        assert any(both) == shared


def test_leaky_rows_leaderboard_and_html_say_so(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"""dataset: {data}
scheme: {{name: kfold, k: 3}}
features: [[test-mean]]
classifiers: [test-logreg]
methods:
  - {{features: [test-mean], estimator: test-logreg, subject_id_feature: true}}
""")
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert (res.scores["leakage"].str.startswith(SUBJECTS_SHARED)).all()
    with_id = res.scores[res.scores["classifier"].str.contains("subject-id")]
    assert len(with_id) == 3 and with_id["leakage"].str.contains("the subject's id is a feature").all()
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert (preds["leakage"] != "").all()
    rs = load_results([tmp_path / "out"])
    lbs = build_leaderboards(rs)
    assert len(lbs) == 1 and lbs[0].is_leaky and "LEAKY" in lbs[0].title
    assert len(lbs[0].rows) == 2  # the subject-id variant is a method of its own
    header, cells = display_rows(lbs[0])
    col = header.index("evaluation")
    assert all(c[col].startswith("LEAKY: ") for c in cells)
    assert "LEAKY" in to_markdown(lbs)
    page = write_report(rs, lbs, tmp_path / "report", kinds=()).read_text()
    assert "LEAKY evaluation" in page and page.count('<tr class="leaky">') == 2


def test_an_honest_scheme_shows_no_leak_column(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    run_protocol(p, out=tmp_path / "out", progress=False)
    lb = build_leaderboards(load_results([tmp_path / "out"]))[0]
    assert not lb.is_leaky and "evaluation" not in display_rows(lb)[0]


def test_tuned_on_test_keeps_the_grid_value_with_the_best_test_accuracy(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"""dataset: {data}
scheme: loso
methods:
  - {{features: [test-mean], estimator: test-logreg, params: {{C: {{grid: [0.0001, 1.0]}}}}, tuned_on_test: true}}
""")
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert (res.scores["leakage"] == "a parameter chosen by its test accuracy").all()
    per_value = res.scores.groupby("classifier")["accuracy"].mean()
    lb = build_leaderboards(load_results([tmp_path / "out"]))[0]
    assert len(lb.rows) == 1
    assert lb.rows["accuracy"].iloc[0] == pytest.approx(per_value.max())
    assert "chosen on test" in lb.rows["classifier"].iloc[0]


def test_subject_id_feature_is_refused_for_an_estimator_on_captures(tmp_path):
    with pytest.raises(ProtocolError, match="takes the captures themselves"):
        parse_protocol("name: x\ndataset: haart-sample\nscheme: loso\nmethods:\n"
                       "  - {name: minirocket, subject_id_feature: true}\n", deep=False)


# ----------------------------------------------------------------- cross-dataset
def test_cross_dataset_trains_on_one_dataset_and_tests_on_the_other(tmp_path):
    train = _data(tmp_path, "train.parquet", subjects=("a1", "a2"), seed=1)
    test = _data(tmp_path, "test.parquet", subjects=("b1",), seed=2)
    p = _protocol(tmp_path, f"dataset: {train}\nscheme: {{name: cross-dataset, test: {test}}}\n"
                            "features: [[test-mean]]\nclassifiers: [test-logreg]\n")
    plan = plan_run(parse_protocol(p.read_text(), p))
    t = plan.tasks[0]  # one test set: five seeds of the one split by default
    assert len(plan.tasks) == 5 and all(np.array_equal(u.fold.test, t.fold.test) for u in plan.tasks)
    meta = plan.dataset.meta
    assert set(meta["origin"].to_numpy()[t.fold.train]) == {"train"} and len(t.fold.train) == 2 * 3 * 2
    assert set(meta["origin"].to_numpy()[t.fold.test]) == {"test"} and len(t.fold.test) == 3 * 2
    assert set(meta["subject"].to_numpy()[t.fold.test]) == {"b1"}
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert res.scores["leakage"].tolist() == [""] * 5


def test_multi_source_trains_on_one_dataset_and_the_others_other_subjects(tmp_path):
    train = _data(tmp_path, "train.parquet", subjects=("a1", "a2"), seed=1)
    test = _data(tmp_path, "test.parquet", subjects=("b1", "b2", "b3"), seed=2)
    p = _protocol(tmp_path, f"dataset: {train}\nscheme: {{name: multi-source, test: {test}}}\n"
                            "features: [[test-mean]]\nclassifiers: [test-logreg]\n")
    plan = plan_run(parse_protocol(p.read_text(), p))
    meta = plan.dataset.meta
    origin, subject = meta["origin"].to_numpy(), meta["subject"].to_numpy()
    # one fold (and one seed) per subject of the second dataset: not a single test set
    assert [t.fold.name for t in plan.tasks] == ["subject=b1", "subject=b2", "subject=b3"]
    for t, held in zip(plan.tasks, ("b1", "b2", "b3")):
        assert set(subject[t.fold.test]) == {held} and len(t.fold.test) == 3 * 2
        # all 12 captures of the first dataset and the 2 x 6 of the second's other subjects
        assert len(t.fold.train) == 2 * 3 * 2 + 2 * 3 * 2 and held not in set(subject[t.fold.train])
        assert set(origin[t.fold.train]) == {"train", "test"}
    assert sorted(np.concatenate([t.fold.test for t in plan.tasks]).tolist()) == np.flatnonzero(origin == "test").tolist()
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert res.scores["leakage"].tolist() == [""] * 3


def test_early_prepares_the_data_as_its_base_does(tmp_path):
    train = _data(tmp_path, "train.parquet", subjects=("a1", "a2"), seed=1)
    test = _data(tmp_path, "test.parquet", subjects=("b1",), seed=2)
    p = _protocol(tmp_path, f"dataset: {train}\nscheme: {{name: early, frames: [2, 3], base: {{name: cross-dataset, "
                            f"test: {test}}}}}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    plan = plan_run(parse_protocol(p.read_text(), p))
    origin = plan.dataset.meta["origin"].to_numpy()
    assert [t.fold.name for t in plan.tasks] == ["first2f/train->test", "first3f/train->test"]
    assert all(set(origin[t.fold.train]) == {"train"} and set(origin[t.fold.test]) == {"test"} for t in plan.tasks)


def test_cross_dataset_refuses_test_captures_that_are_training_ones(tmp_path):
    train = random_dataset(subjects=("a1", "a2"), per_cell=2, seed=1)
    same = train.subset([0, 5])  # two training recordings, read again as another study's
    meta = same.meta.assign(subject="b1", capture_id=["x0", "x1"])
    other = random_dataset(subjects=("b2",), per_cell=2, seed=3)
    test = TouchDataset("other", [*same.captures, *other.captures],
                        pd.concat([meta, other.meta.assign(capture_id=lambda m: "y" + m["capture_id"])]), SENSOR)
    train.to_parquet(tmp_path / "train.parquet")
    test.to_parquet(tmp_path / "test.parquet")
    p = _protocol(tmp_path, f"dataset: {tmp_path / 'train.parquet'}\nscheme: {{name: cross-dataset, test: "
                            f"{tmp_path / 'test.parquet'}}}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    with pytest.raises(ProtocolError, match="2 test capture\\(s\\) have the frames of a training capture"):
        plan_run(parse_protocol(p.read_text(), p))
    # filtered out of the test data, the evaluation runs and no test capture is a training one
    p.write_text(f"name: p\ndataset: {tmp_path / 'train.parquet'}\nscheme:\n  name: cross-dataset\n  test:\n"
                 f"    name: {tmp_path / 'test.parquet'}\n    exclude: {{subject: [b1]}}\n"
                 "features: [[test-mean]]\nclassifiers: [test-logreg]\n")
    plan = plan_run(parse_protocol(p.read_text(), p))
    sha = plan.dataset.meta["frames_sha256"].to_numpy()
    t = plan.tasks[0]
    assert not set(sha[t.fold.test]) & set(sha[t.fold.train])
    assert {frames_checksum(c) for c in same.captures}.isdisjoint(sha[t.fold.test])


def test_adapters_bring_another_sensor_to_the_training_one():
    src = SensorSpec("big", (6, 6), 100.0, (0.0, 4095.0))
    to = SensorSpec("train", (4, 4), 50.0, (0.0, 1023.0))
    cap = np.arange(10 * 36, dtype=np.float64).reshape(10, 6, 6) % 4096
    ds = TouchDataset("d", [cap], pd.DataFrame({"capture_id": ["c"], "subject": ["s"], "gesture": ["g"]}), src)
    with pytest.raises(AdapterError, match="grid: training \\(4, 4\\), test \\(6, 6\\)"):
        adapt(ds, to, [])
    out, notes = adapt(ds, to, [{"crop": {"top": 1, "left": 2}}, {"resample": "linear"}, {"rescale": "linear"}])
    assert out.sensor == to and len(notes) == 3
    c = out.captures[0]
    assert c.shape == (5, 4, 4)  # 10 frames at 100 Hz -> 5 at 50 Hz
    # frame k at 50 Hz is the frame 2k at 100 Hz (the times coincide), cropped, scaled 1023/4095
    np.testing.assert_allclose(c[2], cap[4, 1:5, 2:6] * 1023.0 / 4095.0)
    with pytest.raises(AdapterError, match="does not fit"):
        adapt(ds, to, [{"crop": {"top": 3, "left": 0}}])


# ----------------------------------------------------------------- several evaluations, design
def test_one_methods_block_under_several_evaluations(tmp_path):
    data = _data(tmp_path, extra={"substrate": ["flat", "curve", "foam"]}, per_cell=1)
    p = _protocol(tmp_path, f"""dataset: {data}
features: [[test-mean]]
classifiers: [test-logreg]
design: {{subjects: [s1, s2], note: chosen by looking at them}}
evaluations:
  - {{name: loso, scheme: loso}}
  - name: to-curve
    scheme: {{name: challenge, column: substrate, train: [flat, foam], test: [curve]}}
  - name: to-s4
    scheme: {{name: challenge, column: subject, train: [s1, s2, s3], test: [s4]}}
""", name="multi")
    res = run_protocol(p, out=tmp_path / "results" / "multi", progress=False)
    assert isinstance(res, list) and [r.out.name for r in res] == ["loso", "to-curve", "to-s4"]
    assert len(res[0].scores) == 4 and len(res[1].scores) == 5  # one test set: five seeds by default
    preds = pd.read_parquet(res[1].out / "predictions.parquet")
    train_sub = pd.read_parquet(data)  # no curve capture is trained on: the test captures are all curve
    assert len(preds) == 5 * (train_sub["substrate"] == "curve").sum()
    lbs = build_leaderboards(load_results([tmp_path / "results" / "multi"]))
    assert len(lbs) == 3
    # a test set without design subjects: the usual figure is the held-out one, not marked
    challenge = sorted((lb for lb in lbs if lb.scheme.startswith("challenge(")), key=lambda lb: bool(lb.rows["designed"].iloc[0]))
    lb4, curve = challenge  # to-s4 tests no design subject; to-curve tests all four subjects
    assert lb4.rows["n_held_out"].iloc[0] == res[2].scores["n_test"].iloc[0]
    assert lb4.rows["held_out_accuracy"].iloc[0] == pytest.approx(res[2].scores["accuracy"].iloc[0])
    assert any("already a held-out one" for n in lb4.notes) and any("marked †" for n in curve.notes)
    for table, marked in ((lb4, False), (curve, True)):
        h, c = display_rows(table)
        assert c[0][h.index("accuracy % (±sd)")].endswith("†") is marked
    lb = next(lb for lb in lbs if lb.scheme == "loso")
    # held out: the folds of s3 and s4 only (mean of their accuracies)
    folds = res[0].scores.set_index("fold")["accuracy"]
    assert lb.rows["held_out_accuracy"].iloc[0] == pytest.approx((folds["subject=s3"] + folds["subject=s4"]) / 2)
    header, cells = display_rows(lb)
    assert "held out %" in header and cells[0][header.index("accuracy % (±sd)")].endswith("†")


def test_design_blocks_give_each_method_its_own_held_out_captures(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"""dataset: {data}
scheme: loso
features: [[test-mean]]
classifiers: [test-logreg, test-forest]
design:
  - {{subjects: [s1, s2], methods: [test-logreg], note: chosen on two subjects}}
  - {{subjects: [s1, s2, s3, s4], methods: [test-forest], note: chosen on every subject}}
""", name="blocks")
    res = run_protocol(p, out=tmp_path / "blocks", progress=False)
    lb = build_leaderboards(load_results([tmp_path / "blocks"]))[0]
    rows = lb.rows.set_index("classifier")
    acc = res.scores.set_index(["classifier", "fold"])["accuracy"]
    # test-logreg: held out on s3 and s4, the mean of those two folds
    assert rows.loc["test-logreg", "held_out_accuracy"] == pytest.approx(
        (acc["test-logreg", "subject=s3"] + acc["test-logreg", "subject=s4"]) / 2)
    # test-forest was designed on every subject: no held-out capture, and its figure is marked
    assert rows.loc["test-forest", "n_held_out"] == 0 and np.isnan(rows.loc["test-forest", "held_out_accuracy"])
    assert bool(rows.loc["test-forest", "designed"]) and bool(rows.loc["test-logreg", "designed"])
    for bad, why in (("- {subjects: [s1]}\n  - {subjects: [s2], methods: [test-forest]}", "each name their methods"),
                     ("- {subjects: [s1], methods: [test-forest]}\n  - {subjects: [s2], methods: [test-forest]}",
                      "in two design blocks")):
        q = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [test-forest]\n"
                                f"design:\n  {bad}\n", name="bad")
        with pytest.raises(ProtocolError, match=why):
            parse_protocol(q.read_text(), q)


def test_evaluation_errors_name_the_evaluation_field(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"""dataset: {data}
features: [[test-mean]]
classifiers: [test-logreg]
evaluations:
  - {{name: a, scheme: loso}}
  - {{name: b, scheme: {{name: kfold, k: 1}}}}
""")
    with pytest.raises(ProtocolError, match=r"p.yaml:7: evaluations\[1\]\.scheme\.k: Input should be greater than or equal to 2"):
        parse_protocol(p.read_text(), p)


# ----------------------------------------------------------------- ledger and --final
def test_the_ledger_counts_looks_and_final_refuses_other_methods(tmp_path):
    data = _data(tmp_path)
    body = f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [{{clf}}]\n"
    one = _protocol(tmp_path, body.format(clf="test-logreg"), name="one")
    two = _protocol(tmp_path, body.format(clf="test-forest"), name="two")
    root = tmp_path / "results"
    run_protocol(one, out=root / "one", progress=False)
    run_protocol(one, out=root / "one", progress=False)  # nothing computed: not a look
    run_protocol(two, out=root / "two", progress=False)
    entries = read_ledger(root / "ledger.jsonl")
    assert len(entries) == 2 and entries[0]["test_set"] == entries[1]["test_set"]
    lb = build_leaderboards(load_results([root / "two"]))[0]
    assert (lb.looks.runs, lb.looks.methods) == (2, 2)
    assert any("scored by 2 run(s), 2 method(s)" in n for n in lb.notes)
    run_protocol(one, out=root / "one", progress=False, final=True)
    run_protocol(one, out=root / "one", progress=False, final=True)  # the same methods again: allowed
    with pytest.raises(FinalRunError, match="already had a final run"):
        run_protocol(two, out=root / "two", progress=False, final=True)
    res = run_protocol(two, out=root / "two", progress=False, final=True, force_final=True)
    assert any(n.startswith("forced:") for n in res.notes)
    last = read_ledger(root / "ledger.jsonl")[-1]
    assert last["final"] and last["forced"]
    # the refused run scored nothing: 2 plain looks + 2 finals of one + the forced final of two
    assert looks(root / "ledger.jsonl", last["test_set"]) == Looks(runs=5, methods=2, finals=3)


def test_final_from_the_command_line_exits_with_a_data_error(tmp_path):
    data = _data(tmp_path)
    body = f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [{{clf}}]\n"
    one = _protocol(tmp_path, body.format(clf="test-logreg"), name="one")
    two = _protocol(tmp_path, body.format(clf="test-forest"), name="two")
    runner = CliRunner()
    assert runner.invoke(main, ["-q", "run", str(one), "--final"]).exit_code == 0
    r = runner.invoke(main, ["-q", "run", str(two), "--final"])
    assert r.exit_code == 3 and "--force-final" in r.output
    assert runner.invoke(main, ["-q", "run", str(two), "--final", "--force-final"]).exit_code == 0
    assert runner.invoke(main, ["run", str(two), "--force-final"]).exit_code == 2


def _append_forever(path: str, started) -> None:
    started.set()
    i = 0
    while True:
        record_look(path, {"test_set": "t", "methods": [f"m{i}"], "pad": "x" * 5000})
        i += 1


def test_the_ledger_survives_a_writer_killed_mid_line(tmp_path):
    path = tmp_path / "ledger.jsonl"
    ctx = mp.get_context("fork")
    started = ctx.Event()
    proc = ctx.Process(target=_append_forever, args=(str(path), started))
    proc.start()
    assert started.wait(SUBPROCESS_HANG_S)
    # killed once it has written some lines, at no chosen moment: most often in the middle of one
    wait_for(lambda: path.is_file() and path.stat().st_size > 20000, "the writer's first lines")
    os.kill(proc.pid, signal.SIGKILL)
    proc.join()
    n = len(read_ledger(path))
    with open(path, "ab") as f:  # a line cut short, as a crash between two writes leaves it
        f.write(b'{"test_set": "t", "meth')
    record_look(path, {"test_set": "t", "methods": ["after"]})
    entries = read_ledger(path)
    assert len(entries) == n + 1 and entries[-1]["methods"] == ["after"]
    assert all(json.loads(line) for line in path.read_text().splitlines()[-1:])


# ----------------------------------------------------------------- audit
def test_audit_runs_the_honest_scheme_and_each_leaky_variant(tmp_path):
    data = _data(tmp_path, frames=(12, 12), per_cell=3)
    p = _protocol(tmp_path, f"""dataset: {data}
scheme: loso
features: [[test-mean]]
classifiers: [{{name: test-logreg, params: {{C: 1.0}}}}]
expected:
  results: [{{features: [test-mean], classifier: test-logreg, value: 50.0, source: made up}}]
  tolerance: 2.0
""", name="aud")
    r = CliRunner().invoke(main, ["-q", "audit", str(p), "--k", "3", "--window-seconds", "0.4", "--tune",
                                  "C=0.0001,1.0", "--out", str(tmp_path / "audit"), "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    rows = pd.DataFrame(doc["rows"])
    assert list(dict.fromkeys(rows["variant"])) == ["honest", "capture-kfold", "window-kfold", "subject-id",
                                                     "tuned-on-test"]
    # every variant's number is its own run's mean over folds, and the inflation is against the honest one
    honest = pd.read_parquet(tmp_path / "audit" / "honest" / "scores.parquet")
    assert rows.loc[rows["variant"] == "honest", "accuracy"].item() == pytest.approx(honest["accuracy"].mean())
    windows = pd.read_parquet(tmp_path / "audit" / "window-kfold" / "scores.parquet")
    assert (windows["leakage"].str.contains("windows of one capture")).all()
    assert windows["n_test"].sum() == 4 * 3 * 3 * 3  # 108 captures of 12 frames -> 3 windows of 4 frames each
    row = rows[rows["variant"] == "window-kfold"].iloc[0]
    assert row["inflation_pp"] == pytest.approx(100 * (windows["accuracy"].mean() - honest["accuracy"].mean()))
    tuned = pd.read_parquet(tmp_path / "audit" / "tuned-on-test" / "scores.parquet")
    best = tuned.groupby("classifier")["accuracy"].mean().max()
    assert rows.loc[rows["variant"] == "tuned-on-test", "accuracy"].item() == pytest.approx(best)
    # C = 1.0 is the honest setting: those 4 tasks are the honest variant's, taken from its folder
    shared = tuned[tuned["task_id"].isin(honest["task_id"])]
    assert len(shared) == 4 and (shared["classifier_params"] == honest["classifier_params"].iloc[0]).all()
    manifest = json.loads((tmp_path / "audit" / "tuned-on-test" / "manifest.json").read_text())
    assert manifest["sessions"][-1]["ran"] == 4, manifest["sessions"]
    assert any("4 tasks had finished" in n and "honest" in n for n in manifest["notes"]), manifest["notes"]
    assert not rows["within_tolerance"].any()  # the gestures are easy: every variant is far above a made-up 50 %
    for f in ("audit.md", "audit.html", "audit.png", "audit.svg", "honest/protocol.yaml"):
        assert (tmp_path / "audit" / f).is_file(), f
    assert "capture-kfold % (Δ pp)" in (tmp_path / "audit" / "audit.md").read_text()


def _small_audit_protocol(tmp_path):
    data = _data(tmp_path, frames=(12, 12))
    return _protocol(tmp_path, f"""dataset: {data}
scheme: loso
features: [[test-mean]]
classifiers: [{{name: test-logreg, params: {{C: 1.0}}}}]
""", name="aud")


def test_audit_says_how_many_tasks_each_variant_runs_before_it_starts(tmp_path):
    p = _small_audit_protocol(tmp_path)
    r = CliRunner().invoke(main, ["audit", str(p), "--variant", "honest", "--variant", "capture-kfold",
                                  "--variant", "tuned-on-test", "--k", "3", "--tune", "C=0.1,1.0",
                                  "--out", str(tmp_path / "audit")])
    assert r.exit_code == 0, r.output
    # 4 subjects: honest = LOSO, 4 folds x 1 method; capture-kfold 3 folds x 1; tuned-on-test 4 folds x 2 values of C
    line = next(l for l in r.stderr.splitlines() if l.startswith("audit of aud:"))
    assert ("3 variants, 15 tasks in all: honest 4 (4 folds x 1 method), capture-kfold 3 (3 folds x 1 method), "
            "tuned-on-test 8 (4 folds x 2 methods)") in line
    assert r.stderr.index(line) < r.stderr.index("audit: ")  # before the audit ran (its files listed last)
    help_text = " ".join(CliRunner().invoke(main, ["audit", "--help"]).output.split())
    assert "up to six runs of the protocol's methods" in help_text and "printed before any runs" in help_text


@pytest.mark.parametrize("value", ["nonsense=1,2", "c=1,2"])
def test_audit_refuses_a_tuned_parameter_no_entry_states(tmp_path, value):
    p = _small_audit_protocol(tmp_path)
    r = CliRunner().invoke(main, ["audit", str(p), "--tune", value, "--out", str(tmp_path / "audit")])
    assert r.exit_code == 2, r.output
    name = value.split("=")[0]
    assert f"'{name}' is no parameter of the protocol's classifier or method entries" in r.output
    assert "the parameters it can tune: C" in r.output and "--tune" in r.output
    assert not (tmp_path / "audit").exists()  # refused before anything is written
    with pytest.raises(TouchbenchError, match=f"tune: '{name}' is no parameter.*parameters it can tune: C"):
        from touchbench.engine.audit import audit_protocols
        from touchbench.protocols.loading import load_protocol
        audit_protocols(load_protocol(p), tune={name: [1, 2]})


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "0", "-2"])
def test_audit_refuses_a_window_length_that_is_not_a_finite_positive_number(tmp_path, value):
    p = _small_audit_protocol(tmp_path)
    r = CliRunner().invoke(main, ["audit", str(p), "--window-seconds", value, "--out", str(tmp_path / "audit")])
    assert r.exit_code == 2, r.output
    assert "--window-seconds" in r.output and "a finite number above 0" in r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)
    assert not (tmp_path / "audit").exists()


def test_a_component_a_sensor_refuses_is_left_out_of_that_evaluation_only_and_said(tmp_path):
    if os.environ.get("CI", "").lower() != "true":  # CI installs the deep extra: there a missing torch fails
        pytest.importorskip("torch")
    long = _data(tmp_path, "long.parquet", frames=(12, 12))
    short = _data(tmp_path, "short.parquet", frames=(5, 6))
    cnn = "{name: cnn, params: {L: 10, max_epochs: 1, channels: [2, 2, 2], hidden_units: 4}}"
    p = _protocol(tmp_path, f"""features: [[test-mean]]
classifiers: [test-logreg]
methods: [{cnn}]
evaluations:
  - {{name: long, dataset: {long}, scheme: loso}}
  - {{name: short, dataset: {short}, scheme: loso}}
""", name="both")
    res = run_protocol(p, out=tmp_path / "results" / "both", progress=False)
    # 12-frame captures serve L = 10 windows; 5 or 6 frames cannot (one frame per window at least)
    assert sorted(set(res[0].scores["classifier_name"])) == ["cnn", "test-logreg"]
    assert set(res[1].scores["classifier_name"]) == {"test-logreg"}
    manifest = json.loads((res[1].out / "manifest.json").read_text())
    left = [n for n in manifest["notes"] if n.startswith("left out of evaluation 'short'")]
    assert len(left) == 1 and "L=10 windows need captures of at least 10 frames" in left[0] and "the shortest has 5" in left[0]
    lbs = build_leaderboards(load_results([tmp_path / "results" / "both"]))
    assert [any(n.startswith("left out of evaluation") for n in lb.notes) for lb in lbs] == [False, True]
    # one protocol, one dataset: the refusal stays a refusal, naming the field
    single = _protocol(tmp_path, f"dataset: {short}\nscheme: loso\nmethods: [{cnn}]\n", name="single")
    with pytest.raises(ProtocolError, match=r"methods\[0\].*L=10 windows need captures of at least 10 frames"):
        run_protocol(single, out=tmp_path / "results" / "single", progress=False)


def test_run_some_methods_now_and_the_others_later(tmp_path):
    data = _data(tmp_path)
    p = _protocol(tmp_path, f"""dataset: {data}
scheme: loso
features: [[test-mean]]
classifiers: [test-logreg, {{name: test-forest, params: {{n_estimators: 3}}}}]
""", name="some")
    out = tmp_path / "results" / "some"
    first = run_protocol(p, out=out, progress=False, methods=["test-logreg"])
    assert first.n_ran == 4 and set(first.scores["classifier_name"]) == {"test-logreg"}  # 4 subjects
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(out), "--method", "test-forest"])
    assert r.exit_code == 0, r.output
    both = pd.read_parquet(out / "scores.parquet")
    assert sorted(both.groupby("classifier_name").size().items()) == [("test-forest", 4), ("test-logreg", 4)]
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(out), "--method", "nope"])
    assert r.exit_code != 0 and "'nope' is not a method of some" in r.output and "test-logreg" in r.output
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(out), "--method", "test-logreg", "--final"])
    assert r.exit_code != 0 and "--final reports every method" in r.output


def _cnn_audit_protocol(tmp_path, frames=12, L=5):
    data = _data(tmp_path, frames=(frames, frames), subjects=("s1", "s2", "s3", "s4"), per_cell=5)
    return _protocol(tmp_path, f"""dataset: {data}
scheme: loso
features: [[{{name: raw-window, params: {{frames: {frames}, shorter: pad}}}}]]
classifiers: [{{name: cnn, params: {{L: {L}}}}}]
seed: 0
""", name="cnnaud")


def test_window_variant_of_a_cnn_is_its_first_L_windows_dealt_by_stratified_kfold(tmp_path):
    from touchbench.engine.audit import audit_protocols
    from touchbench.protocols.loading import load_protocol

    # 4 subjects x 3 gestures x 5 = 60 captures of 12 frames; L = 5: windows of floor(12 / 5) = 2 frames, of
    # which a capture has 6; the first 5 are kept: 300 windows, 100 per gesture
    protos, notes = audit_protocols(load_protocol(_cnn_audit_protocol(tmp_path)), k=10,
                                    variants=("honest", "window-kfold"))
    w = protos["window-kfold"]
    assert w.scheme.params == {"k": 10, "frames": 2, "per_capture": 5}
    [m] = w.evaluated_methods()
    assert m.params["L"] == 1 and m.params["validation_by"] == "rows"  # early stopping on windows too
    assert any("windows of 2 frames (floor(12 / L=5), the first 5 of each capture)" in n for n in notes)
    plan = plan_run(w)
    meta = plan.dataset.meta
    assert len(meta) == 300 and sorted(set(meta["window"])) == [0, 1, 2, 3, 4]
    assert (meta.groupby("source_capture").size() == 5).all()
    assert len(plan.tasks) == 10
    src, gesture = meta["source_capture"].to_numpy(), meta["gesture"].to_numpy()
    tested = np.concatenate([t.fold.test for t in plan.tasks])
    assert sorted(tested) == list(range(300))  # every window tested once
    for t in plan.tasks:
        # stratified: 100 windows per gesture over 10 folds -> 10 of each gesture tested, 90 trained on
        assert pd.Series(gesture[t.fold.test]).value_counts().tolist() == [10, 10, 10]
        assert len(t.fold.train) == 270
    # windows of one capture on both sides: a capture's 5 windows cannot all fall in one of 10 folds of 30
    assert all(set(src[t.fold.train]) & set(src[t.fold.test]) for t in plan.tasks)
    # the cheaper run: the same split, its first 2 folds
    cheap, cheap_notes = audit_protocols(load_protocol(_cnn_audit_protocol(tmp_path)), k=10,
                                         variants=("honest", "window-kfold"), window_folds=2)
    cplan = plan_run(cheap["window-kfold"])
    assert [t.fold.name for t in cplan.tasks] == [t.fold.name for t in plan.tasks[:2]]
    for a, b in zip(cplan.tasks, plan.tasks):
        np.testing.assert_array_equal(a.fold.test, b.fold.test)
    assert any("its first 2 folds run" in n for n in cheap_notes)


def test_window_kfold_keeps_the_first_windows_and_runs_the_first_folds():
    ds = random_dataset(subjects=("s1",), gestures=("pat", "rub"), per_cell=2, frames=(10, 10))
    s = make_splitter("window-kfold", k=4, frames=3, per_capture=2, folds=3)
    from touchbench.protocols.schemes.base import DataContext
    notes: list[str] = []
    w = s.prepare(ds, DataContext("d", notes, None, None))
    # 10 frames: windows at 0, 3, 6 (3 of them); the first 2 kept: 4 captures x 2 = 8 windows
    assert len(w) == 8 and w.meta["window"].tolist() == [0, 1] * 4
    assert notes == ["the samples are windows of 3 frames every 3, the first 2 of each capture (from 4 captures: "
                     "8 windows)"]
    folds = s.folds(w.meta)
    assert len(folds) == 3 and not s.tests_each_capture_once()
    with pytest.raises(ValueError, match="folds: 5 runs the first of k=4 folds"):
        make_splitter("window-kfold", k=4, frames=3, folds=5)


def test_window_twins_are_entries_that_one_window_makes_the_same_network():
    from touchbench.engine.audit import window_twins

    cnn = {"name": "cnn", "params": {"L": 30}}
    data = {"classifiers": [cnn,
                            {"name": "cnn", "label": "all", "params": {"L": 30, "test_windows": "all", "vote": "soft"}},
                            {"name": "cnn", "label": "hard", "params": {"L": 30, "test_windows": [0, 3], "vote": "hard",
                                                                        "train_windows": "all"}},
                            {"name": "cnn", "label": "short", "params": {"L": 30, "max_epochs": 5}},
                            {"name": "cnn", "label": "grid", "params": {"L": 30, "vote": {"grid": ["soft", "hard"]}}}]}
    assert window_twins(data) == {"all": "cnn", "hard": "cnn"}
    assert data["classifiers"][1]["params"]["L"] == 30  # the protocol's data are left as they were
    assert window_twins({"classifiers": [{"name": "cnn", "params": {"L": 3}}, {"name": "cnn", "params": {"L": 9}}]}) == {}


def test_with_one_window_the_windows_tested_and_their_vote_do_not_change_the_cnn():
    pytest.importorskip("torch")
    from touchbench.classifiers.cnn import HaartCNNClassifier

    rng = np.random.default_rng(3)
    X, y = rng.normal(size=(40, 3 * 2 * 2)), np.repeat(["a", "b"], 20)
    kw = dict(grid=(2, 2), L=1, max_epochs=2, channels=(2, 2, 2), hidden_units=4, random_state=5)
    one = HaartCNNClassifier(**kw).fit(X, y).predict_proba(X)
    for other in (dict(test_windows="all", vote="hard", train_windows="all"), dict(test_windows=[0], vote="soft")):
        np.testing.assert_array_equal(HaartCNNClassifier(**kw, **other).fit(X, y).predict_proba(X), one)


def test_the_window_variant_runs_a_twin_once_and_reports_it_for_both(tmp_path):
    from touchbench.engine.audit import audit_protocols, run_audit
    from touchbench.protocols.loading import load_protocol

    p = _cnn_audit_protocol(tmp_path)
    cheap = "max_epochs: 1, channels: [4, 8, 8], hidden_units: 16"
    p.write_text(p.read_text().replace(
        "classifiers: [{name: cnn, params: {L: 5}}]",
        f"classifiers: [{{name: cnn, params: {{L: 5, {cheap}}}}}, "
        f"{{name: cnn, label: cnn-all-windows, params: {{L: 5, test_windows: all, vote: soft, {cheap}}}}}]"))
    protos, notes = audit_protocols(load_protocol(p), k=10, variants=("honest", "window-kfold"), window_folds=2)
    assert [m.label for m in protos["window-kfold"].evaluated_methods()] == ["cnn"]
    assert [m.label for m in protos["honest"].evaluated_methods()] == ["cnn", "cnn-all-windows"]
    assert any("cnn-all-windows is the same method as cnn" in n for n in notes)
    a = run_audit(load_protocol(p), tmp_path / "audit", k=10, variants=("honest", "window-kfold"), window_folds=2)
    windows = pd.read_parquet(tmp_path / "audit" / "window-kfold" / "scores.parquet")
    # one network, 2 of 10 folds of 30 of the 300 windows
    assert len(windows) == 2 and set(windows["classifier"]) == {"cnn"} and (windows["n_test"] == 30).all()
    # raw-window's frames differ (12 -> 2), yet the window variant's rows are the honest methods'
    assert sorted(set(a.table["method"])) == ["captures(frames=12) / cnn", "captures(frames=12) / cnn-all-windows"]
    t = a.table.set_index(["method", "variant"])["accuracy"]
    for method in ("captures(frames=12) / cnn", "captures(frames=12) / cnn-all-windows"):
        assert t[(method, "window-kfold")] == pytest.approx(windows["accuracy"].mean())
    honest = pd.read_parquet(tmp_path / "audit" / "honest" / "scores.parquet")
    assert sorted(set(honest["classifier"])) == ["cnn", "cnn-all-windows"]  # both run where they differ
