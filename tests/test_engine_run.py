"""The run engine end to end on small datasets built here.

Reports and their columns, metrics recomputed independently from the
predictions, --jobs 1 vs 2 identical predictions, rerun = no-op, resume
after an interruption with the same final numbers, failed tasks as rows,
--force, the feature cache, fold-only fitting, groups passed to fit.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner
from sklearn.metrics import balanced_accuracy_score, f1_score

from touchbench.core.errors import TouchbenchError
from touchbench.engine import run_protocol
from touchbench.engine import testing as tk
from touchbench.engine.tasks import LATENCY_MAX_CALLS, LATENCY_MIN_CALLS
from touchbench.engine.testing import random_dataset, register_test_components
from touchbench.protocols.loading import parse_protocol

PROTOCOL = """\
name: small
dataset: {data}
scheme: {scheme}
features:
  - [test-mean]
  - [test-centered]
  - [test-mean, test-centered]
classifiers:
{classifiers}
seed: 7
"""

SCORE_COLUMNS = [
    "run_id", "protocol", "dataset", "dataset_hash", "scheme", "fold", "features", "classifier",
    "classifier_params", "seed", "n_train", "n_test", "accuracy", "balanced_accuracy", "macro_f1",
    "feature_seconds_per_capture", "fit_seconds", "predict_seconds", "latency_ms", "status", "error", "notes",
]
PREDICTION_COLUMNS = ["run_id", "task_id", "capture_id", "subject", "true_label", "predicted_label"]


@pytest.fixture(autouse=True)
def env(engine_env):
    """A private cache and working folder, with the test-only components."""
    yield


def protocol(tmp_path: Path, scheme="loso", classifiers=("test-logreg",), ds=None, **fmt):
    data = tmp_path / "data.parquet"
    if not data.exists():
        (ds or random_dataset(subjects=("s1", "s2", "s3", "s4"), per_cell=2)).to_parquet(data)
    clf = "".join(f"  - {c}\n" for c in classifiers)
    return parse_protocol(PROTOCOL.format(data=data, scheme=scheme, classifiers=clf, **fmt), tmp_path / "small.yaml")


def test_reports_exist_with_their_columns(tmp_path):
    p = protocol(tmp_path, classifiers=("test-logreg", "{name: test-forest, params: {n_estimators: 5}}"))
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    out = tmp_path / "out"
    scores = pd.read_parquet(out / "scores.parquet")
    preds = pd.read_parquet(out / "predictions.parquet")
    conf = pd.read_parquet(out / "confusion.parquet")
    manifest = json.loads((out / "manifest.json").read_text())
    assert res.n_tasks == 4 * 3 * 2 == len(scores) and (scores["status"] == "ok").all()
    assert set(SCORE_COLUMNS) <= set(scores.columns)
    assert set(PREDICTION_COLUMNS) <= set(preds.columns)
    assert {"proba_pat", "proba_rub", "proba_stroke"} <= set(preds.columns)  # logistic regression has probabilities
    assert np.allclose(preds[["proba_pat", "proba_rub", "proba_stroke"]].sum(axis=1), 1.0)
    assert len(preds) == 24 * 6  # every capture once per (combination, classifier)
    # latency is measured once per method and run (in its first task), and reused for every fold
    measured = scores.groupby(["features", "classifier"])["latency_ms"].count()
    assert (measured == 1).all() and (scores["latency_ms"].dropna() > 0).all() and (scores["fit_seconds"] >= 0).all()
    assert scores["run_id"].nunique() == 1 and scores["protocol"].iloc[0] == "small"
    assert json.loads(scores.loc[scores["classifier"] == "test-forest", "classifier_params"].iloc[0]) == {"n_estimators": 5}
    for key in ("touchbench_version", "git", "packages", "platform", "protocol", "dataset", "started_at", "finished_at"):
        assert key in manifest
    assert manifest["protocol"]["text"] == p.text and manifest["platform"]["cpu_count"] == os.cpu_count()
    assert manifest["dataset"]["hash"] == scores["dataset_hash"].iloc[0]
    # per task: each configuration's counts sum to its test captures over the folds, once
    one = conf[(conf["features"] == "test-mean") & (conf["classifier"] == "test-logreg")]
    assert conf["task_id"].notna().all() and one["count"].sum() == 24 and conf["count"].sum() == len(preds)
    # pooled over the folds, in its own file: one configuration sums to the number of captures
    pooled_all = pd.read_parquet(out / "confusion_pooled.parquet")
    assert "task_id" not in pooled_all and pooled_all["count"].sum() == len(preds)
    pooled = pooled_all[(pooled_all["features"] == "test-mean") & (pooled_all["classifier"] == "test-logreg")]
    assert pooled["count"].sum() == 24
    # every results file says its layout
    assert pq.read_schema(out / "scores.parquet").metadata[b"touchbench_results_schema"] == b"3"


@pytest.mark.filterwarnings("ignore:y_pred contains classes not in y_true")
def test_metrics_match_sklearn_on_the_predictions(tmp_path):
    ds = random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=3)
    # make the task hard enough to have errors: shuffle labels of half the captures
    rng = np.random.default_rng(0)
    meta = ds.meta.copy()
    flip = rng.choice(len(meta), size=len(meta) // 2, replace=False)
    meta.loc[flip, "gesture"] = rng.permutation(meta.loc[flip, "gesture"].to_numpy())
    ds = type(ds)(ds.name, ds.captures, meta, ds.sensor)
    res = run_protocol(protocol(tmp_path, ds=ds), out=tmp_path / "out", progress=False)
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    for _, row in res.scores.iterrows():
        p = preds[preds["task_id"] == row["task_id"]]
        assert row["n_test"] == len(p)
        assert row["accuracy"] == pytest.approx((p["true_label"] == p["predicted_label"]).mean())
        assert row["balanced_accuracy"] == pytest.approx(balanced_accuracy_score(p["true_label"], p["predicted_label"]))
        labels = sorted(set(p["true_label"]) | set(p["predicted_label"]))
        assert row["macro_f1"] == pytest.approx(f1_score(p["true_label"], p["predicted_label"], average="macro", labels=labels, zero_division=0))
    assert (res.scores["accuracy"] < 1).any()


def test_rerun_is_a_noop_and_force_recomputes(tmp_path):
    p = protocol(tmp_path)
    first = run_protocol(p, out=tmp_path / "out", progress=False)
    before = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    def stamps():  # every file but the lock, which each run takes (and says who holds it there)
        return {f: f.stat().st_mtime_ns for f in (tmp_path / "out").rglob("*")
                if f.is_file() and f.name != ".touchbench.lock"}

    before_stamps = stamps()
    again = run_protocol(p, out=tmp_path / "out", progress=False)
    assert again.noop and again.n_ran == 0 and again.n_skipped == first.n_tasks
    assert stamps() == before_stamps
    forced = run_protocol(p, out=tmp_path / "out", force=True, progress=False)
    assert forced.n_ran == first.n_tasks and not forced.noop
    after = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    pd.testing.assert_frame_equal(before, after, check_exact=True)  # recomputed, bit-identical
    assert len(json.loads((tmp_path / "out" / "manifest.json").read_text())["sessions"]) == 2


def test_jobs_1_and_2_give_identical_predictions(tmp_path):
    p = protocol(tmp_path, scheme="{name: kfold, k: 3}",
                 classifiers=("test-logreg", "{name: test-forest, params: {n_estimators: 4}}"))
    one = run_protocol(p, out=tmp_path / "j1", jobs=1, progress=False)
    two = run_protocol(p, out=tmp_path / "j2", jobs=2, progress=False, worker_setup=register_test_components)
    a = pd.read_parquet(tmp_path / "j1" / "predictions.parquet")
    b = pd.read_parquet(tmp_path / "j2" / "predictions.parquet")
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    cols = ["task_id", "fold", "features", "classifier", "seed", "accuracy", "balanced_accuracy", "macro_f1"]
    pd.testing.assert_frame_equal(one.scores[cols], two.scores[cols], check_exact=True)


def test_resume_after_interruption_gives_the_same_final_numbers(tmp_path):
    p = protocol(tmp_path, classifiers=("test-interrupt",))
    reference = run_protocol(p, out=tmp_path / "ref", progress=False)
    tk.INTERRUPT["after"] = 5  # Ctrl-C during the 6th task
    with pytest.raises(KeyboardInterrupt):
        run_protocol(p, out=tmp_path / "out", progress=False)
    frags = tmp_path / "out" / "fragments"
    assert len(list(frags.glob("*.scores.parquet"))) == 5
    assert not (tmp_path / "out" / "scores.parquet").exists()
    # a kill between the two writes of a task, and a stale temporary file
    stray = next(frags.glob("*.predictions.parquet"))
    (frags / "0123.predictions.parquet").write_bytes(stray.read_bytes())
    tmp = frags / ".x.scores.parquet.tmp"
    tmp.write_bytes(b"half")
    os.utime(tmp, (0, 0))
    resumed = run_protocol(p, out=tmp_path / "out", progress=False)
    assert resumed.n_ran == reference.n_tasks - 5 and resumed.n_skipped == 5
    assert not tmp.exists()
    cols = ["task_id", "accuracy", "balanced_accuracy", "macro_f1", "n_train", "n_test", "seed"]
    pd.testing.assert_frame_equal(resumed.scores[cols], reference.scores[cols], check_exact=True)
    a = pd.read_parquet(tmp_path / "ref" / "predictions.parquet")
    b = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    pd.testing.assert_frame_equal(a, b, check_exact=True)


def test_a_task_finished_in_another_folder_is_taken_not_computed(tmp_path):
    """Another protocol's run of the same tasks (same data, folds, methods, seed) gives its finished
    tasks to a run that names its folder: they are not computed again, a damaged one is, and the
    results equal a run that computed everything, labelled as the new protocol names them."""
    run_protocol(protocol(tmp_path), out=tmp_path / "a", progress=False)  # logreg: 4 folds x 3 feature sets
    frags = tmp_path / "a" / "fragments"
    damaged = sorted(frags.glob("*.predictions.parquet"))[0]
    damaged.write_bytes(damaged.read_bytes()[:-8])  # no longer what its task wrote
    both = ("test-logreg", "{name: test-forest, params: {n_estimators: 4}}")
    other = parse_protocol(protocol(tmp_path, classifiers=both).text.replace("name: small", "name: other"),
                           tmp_path / "other.yaml")
    taken = run_protocol(other, out=tmp_path / "b", progress=False, reuse=[tmp_path / "a"])
    assert taken.n_tasks == 24 and taken.n_ran == 12 + 1  # the forest's 12 and the damaged one
    assert any("11 tasks had finished" in n and str(tmp_path / "a") in n for n in taken.notes)
    fresh = run_protocol(other, out=tmp_path / "c", progress=False)
    assert fresh.n_ran == 24
    cols = ["task_id", "protocol", "features", "classifier", "seed", "n_train", "n_test", "status", "accuracy",
            "balanced_accuracy", "macro_f1"]
    pd.testing.assert_frame_equal(taken.scores[cols], fresh.scores[cols], check_exact=True)
    assert (taken.scores["protocol"] == "other").all()
    a = pd.read_parquet(tmp_path / "b" / "predictions.parquet")
    b = pd.read_parquet(tmp_path / "c" / "predictions.parquet")
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    again = run_protocol(other, out=tmp_path / "d", progress=False, reuse=[tmp_path / "a"], force=True)
    assert again.n_ran == 24  # --force computes every task


def test_failed_task_is_a_row_and_the_run_goes_on(tmp_path):
    p = protocol(tmp_path, classifiers=("test-logreg", "test-fail"))
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    failed = res.scores[res.scores["classifier"] == "test-fail"]
    ok = res.scores[res.scores["classifier"] == "test-logreg"]
    assert len(failed) == 12 and (failed["status"] == "failed").all()
    assert failed["error"].str.startswith("ValueError: deliberate failure").all()
    assert failed["accuracy"].isna().all()
    assert len(ok) == 12 and (ok["status"] == "ok").all()
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert set(preds["classifier"]) == {"test-logreg"}
    assert res.n_failed == 12
    # failed tasks count as finished: a rerun is a no-op, --retry-failed runs them again
    assert run_protocol(p, out=tmp_path / "out", progress=False).noop
    assert run_protocol(p, out=tmp_path / "out", progress=False, retry_failed=True).n_ran == 12


def test_fold_independent_features_are_computed_once_and_cached(tmp_path, monkeypatch):
    calls = []
    original = tk.MeanFrame._transform_one
    monkeypatch.setattr(tk.MeanFrame, "_transform_one", lambda self, c: calls.append(1) or original(self, c))
    p = protocol(tmp_path)
    run_protocol(p, out=tmp_path / "a", progress=False)
    # 24 captures once into the cache, then once per method using test-mean (2
    # combinations): one warm-up + between LATENCY_MIN_CALLS and LATENCY_MAX_CALLS
    # timed calls (as many as the time budget takes), one capture per call
    low, high = 2 * (1 + LATENCY_MIN_CALLS), 2 * (1 + LATENCY_MAX_CALLS)
    assert 24 + low <= len(calls) <= 24 + high
    cache = tmp_path / "cache" / "features"
    entries = sorted(cache.glob("*.json"))
    assert len(entries) == 1  # test-mean only: test-centered is fold-dependent
    calls.clear()
    run_protocol(p, out=tmp_path / "b", progress=False)  # another results folder, same cache
    assert low <= len(calls) <= high  # the matrix came from the cache
    assert sorted(cache.glob("*.json")) == entries


def test_fold_dependent_features_fit_on_the_training_fold_only(tmp_path, monkeypatch):
    seen = []
    original = tk.CenteredMax._fit
    monkeypatch.setattr(tk.CenteredMax, "_fit", lambda self, caps, y=None: seen.append(len(caps)) or original(self, caps, y))
    p = protocol(tmp_path)
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    n_train = set(res.scores["n_train"])
    assert n_train == {18}
    # each fold-dependent fit saw exactly the training fold (latency fits use 2 captures)
    assert set(seen) <= {18, 2} and seen.count(18) == 8  # 4 folds x 2 combinations with test-centered


def test_training_subjects_are_passed_as_groups(tmp_path):
    p = protocol(tmp_path, classifiers=("test-interrupt",))
    tk.InterruptAfter.last_groups = None
    run_protocol(p, out=tmp_path / "out", progress=False)
    assert tk.InterruptAfter.last_groups == ["s1", "s2", "s3"]  # last fold tests s4


def test_seed_changes_randomness_but_rerun_is_identical(tmp_path):
    p = protocol(tmp_path, scheme="{name: kfold, k: 3}", classifiers=("{name: test-forest, params: {n_estimators: 3}}",))
    a = run_protocol(p, out=tmp_path / "a", progress=False)
    b = run_protocol(p, out=tmp_path / "b", progress=False)
    assert a.scores["seed"].tolist() == b.scores["seed"].tolist()
    q = parse_protocol(p.text.replace("seed: 7", "seed: 8"), tmp_path / "small.yaml")
    c = run_protocol(q, out=tmp_path / "c", progress=False)
    assert set(c.scores["seed"]).isdisjoint(a.scores["seed"])
    assert c.run_id != a.run_id


def test_early_scheme_cuts_test_captures(tmp_path):
    p = protocol(tmp_path, scheme="{name: early, base: loso, frames: [1, 4]}")
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert sorted(set(res.scores["early_frames"])) == [1.0, 4.0]
    assert len(res.scores) == 2 * 4 * 3
    summary = res.summary
    assert set(summary["early_frames"]) == {1.0, 4.0}
    # two cached matrices for test-mean: the whole captures (training) and the first 1 and 4 frames
    assert len(list((tmp_path / "cache" / "features").glob("*.json"))) == 3


def test_within_subject_scores_per_subject(tmp_path):
    ds = random_dataset(subjects=("s1", "s2"), per_cell=3)
    p = protocol(tmp_path, ds=ds, scheme="{name: within-subject, k: 3}")
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert set(res.scores["fold_group"]) == {"s1", "s2"}
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    # every model is trained and tested on one subject
    for tid, g in preds.groupby("task_id"):
        assert g["subject"].nunique() == 1


def test_cli_run_and_rerun(tmp_path):
    from touchbench.cli.main import cli

    p = protocol(tmp_path)
    (tmp_path / "small.yaml").write_text(p.text)
    runner = CliRunner()
    r = runner.invoke(cli, ["run", str(tmp_path / "small.yaml"), "--out", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    assert "test-mean+test-centered" in r.output and (tmp_path / "out" / "scores.parquet").is_file()
    r = runner.invoke(cli, ["run", str(tmp_path / "small.yaml"), "--out", str(tmp_path / "out")])
    assert r.exit_code == 0 and "nothing to do" in r.output
    # default results directory: results/<protocol name>/
    r = runner.invoke(cli, ["run", str(tmp_path / "small.yaml")])
    assert r.exit_code == 0 and (tmp_path / "results" / "small" / "scores.parquet").is_file()


def test_repetitions_redraw_the_folds(tmp_path):
    p = protocol(tmp_path, scheme="{name: kfold, k: 2}")
    q = parse_protocol(p.text + "repetitions: 2\n", tmp_path / "small.yaml")
    res = run_protocol(q, out=tmp_path / "out", progress=False)
    assert len(res.scores) == 2 * 2 * 3 and sorted(set(res.scores["repetition"])) == [0, 1]
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    sel = preds[(preds["features"] == "test-mean")]
    folds = {r: set(g.loc[g["fold"] == "f0", "capture_id"]) for r, g in sel.groupby("repetition")}
    assert folds[0] != folds[1]  # another seed, other folds
    for r, g in sel.groupby("repetition"):
        assert g["capture_id"].is_unique and len(g) == 24  # each repetition tests every capture once


def test_person_identification_target(tmp_path):
    ds = random_dataset(subjects=("s1", "s2", "s3"), per_cell=4)
    data = tmp_path / "data.parquet"
    ds.to_parquet(data)
    text = PROTOCOL.format(data=data, scheme="{name: kfold, k: 4}", classifiers="  - test-logreg\n") + "target: subject\n"
    text = text.replace(f"dataset: {data}", f"dataset:\n  name: {data}\n  filters: {{gesture: [rub]}}")
    res = run_protocol(parse_protocol(text, tmp_path / "pid.yaml"), out=tmp_path / "out", progress=False)
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert set(preds["gesture"]) == {"rub"} and (preds["true_label"] == preds["subject"]).all()
    assert {"proba_s1", "proba_s2", "proba_s3"} <= set(preds.columns)
    assert (res.scores["target"] == "subject").all()


@pytest.mark.parametrize("scheme", [
    "{name: challenge, test_subjects: [s1]}", "loso", "{name: kfold, k: 3, grouped: true}",
    "{name: within-subject, k: 2}", "leave-recording-out", "{name: person-independent, k: 2}",
    "transfer", "{name: early, base: transfer, seconds: [0.3]}",
])
def test_every_scheme_runs_end_to_end(tmp_path, scheme):
    rows = [{"subject": s, "gesture": g, "session": r, "group": "A" if s in ("s1", "s2") else "B"}
            for s in ("s1", "s2", "s3", "s4") for g in ("pat", "rub") for r in (1, 2)]
    ds = random_dataset(rows=rows)
    res = run_protocol(protocol(tmp_path, scheme=scheme, ds=ds), out=tmp_path / "out", progress=False)
    assert (res.scores["status"] == "ok").all() and len(res.scores) > 0
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert len(preds) == res.scores["n_test"].sum()
    if "early" in scheme:
        assert set(res.scores["early_frames"]) == {3.0}  # 0.3 s at 10 frames/s


def test_a_run_of_the_first_layout_is_still_read(tmp_path):
    """Results written before the schema version (label columns ``true`` / ``predicted``, pooled rows
    in confusion.parquet) are read in today's layout; a newer layout is refused with both versions."""
    from touchbench.reports.results import load_results
    from touchbench.results.store import read_results_table

    p = protocol(tmp_path)
    run_protocol(p, out=tmp_path / "out", progress=False)
    out = tmp_path / "out"
    preds = pd.read_parquet(out / "predictions.parquet")
    old = preds.rename(columns={"true_label": "true", "predicted_label": "predicted"})
    pq.write_table(pa.Table.from_pandas(old, preserve_index=False), out / "predictions.parquet")  # no version
    back = read_results_table(out / "predictions.parquet")
    pd.testing.assert_frame_equal(back, preds)
    assert read_results_table(out / "predictions.parquet", columns=["task_id", "predicted_label"]).columns.tolist() == [
        "task_id", "predicted_label"]
    rs = load_results([out])
    assert (rs.predictions["true_label"] == preds["true_label"].to_numpy()).all()
    table = pa.Table.from_pandas(preds, preserve_index=False)
    pq.write_table(table.replace_schema_metadata({**table.schema.metadata, b"touchbench_results_schema": b"9"}),
                   out / "predictions.parquet")
    with pytest.raises(TouchbenchError, match=r"predictions.parquet: written by a newer touchbench \(results schema 9; "
                                              r"this version reads up to 3\)"):
        read_results_table(out / "predictions.parquet")


ADAPT_PROTOCOL = """\
name: adapt
dataset: {data}
scheme: {{name: kfold, k: 2, grouped: true}}
methods:
  - {{features: [test-mean], estimator: jung-naive-bayes, label: plain-nb}}
  - {{features: [test-mean], estimator: session-centred, params: {{estimator: jung-naive-bayes}}, label: adapted-nb}}
seed: 7
"""


def test_an_adapted_method_is_adapted_to_each_test_subject_and_says_so(tmp_path):
    """Two folds of two test subjects each: the adapted method's predictions are scikit-learn's
    Gaussian naive Bayes on the training rows centred by their subject's mean, applied to the test
    rows centred by their own subject's mean (worked out here with NumPy); its scores rows carry
    the adaptation, the plain method's none."""
    from sklearn.naive_bayes import GaussianNB

    from touchbench.datasets.model import TouchDataset
    from touchbench.methods.base import ADAPTED

    ds = random_dataset(subjects=("s1", "s2", "s3", "s4"), per_cell=2)
    offsets = {"s1": 0, "s2": 40, "s3": 80, "s4": 120}  # each person presses harder: a session offset
    caps = [np.clip(c.astype(np.int64) + offsets[s], 0, 255).astype(np.uint8) for c, s in zip(ds.captures, ds.meta["subject"])]
    data = TouchDataset(ds.name, caps, ds.meta, ds.sensor).to_parquet(tmp_path / "data.parquet")
    (tmp_path / "adapt.yaml").write_text(ADAPT_PROTOCOL.format(data=data))
    res = run_protocol(tmp_path / "adapt.yaml", out=tmp_path / "out", progress=False)
    scores, preds = res.scores, pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert (scores["status"] == "ok").all() and len(scores) == 4
    assert set(scores.loc[scores["classifier"] == "adapted-nb", "adaptation"]) == {ADAPTED}
    assert set(scores.loc[scores["classifier"] == "plain-nb", "adaptation"]) == {""}
    assert scores.loc[scores["classifier"] == "adapted-nb", "latency_ms"].notna().sum() == 1  # after adaptation
    X = np.stack([c.astype(np.float64).mean(axis=0).ravel() for c in caps])  # test-mean by hand
    subjects = ds.meta["subject"].astype(str).to_numpy()
    centred = X.copy()
    for s in offsets:
        centred[subjects == s] -= X[subjects == s].mean(axis=0)
    adapted = preds[preds["classifier"] == "adapted-nb"]
    for _, fold in adapted.groupby("fold"):
        test = ds.meta["capture_id"].isin(fold["capture_id"]).to_numpy()
        assert len(set(subjects[test])) == 2  # two test subjects, each adapted to on its own
        nb = GaussianNB().fit(centred[~test], ds.meta["gesture"].to_numpy()[~test])
        expected = dict(zip(ds.meta["capture_id"][test], nb.predict(centred[test])))
        assert fold["predicted_label"].tolist() == [expected[c] for c in fold["capture_id"]]
