"""The staged run path: an evaluation's training side, methods chosen by label, seeds from content.

Every expected count is worked out from the datasets built here (``random_dataset``: ``per_cell``
captures per subject and gesture, three gestures), never read from the code's own output.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli as main
from touchbench.datasets.model import TouchDataset
from touchbench.deploy.model import TrainedModel
from touchbench.engine import run_protocol
from touchbench.engine.planning import plan_run, prepare_evaluation, training_side
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol

GESTURES = 3


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _protocol(tmp_path: Path, body: str, name: str = "p") -> Path:
    p = tmp_path / f"{name}.yaml"
    p.write_text(f"name: {name}\n" + body)
    return p


def _cross_dataset(tmp_path: Path) -> tuple[Path, Path, Path]:
    train, test = tmp_path / "train.parquet", tmp_path / "test.parquet"
    random_dataset(subjects=("a1", "a2", "a3"), per_cell=2, seed=1).to_parquet(train)
    random_dataset(subjects=("b1",), per_cell=3, seed=2).to_parquet(test)
    p = _protocol(tmp_path, f"dataset: {train}\nscheme: {{name: cross-dataset, test: {test}}}\n"
                            "features: [[test-mean]]\nclassifiers: [test-logreg]\n")
    return p, train, test


def test_train_on_a_transfer_fits_the_training_dataset_alone(tmp_path):
    p, train, test = _cross_dataset(tmp_path)
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    out = tmp_path / "model.joblib"
    r = CliRunner().invoke(main, ["train", str(p), "--out", str(out)], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    manifest = json.loads(Path(str(out) + ".json").read_text())
    assert manifest["dataset"]["n_captures"] == 3 * GESTURES * 2  # the training dataset: 3 subjects
    test_ds = TouchDataset.from_parquet(test)
    model = TrainedModel.load(out, trust=True)  # test-only components: not on the list read without trust
    got = model.predict(test_ds.captures)
    accuracy = float(np.mean(got == test_ds.meta["gesture"].astype(str).to_numpy()))
    assert accuracy == pytest.approx(float(res.scores["accuracy"].iloc[0]))  # the run's one fold


def test_training_side_leaves_out_captures_that_are_only_tested(tmp_path):
    p, _, _ = _cross_dataset(tmp_path)
    prepared = prepare_evaluation(parse_protocol(p.read_text(), p))
    side = training_side(prepared)
    assert len(prepared.dataset) == 3 * GESTURES * 2 + 1 * GESTURES * 3
    assert set(prepared.dataset.meta["origin"].to_numpy()[side]) == {"train"} and len(side) == 18
    data = tmp_path / "one.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=1).to_parquet(data)
    loso = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n",
                     "loso")
    assert len(training_side(prepare_evaluation(parse_protocol(loso.read_text(), loso)))) == 3 * GESTURES


def _two_methods(tmp_path: Path) -> Path:
    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=1).to_parquet(data)
    return _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                               "classifiers: [test-logreg, {name: test-forest, label: forest}]\n")


def _run_json(p: Path, out: Path, *args: str) -> dict:
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(out), "--json", *args], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_run_method_counts_only_the_selected_methods_tasks(tmp_path):
    p, out = _two_methods(tmp_path), tmp_path / "out"
    first = _run_json(p, out, "--method", "forest")
    assert first["tasks"] == {"total": 3, "ran": 3, "skipped": 0, "failed": 0}  # 3 subjects, one method
    second = _run_json(p, out, "--method", "test-logreg")  # the forest's 3 finished tasks are not this run's
    assert second["tasks"] == {"total": 3, "ran": 3, "skipped": 0, "failed": 0}
    again = _run_json(p, out, "--method", "forest")
    assert again["tasks"] == {"total": 3, "ran": 0, "skipped": 3, "failed": 0}
    assert len(pd.read_parquet(out / "scores.parquet")) == 6  # the tables hold both methods


def test_run_method_counts_only_the_selected_methods_failures(tmp_path):
    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=1).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                            "classifiers: [test-logreg, test-fail]\n")
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["run", str(p), "--out", str(out), "--method", "test-fail"])
    assert r.exit_code == 1  # its 3 tasks failed
    for _ in range(2):  # the other method's run, then its rerun with nothing to do: no failure of theirs
        fine = _run_json(p, out, "--method", "test-logreg")
        assert fine["tasks"]["failed"] == 0 and fine["tasks"]["total"] == 3
    assert (pd.read_parquet(out / "scores.parquet")["status"] == "failed").sum() == 3  # still in the tables


def _forest(tmp_path: Path, label: str, name: str) -> Path:
    data = tmp_path / "d.parquet"
    if not data.exists():
        random_dataset(subjects=("s1", "s2", "s3"), per_cell=2).to_parquet(data)
    return _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                               f"classifiers: [{{name: test-forest, label: {label}}}]\n", name)


def test_renaming_a_label_changes_no_seed_and_no_stored_result(tmp_path):
    before = plan_run(parse_protocol(_forest(tmp_path, "a", "p").read_text(), tmp_path / "p.yaml"))
    res_a = run_protocol(tmp_path / "p.yaml", out=tmp_path / "out", progress=False)
    renamed = _forest(tmp_path, "b", "p")
    after = plan_run(parse_protocol(renamed.read_text(), renamed))
    assert [t.seed for t in after.tasks] == [t.seed for t in before.tasks]
    assert after.task_ids == before.task_ids
    res_b = run_protocol(renamed, out=tmp_path / "out", progress=False)
    assert res_b.n_ran == 0  # nothing recomputed ...
    assert set(res_b.scores["classifier"]) == {"b"}  # ... and the tables carry the new name
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert set(preds["classifier"]) == {"b"}
    fresh = run_protocol(renamed, out=tmp_path / "fresh", progress=False)  # the same method, anew
    np.testing.assert_array_equal(fresh.scores["accuracy"].to_numpy(), res_a.scores["accuracy"].to_numpy())
    np.testing.assert_array_equal(fresh.scores["seed"].to_numpy(), res_a.scores["seed"].to_numpy())


def test_a_named_method_is_reported_by_its_own_feature_sets(tmp_path):
    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2"), per_cell=1, frames=(60, 60)).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nmethods: [touch-et-fast]\n")
    (method,) = parse_protocol(p.read_text(), p).evaluated_methods()
    assert method.features_label == "touch-rhythm" and method.label == "touch-et-fast"
    p2 = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[{{name: raw-window, params: {{frames: 60}}}}]]\n"
                            "classifiers: [touch-et-fast]\n",
                   "p2")
    (same,) = parse_protocol(p2.read_text(), p2).evaluated_methods()
    assert same.key == method.key and same.features_label == "touch-rhythm"


def test_every_report_names_a_named_method_and_its_own_feature_sets(tmp_path):
    from touchbench.reports.leaderboard import build_leaderboards
    from touchbench.reports.rendering import display_rows, to_markdown
    from touchbench.reports.results import load_results

    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2"), per_cell=2, frames=(60, 60)).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\n"
                            "methods: [touch-et-fast, {name: minirocket, params: {n_kernels: 84}}]\n")
    run_protocol(p, out=tmp_path / "out", progress=False)
    (lb,) = build_leaderboards(load_results([tmp_path / "out"]))
    header, cells = display_rows(lb)
    named = {row[header.index("method")]: row[header.index("features")] for row in cells}
    assert named == {"touch-et-fast": "touch-rhythm", "minirocket": "captures"}
    text = to_markdown([lb])
    assert "raw-window" not in text
    for mid in lb.rows["method_id"]:
        assert str(mid) not in text
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert set(preds["features"]) == {"touch-rhythm", "captures"}


def test_an_expected_result_finds_its_method_by_the_combination_as_written(tmp_path):
    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2"), per_cell=2, frames=(24, 24)).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\n"
                            "features: [[{name: raw-window, params: {frames: 24}}]]\n"
                            "classifiers: [{name: minirocket, params: {n_kernels: 84}}]\n"
                            "expected:\n  results:\n    - {features: [raw-window], classifier: minirocket, value: 50}\n")
    proto = parse_protocol(p.read_text(), p)
    assert proto.features_label_of(["raw-window"]) == "captures(frames=24)"
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    (row,) = res.expected
    assert row["n_folds"] == 2  # both subjects' folds were found under the method's own name
    assert row["features"] == "captures(frames=24)"  # and the comparison names it so
    assert row["observed"] == pytest.approx(100 * float(res.scores["accuracy"].mean()))


def test_a_feature_set_that_rejects_its_parameters_with_the_sensor_is_refused_at_its_field(tmp_path, monkeypatch):
    from touchbench.engine import planning
    from touchbench.protocols.errors import ProtocolError

    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2"), per_cell=1).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: loso\nfeatures: [[test-mean, test-centered]]\n"
                            "classifiers: [test-logreg]\n")
    original = planning.make_feature_set

    def build(name, params, sensor):
        if name == "test-centered":
            raise ValueError("no such setting for this sensor")
        return original(name, params, sensor)

    monkeypatch.setattr(planning, "make_feature_set", build)
    with pytest.raises(ProtocolError, match=r"features\[0\]\[1\]: feature set 'test-centered' rejects \{\}: "
                                            r"ValueError: no such setting for this sensor"):
        plan_run(parse_protocol(p.read_text(), p))


# ------------------------------------------------------- classes a fold never trains on
def _rows(cells):
    return [{"subject": s, "gesture": g} for s, g, n in cells for _ in range(n)]


def _notes(tmp_path, rows, scheme):
    data = tmp_path / "data.parquet"
    random_dataset(rows=rows).to_parquet(data)
    p = _protocol(tmp_path, f"dataset: {data}\nscheme: {scheme}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    return prepare_evaluation(parse_protocol(p.read_text(), p)).notes


@pytest.mark.parametrize("scheme", ["loso", "{name: kfold, k: 3}", "{name: kfold, k: 3, grouped: true}"])
def test_a_class_with_one_capture_gets_a_note_under_every_scheme(tmp_path, scheme):
    # 3 subjects x (pat, rub) x 2 captures, and one capture of 'lonely' (s1): 13 captures, each tested once;
    # the fold that tests 'lonely' trains without it, whatever the scheme
    rows = _rows([(s, g, 2) for s in ("s1", "s2", "s3") for g in ("pat", "rub")] + [("s1", "lonely", 1)])
    notes = [n for n in _notes(tmp_path, rows, scheme) if n.startswith("class(es)")]
    assert notes == ["class(es) 'lonely' (1 capture) tested in a fold that trains on none of their captures: "
                     "those 1 of 13 test captures cannot be labelled right"]


@pytest.mark.parametrize("scheme", ["loso", "{name: kfold, k: 2}"])
def test_classes_that_all_have_one_capture_are_said_to_score_zero(tmp_path, scheme):
    rows = _rows([("s1", "pat", 1), ("s2", "rub", 1), ("s3", "stroke", 1), ("s4", "tickle", 1)])
    notes = [n for n in _notes(tmp_path, rows, scheme) if n.startswith("class(es)")]
    assert notes == ["class(es) 'pat' (1 capture), 'rub' (1 capture), 'stroke' (1 capture), 'tickle' (1 capture) "
                     "tested in a fold that trains on none of their captures: those 4 of 4 test captures cannot be "
                     "labelled right; that is every test capture: accuracy is 0 % by construction"]
