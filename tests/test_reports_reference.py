"""Reference results: a finished run saved under a name, placed beside another run's methods by
``leaderboard --reference`` only where the test sets have the same content."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol


def _run(tmp_path, out: str, seed: int = 4, classifiers: str = "[test-logreg]"):
    data = tmp_path / f"data-{seed}.parquet"
    if not data.exists():
        random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=seed).to_parquet(data)
    p = parse_protocol(f"name: x\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                       f"classifiers: {classifiers}\nseed: 1\n", tmp_path / "x.yaml")
    run_protocol(p, out=tmp_path / out, progress=False)
    return tmp_path / out


@pytest.fixture
def refs(engine_env, tmp_path, monkeypatch):
    store = tmp_path / "refs"
    monkeypatch.setenv("TOUCHBENCH_REFERENCE_DIR", str(store))
    return store


def _invoke(*args):
    return CliRunner().invoke(cli, list(map(str, args)))


def test_a_reference_is_placed_beside_a_run_on_the_same_test_set(refs, tmp_path):
    saved = _run(tmp_path, "saved", classifiers="[test-logreg, zhou-lda]")
    r = _invoke("reference", "save", saved, "--name", "mine", "--to", refs)
    assert r.exit_code == 0, r.output
    index = json.loads((refs / "mine" / "reference.json").read_text())
    assert index["protocol"] == "x" and index["touchbench_version"] and index["machine"]
    new = _run(tmp_path, "new")  # only test-logreg: zhou-lda comes from the reference
    r = _invoke("leaderboard", new, "--reference", "mine", "--json")
    assert r.exit_code == 0, r.output
    assert "beside reference mine" in r.stderr
    rows = {row["classifier"]: row for row in json.loads(r.stdout)["tables"][0]["rows"]}
    assert set(rows) == {"test-logreg", "test-logreg (reference mine)", "zhou-lda (reference mine)"}
    scores = pd.read_parquet(saved / "scores.parquet")
    lda = scores[scores["classifier"] == "zhou-lda"]["accuracy"].mean()
    assert rows["zhou-lda (reference mine)"]["accuracy"] == pytest.approx(lda)


def test_a_reference_on_other_captures_is_refused(refs, tmp_path):
    _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine", "--to", refs)
    other = _run(tmp_path, "other", seed=5)  # another random dataset: other frames
    r = _invoke("leaderboard", other, "--reference", "mine")
    assert r.exit_code != 0
    assert "none of its 1 test set(s) has the content" in r.output


def test_an_unknown_reference_names_the_saved_ones(refs, tmp_path):
    _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine", "--to", refs)
    r = _invoke("leaderboard", tmp_path / "saved", "--reference", "mines")
    assert r.exit_code != 0 and "did you mean 'mine'" in r.output and "saved: mine" in r.output
    r = _invoke("reference", "list")
    assert r.exit_code == 0 and r.output.startswith("mine")


def test_an_unfinished_run_is_not_saved(refs, tmp_path):
    saved = _run(tmp_path, "saved")
    m = json.loads((saved / "manifest.json").read_text())
    m["finished_at"] = None
    (saved / "manifest.json").write_text(json.dumps(m))
    r = _invoke("reference", "save", saved, "--name", "mine", "--to", refs)
    assert r.exit_code != 0 and "not finished" in r.output
    assert not (refs / "mine").exists()


def test_the_shipped_tiny_reference_is_what_this_code_computes(tmp_path, monkeypatch):
    """A fresh run of the shipped ``tiny`` protocol matches the shipped reference's test set and
    reproduces its accuracies (when it does not, `make reference-results` saves them again)."""
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("TOUCHBENCH_REFERENCE_DIR", raising=False)
    r = _invoke("run", "tiny", "--out", tmp_path / "tiny", "--no-progress")
    assert r.exit_code == 0, r.output
    r = _invoke("leaderboard", tmp_path / "tiny", "--reference", "tiny", "--json")
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)["tables"][0]["rows"]
    mine = {row["classifier"] + "/" + row["features"]: row["accuracy"] for row in rows if "(reference" not in row["classifier"]}
    ref = {row["classifier"].replace(" (reference tiny)", "") + "/" + row["features"]: row["accuracy"]
           for row in rows if "(reference tiny)" in row["classifier"]}
    assert mine and mine == ref
