"""Evaluations with a single test set run several seeds of every method (``repetitions``, default
:data:`touchbench.protocols.schemes.DEFAULT_SEEDS` for such a scheme): the same folds in every
repetition, another seed for every task; ``touchbench train`` without ``--fold`` on such an
evaluation fits the run's repetition-0 model."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.engine import run_protocol
from touchbench.engine.planning import plan_run
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol

BASE = """\
name: seeds
dataset: {data}
scheme: {scheme}
features: [[msd]]
classifiers:
  - {{name: gaus-rf, params: {{n_estimators: 15}}, label: rf15}}
seed: 4
"""
CHALLENGE = "{name: challenge, test_subjects: [s4]}"


@pytest.fixture()
def data(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    ds = random_dataset(subjects=("s1", "s2", "s3", "s4"), gestures=("pat", "rub", "stroke"), per_cell=3,
                        frames=(20, 24), seed=2)
    path = tmp_path / "data.parquet"
    ds.to_parquet(path)
    return ds, path


@pytest.mark.parametrize("scheme, extra, expected", [
    (CHALLENGE, "", 5),  # a single test set, repetitions unsaid: five seeds
    ("{name: transfer, column: subject, groups: [s1, s2]}", "", 5),
    ("{name: cross-dataset, test: {name: 'scene:tiny'}}", "", 5),
    (CHALLENGE, "repetitions: 2\n", 2),  # said: as said
    (CHALLENGE, "repetitions: 1\n", 1),
    ("loso", "", 1),  # folds that cover the data: one repetition unless said
])
def test_repetitions_default_to_several_seeds_for_a_single_test_set(scheme, extra, expected):
    p = parse_protocol(BASE.format(data="scene:tiny", scheme=scheme) + extra)
    assert p.repetitions == expected


def test_each_evaluation_takes_the_default_of_its_own_scheme():
    text = BASE.format(data="scene:tiny", scheme="loso") + f"""\
evaluations:
  - {{name: cv, scheme: loso}}
  - {{name: split, scheme: {CHALLENGE}}}
  - {{name: split-once, scheme: {CHALLENGE}, repetitions: 1}}
"""
    subs = parse_protocol(text).evaluation_protocols()
    assert [(s.evaluation, s.repetitions) for s in subs] == [("cv", 1), ("split", 5), ("split-once", 1)]
    said = parse_protocol(text + "repetitions: 3\n").evaluation_protocols()  # the protocol's own, said
    assert [s.repetitions for s in said] == [3, 3, 1]


def test_repetitions_keep_the_folds_and_draw_other_seeds(data, tmp_path):
    ds, path = data
    (tmp_path / "p.yaml").write_text(BASE.format(data=path, scheme=CHALLENGE))
    from touchbench.protocols.loading import load_protocol

    plan = plan_run(load_protocol(tmp_path / "p.yaml"), tmp_path / "cache")
    assert [t.repetition for t in plan.tasks] == [0, 1, 2, 3, 4]
    test = np.flatnonzero(ds.meta["subject"].to_numpy() == "s4")
    for t in plan.tasks:  # the one split, by hand: s4 tested, the others trained on
        np.testing.assert_array_equal(t.fold.test, test)
        np.testing.assert_array_equal(t.fold.train, np.setdiff1d(np.arange(len(ds)), test))
    assert len({t.seed for t in plan.tasks}) == 5


def test_train_without_fold_reproduces_the_runs_first_repetition(data, tmp_path):
    ds, path = data
    proto = tmp_path / "p.yaml"
    proto.write_text(BASE.format(data=path, scheme=CHALLENGE) + "repetitions: 3\n")
    run = run_protocol(proto, tmp_path / "results")
    assert run.n_failed == 0
    scores = pd.read_parquet(tmp_path / "results" / "scores.parquet")
    preds = pd.read_parquet(tmp_path / "results" / "predictions.parquet")
    assert scores["seed"].nunique() == 3
    res = CliRunner().invoke(cli, ["train", str(proto), "-m", "msd/rf15", "-o", str(tmp_path / "m.joblib")],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    s4 = ds.subset(np.flatnonzero(ds.meta["subject"].to_numpy() == "s4"))
    s4.to_parquet(tmp_path / "s4.parquet")
    res = CliRunner().invoke(cli, ["predict", str(tmp_path / "m.joblib"), str(tmp_path / "s4.parquet"),
                                   "--out", str(tmp_path / "p.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    ours = pd.read_csv(tmp_path / "p.csv").set_index("capture_id")
    first = preds[preds["repetition"] == 0].set_index("capture_id")
    assert len(ours) == len(first) == 9
    truth = s4.meta.set_index("capture_id").loc[ours.index, "gesture"].astype(str)
    accuracy = float((ours["predicted_label"].astype(str) == truth).mean())
    assert accuracy == float(scores.loc[scores["repetition"] == 0, "accuracy"].iloc[0])
    for c in ("pat", "rub", "stroke"):  # the same model: the same probabilities, not only the same labels
        np.testing.assert_allclose(ours.loc[first.index, f"proba_{c}"], first[f"proba_{c}"], rtol=0, atol=1e-12)


def test_train_without_fold_reproduces_a_transfers_first_repetition(data, tmp_path):
    """The same on a cross-dataset transfer: trained on one dataset, tested on another."""
    ds, _ = data
    subject = ds.meta["subject"].to_numpy()
    ds.subset(np.flatnonzero(subject != "s4")).to_parquet(tmp_path / "train.parquet")
    s4 = ds.subset(np.flatnonzero(subject == "s4"))
    s4.to_parquet(tmp_path / "test.parquet")
    proto = tmp_path / "t.yaml"
    proto.write_text(BASE.format(data=tmp_path / "train.parquet",
                                 scheme=f"{{name: cross-dataset, test: {tmp_path / 'test.parquet'}}}") + "repetitions: 2\n")
    run_protocol(proto, tmp_path / "results")
    scores = pd.read_parquet(tmp_path / "results" / "scores.parquet")
    preds = pd.read_parquet(tmp_path / "results" / "predictions.parquet")
    res = CliRunner().invoke(cli, ["train", str(proto), "-m", "msd/rf15", "-o", str(tmp_path / "m.joblib")],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["predict", str(tmp_path / "m.joblib"), str(tmp_path / "test.parquet"),
                                   "--out", str(tmp_path / "p.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    ours = pd.read_csv(tmp_path / "p.csv").set_index("capture_id")
    first = preds[preds["repetition"] == 0].assign(capture_id=lambda p: p["capture_id"].str.removeprefix("test:"))
    first = first.set_index("capture_id")
    assert len(ours) == len(first) == 9
    truth = s4.meta.set_index("capture_id").loc[ours.index, "gesture"].astype(str)
    assert float((ours["predicted_label"].astype(str) == truth).mean()) == float(
        scores.loc[scores["repetition"] == 0, "accuracy"].iloc[0])
    for c in ("pat", "rub", "stroke"):
        np.testing.assert_allclose(ours.loc[first.index, f"proba_{c}"], first[f"proba_{c}"], rtol=0, atol=1e-12)
