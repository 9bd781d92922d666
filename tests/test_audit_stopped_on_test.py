"""The audit's stopped-on-test variant: early stopping on the held-out subject, a leak the audit
measures (the CNN given the test fold with its labels, the epoch of its best test accuracy kept)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from touchbench.engine.planning import plan_run
from touchbench.engine.testing import random_dataset
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import load_protocol

torch = pytest.importorskip("torch")

SMALL_CNN = "{L: 3, max_epochs: 4, channels: [4, 8, 8], hidden_units: 16}"


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _protocol(tmp_path: Path, classifiers: str) -> Path:
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=3, frames=(12, 12)).to_parquet(data)
    p = tmp_path / "stop.yaml"
    p.write_text(f"""name: stop
dataset: {data}
scheme: loso
features: [[{{name: raw-window, params: {{frames: 12, shorter: pad}}}}]]
classifiers: {classifiers}
seed: 0
""")
    return p


def test_the_variant_marks_the_methods_that_train_by_epochs_and_only_those(tmp_path):
    from touchbench.engine.audit import audit_protocols

    p = load_protocol(_protocol(tmp_path, f"[{{name: cnn, params: {SMALL_CNN}}}]"))
    protos, _ = audit_protocols(p, variants=("honest", "stopped-on-test"))
    [honest], [stopped] = protos["honest"].evaluated_methods(), protos["stopped-on-test"].evaluated_methods()
    assert not honest.stopped_on_test and honest.leakage == []
    assert stopped.stopped_on_test and stopped.leakage == ["the training epoch chosen by its test accuracy"]
    assert protos["stopped-on-test"].scheme.name == "loso"
    assert stopped.method_id != honest.method_id  # its own tasks and seeds: never mixed with the honest ones
    other = load_protocol(_protocol(tmp_path, "[{name: test-logreg}]"))
    protos, notes = audit_protocols(other, variants=("honest", "stopped-on-test"))
    assert "stopped-on-test" not in protos
    assert any(n.startswith("stopped-on-test: no method that trains by epochs") for n in notes)


def test_stopped_on_test_is_refused_for_an_estimator_that_cannot_stop_on_test(tmp_path):
    p = _protocol(tmp_path, "[{name: test-logreg, stopped_on_test: true}]")
    with pytest.raises(ProtocolError, match="stopped_on_test needs an estimator that stops on test data"):
        plan_run(load_protocol(p))


def test_the_engine_gives_the_test_fold_and_its_labels_to_the_stopped_method(tmp_path):
    from touchbench.engine.audit import run_audit

    p = load_protocol(_protocol(tmp_path, f"[{{name: cnn, params: {SMALL_CNN}}}]"))
    audit = run_audit(p, tmp_path / "audit", variants=("honest", "stopped-on-test"), progress=False)
    scores = pd.read_parquet(tmp_path / "audit" / "stopped-on-test" / "scores.parquet")
    preds = pd.read_parquet(tmp_path / "audit" / "stopped-on-test" / "predictions.parquet")
    assert len(scores) == 3 and (scores["status"] == "ok").all()
    assert scores["leakage"].str.contains("the training epoch chosen by its test accuracy").all()
    # each fold's accuracy is that of its own predictions of the held-out subject (worked out from them)
    by_fold = preds.groupby("fold")["correct"].mean()
    assert np.allclose(scores.set_index("fold")["accuracy"].sort_index(), by_fold.sort_index())
    row = audit.table[audit.table["variant"] == "stopped-on-test"].iloc[0]
    assert row["accuracy"] == pytest.approx(scores["accuracy"].mean()) and row["leaky"]


def test_fit_estimator_hands_the_test_labels_as_the_training_codes(tmp_path):
    from touchbench.methods.fitting import fit_estimator

    rng = np.random.default_rng(0)
    y = np.array(["rub", "pat", "stroke"] * 8)
    X = rng.normal(0, 1, size=(24, 12 * 4))
    for k, name in enumerate(["pat", "rub", "stroke"]):
        X[y == name, k::4] += 2.0
    test = np.arange(24) >= 18
    fitted = fit_estimator("cnn", {"grid": (2, 2), "L": 3, "max_epochs": 5, "channels": (4, 8, 8), "hidden_units": 16},
                           0, X[~test], y[~test], test_set=(X[test], y[test]))
    scores = [h["score"] for h in fitted.estimator.history_]
    # the text labels of the kept network's predictions match the test labels as often as its best epoch said
    assert np.mean(fitted.predict(X[test]) == y[test]) == pytest.approx(max(scores))
    with pytest.raises(Exception, match="cannot stop early on the test data"):
        fit_estimator("test-logreg", {}, 0, X[~test], y[~test], test_set=(X[test], y[test]))
