"""``touchbench export --format tsml``: tsml-eval's results files, read back by tsml-eval's own
loader (installed by ``make setup``; CI fails, not skips, without it) and checked against our
predictions."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from conftest import _missing

from touchbench.cli.main import cli
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol


@pytest.fixture
def run_dir(engine_env, tmp_path):
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=4).to_parquet(data)
    p = parse_protocol(f"name: x\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                       "classifiers: [test-logreg, zhou-lda]\nseed: 1\n", tmp_path / "x.yaml")
    run_protocol(p, out=tmp_path / "run", progress=False)
    return tmp_path / "run"


def _loader():
    try:
        from tsml_eval.evaluation.storage import load_classifier_results
    except ImportError:
        _missing("tsml-eval is not installed (make setup installs it: pip install --no-deps tsml-eval)")
    return load_classifier_results


def test_tsml_export_is_read_back_by_tsml_eval(run_dir, tmp_path):
    load = _loader()
    r = CliRunner().invoke(cli, ["export", str(run_dir), "--format", "tsml", "--out", str(tmp_path / "tsml"), "--json"])
    assert r.exit_code == 0, r.output
    files = sorted(json.loads(r.stdout)["files"])
    preds = pd.read_parquet(run_dir / "predictions.parquet")
    scores = pd.read_parquet(run_dir / "scores.parquet")
    # 2 methods x 3 subjects left out = 6 resamples
    assert len(files) == 6
    assert {f.split("/tsml/")[1].split("/Predictions/")[0] for f in files} == {"test-mean-test-logreg",
                                                                                "test-mean-zhou-lda"}
    classes = sorted(set(preds["true_label"]))
    for f in files:
        res = load(f)
        fold = res.description.split("fold ")[1].split(" repetition")[0]
        method = "test-logreg" if "logreg" in f else "zhou-lda"
        ours = preds[(preds["fold"] == fold) & (preds["classifier"] == method)]
        assert res.split == "TEST" and res.n_classes == len(classes) and res.time_unit == "milliseconds"
        assert [classes[int(i)] for i in res.class_labels] == ours["true_label"].tolist()
        assert [classes[int(i)] for i in res.predictions] == ours["predicted_label"].tolist()
        row = scores[(scores["fold"] == fold) & (scores["classifier"] == method)].iloc[0]
        assert res.accuracy == pytest.approx(row["accuracy"])
        assert np.allclose(res.probabilities.sum(axis=1), 1.0)
        if method == "test-logreg":  # its probabilities, in the sorted class order
            assert np.allclose(res.probabilities, ours[[f"proba_{c}" for c in classes]].to_numpy())


def test_tables_of_one_dataset_and_scheme_are_separate_problems(engine_env, tmp_path):
    """Two targets on the same data and scheme: two problems, no file written over another."""
    load = _loader()
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, extra={"cover": ["fur", "none"]}, seed=4).to_parquet(data)
    for target in ("gesture", "cover"):
        p = parse_protocol(f"name: {target}\ndataset: {data}\ntarget: {target}\nscheme: loso\n"
                           "features: [[test-mean]]\nclassifiers: [test-logreg]\nseed: 1\n", tmp_path / f"{target}.yaml")
        run_protocol(p, out=tmp_path / "runs" / target, progress=False)
    r = CliRunner().invoke(cli, ["export", str(tmp_path / "runs"), "--out", str(tmp_path / "tsml"), "--json"])
    assert r.exit_code == 0, r.output
    files = json.loads(r.stdout)["files"]
    assert len(files) == len(set(files)) == 2 * 3  # 2 tables x 3 subjects left out
    problems = {f.split("/Predictions/")[1].split("/")[0] for f in files}
    assert problems == {"data-loso", "data-loso-target-cover"}
    for f in files:  # each file holds its own table's classes
        res = load(f)
        assert res.n_classes == (2 if "target-cover" in f else 3)
