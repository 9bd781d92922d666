"""The results' vocabulary: scikit-learn scorers named by a protocol, any metadata column as the
target; values recomputed independently from the stored predictions with scikit-learn."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics import f1_score, log_loss, matthews_corrcoef

from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.scoring.metrics import scorer_values
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _protocol(tmp_path, extra="", target="gesture", ds=None):
    data = tmp_path / "data.parquet"
    (ds or random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, extra={"cover": ["fur", "none"]}, seed=1)
     ).to_parquet(data)
    return parse_protocol(f"name: m\ndataset: {data}\ntarget: {target}\nscheme: loso\nfeatures: [[test-mean]]\n"
                          f"classifiers: [test-logreg]\nseed: 2\n{extra}", tmp_path / "m.yaml")


def test_named_scorers_are_computed_from_the_predictions(tmp_path):
    res = run_protocol(_protocol(tmp_path, "metrics: [f1_weighted, matthews_corrcoef, neg_log_loss]"),
                       out=tmp_path / "out", progress=False)
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert res.n_failed == 0
    for _, row in res.scores.iterrows():
        p = preds[preds["task_id"] == row["task_id"]]
        t, y = p["true_label"].to_numpy(), p["predicted_label"].to_numpy()
        assert row["f1_weighted"] == pytest.approx(f1_score(t, y, average="weighted"))
        assert row["matthews_corrcoef"] == pytest.approx(matthews_corrcoef(t, y))
        classes = sorted(c[len("proba_"):] for c in p.columns if c.startswith("proba_"))
        P = p[[f"proba_{c}" for c in classes]].to_numpy()
        assert row["neg_log_loss"] == pytest.approx(-log_loss(t, P, labels=classes))


def test_adding_a_metric_refits_nothing(tmp_path):
    """A metric is computed from the stored predictions: naming one more reuses every task."""
    a = run_protocol(_protocol(tmp_path), out=tmp_path / "out", progress=False)
    b = run_protocol(_protocol(tmp_path, "metrics: [f1_weighted, roc_auc]"), out=tmp_path / "out", progress=False)
    assert b.n_ran == 0 and b.scores["task_id"].tolist() == a.scores["task_id"].tolist()
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    for _, row in b.scores.iterrows():
        p = preds[preds["task_id"] == row["task_id"]]
        assert row["f1_weighted"] == pytest.approx(f1_score(p["true_label"], p["predicted_label"], average="weighted"))
    assert "f1_weighted" in pd.read_parquet(tmp_path / "out" / "scores.parquet")
    # roc_auc is binary only (three gestures here): NaN, and one note says why
    assert b.scores["roc_auc"].isna().all()
    assert [n for n in b.notes if n.startswith("metric roc_auc: not computed for 3 of 3 tasks (ValueError")]


def test_an_unknown_scorer_is_refused_with_the_nearest_name(tmp_path):
    with pytest.raises(ProtocolError) as e:
        _protocol(tmp_path, "metrics: [f1_wieghted]")
    assert "m.yaml:8" in str(e.value) and "unknown metric 'f1_wieghted'" in str(e.value)
    assert "did you mean 'f1_weighted'" in str(e.value)


def test_scorers_without_probabilities_are_nan():
    y = np.array(["a", "b", "a", "b"])
    why: dict[str, str] = {}
    got = scorer_values(["accuracy", "roc_auc"], y, np.array(["a", "b", "b", "b"]), None, why)
    assert got["accuracy"] == 0.75 and np.isnan(got["roc_auc"])
    assert why == {"roc_auc": "it needs class probabilities and the classifier gives none"}
    # binary: the positive class's column; by hand, roc auc of [.9, .2, .6, .3] for b=1: b above a in 0 of 4 pairs
    p = {"a": np.array([0.1, 0.8, 0.4, 0.7]), "b": np.array([0.9, 0.2, 0.6, 0.3])}
    assert scorer_values(["roc_auc"], y, y, p)["roc_auc"] == pytest.approx(0.0)


def test_any_metadata_column_is_a_target(tmp_path):
    res = run_protocol(_protocol(tmp_path, target="cover"), out=tmp_path / "out", progress=False)
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert set(preds["true_label"]) == {"fur", "none"} and (res.scores["target"] == "cover").all()
    gesture = run_protocol(_protocol(tmp_path), out=tmp_path / "g", progress=False)
    assert not set(res.scores["task_id"]) & set(gesture.scores["task_id"])  # the target is in the task's identity


def test_a_target_the_data_lacks_lists_the_columns(tmp_path):
    from touchbench.engine.planning import plan_run

    with pytest.raises(ProtocolError) as e:
        plan_run(_protocol(tmp_path, target="covr"))
    assert "the dataset has no 'covr' column" in str(e.value) and "did you mean 'cover'" in str(e.value)
    assert "its metadata columns: cover, gesture," in str(e.value)


@pytest.mark.parametrize("scheme", ["{name: loso, column: cover}", "{name: kfold, k: 2, grouped: true, group_column: cover}",
                                    "{name: transfer, column: cover}"])
def test_a_target_the_scheme_holds_out_is_refused(tmp_path, scheme):
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2"), per_cell=2, extra={"cover": ["fur", "none"]}, seed=1).to_parquet(data)
    with pytest.raises(ProtocolError) as e:
        parse_protocol(f"name: m\ndataset: {data}\ntarget: cover\nscheme: {scheme}\nfeatures: [[test-mean]]\n"
                       "classifiers: [test-logreg]\n", tmp_path / "m.yaml")
    assert "m.yaml:3: target: target 'cover'" in str(e.value)
    assert "holds out the values of 'cover', so no test capture's class would be in the training data" in str(e.value)


def test_run_json_shows_the_protocol_metrics(tmp_path):
    import json

    from click.testing import CliRunner

    from touchbench.cli.main import cli

    p = _protocol(tmp_path, "metrics: [f1_weighted]")
    p.path.write_text(p.text)
    r = CliRunner().invoke(cli, ["run", str(p.path), "--out", str(tmp_path / "out"), "--json"])
    assert r.exit_code == 0, r.output
    (method,) = json.loads(r.stdout)["methods"]
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    by_hand = [f1_score(g["true_label"], g["predicted_label"], average="weighted") for _, g in preds.groupby("task_id")]
    assert method["f1_weighted_mean"] == pytest.approx(np.mean(by_hand))


def test_a_scores_row_is_defined_once():
    from touchbench.results.store import MEASURED, PLAN_COLUMNS, SCORE_COLUMNS, task_row

    # every column of the table is the run's stamp, planned or measured, and nothing else
    assert set(SCORE_COLUMNS) == {"run_id", "protocol_hash"} | set(PLAN_COLUMNS) | set(MEASURED)
    row = task_row({c: c for c in PLAN_COLUMNS})
    assert list(row) == [*PLAN_COLUMNS, *MEASURED] and row["status"] == "ok" and row["notes"] == ""
    with pytest.raises(ValueError, match="extra \\['colour'\\], missing \\['task_id'\\]"):
        task_row({**{c: c for c in PLAN_COLUMNS if c != "task_id"}, "colour": 1})
