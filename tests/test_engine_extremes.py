"""The extremes of real data: handled (and reported) or refused before any work.

- a training fold that lacks a class the test fold has,
- a subject with one capture,
- a fold with one class (training or test),
- a filter that leaves a class with fewer captures than k,
- filters, schemes and targets that cannot work: refused before any work,
  with the protocol line, and nothing written.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol

TEMPLATE = """\
name: extreme
dataset:
  name: {data}
{filters}scheme: {scheme}
features:
  - [test-mean]
classifiers:
  - {clf}
seed: 1
"""


@pytest.fixture(autouse=True)
def env(engine_env):
    """A private cache and working folder, with the test-only components."""
    yield


def run(tmp_path, rows=None, ds=None, scheme="loso", filters="", clf="test-logreg"):
    data = tmp_path / "data.parquet"
    (ds or random_dataset(rows=rows)).to_parquet(data)
    text = TEMPLATE.format(data=data, scheme=scheme, filters=filters, clf=clf)
    p = parse_protocol(text, tmp_path / "extreme.yaml")
    return run_protocol(p, out=tmp_path / "out", progress=False)


def rows_for(spec: dict[str, list[str]], per: int = 2) -> list[dict]:
    return [{"subject": s, "gesture": g} for s, gs in spec.items() for g in gs for _ in range(per)]


def test_training_fold_lacking_a_test_class(tmp_path):
    # only s3 performs "tickle": when s3 is tested, training has never seen it
    rows = rows_for({"s1": ["pat", "rub"], "s2": ["pat", "rub"], "s3": ["pat", "rub", "tickle"]})
    res = run(tmp_path, rows)
    s3 = res.scores[res.scores["fold"] == "subject=s3"].iloc[0]
    assert s3["status"] == "ok"
    assert "classes absent from training: 'tickle' (2 test captures); counted as errors" in s3["notes"]
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    tickle = preds[preds["true_label"] == "tickle"]
    assert len(tickle) == 2 and (tickle["predicted_label"] != "tickle").all()
    # the two tickle captures are errors: accuracy at most 4/6
    assert s3["accuracy"] <= 4 / 6
    # the s3 model never learned tickle: no probability for it (the other folds' models did)
    assert preds.loc[preds["fold"] == "subject=s3", "proba_tickle"].isna().all()
    assert preds.loc[preds["fold"] == "subject=s1", "proba_tickle"].notna().all()


def test_subject_with_a_single_capture(tmp_path):
    rows = rows_for({"s1": ["pat", "rub"], "s2": ["pat", "rub"]}) + [{"subject": "s3", "gesture": "rub"}]
    res = run(tmp_path, rows)
    s3 = res.scores[res.scores["fold"] == "subject=s3"].iloc[0]
    assert s3["n_test"] == 1 and s3["status"] == "ok"
    assert "test fold has a single class 'rub'" in s3["notes"]
    assert any("single capture" in n for n in res.notes)
    # within-subject: the subject with one capture is left out, and the report says so
    res = run(tmp_path, rows, scheme="{name: within-subject, k: 2}")
    assert set(res.scores["fold_group"]) == {"s1", "s2"}
    assert any("['s3'] have a single capture and are left out" in n for n in res.notes)
    import json

    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert any("left out" in n for n in manifest["notes"])


def test_training_fold_with_a_single_class(tmp_path):
    # s1 and s2 only "pat": when s3 is tested, training has one class
    rows = rows_for({"s1": ["pat"], "s2": ["pat"], "s3": ["pat", "rub"]})
    res = run(tmp_path, rows)
    s3 = res.scores[res.scores["fold"] == "subject=s3"].iloc[0]
    assert s3["status"] == "ok" and s3["n_classes_train"] == 1
    assert "no model fitted, constant prediction" in s3["notes"]
    assert s3["accuracy"] == pytest.approx(0.5)  # 2 pat right, 2 rub wrong
    assert s3["balanced_accuracy"] == pytest.approx(0.5)  # recall 1 on pat, 0 on rub


def test_test_fold_with_a_single_class_metrics(tmp_path):
    rows = rows_for({"s1": ["pat", "rub"], "s2": ["pat", "rub"], "s3": ["rub"]})
    res = run(tmp_path, rows)
    s3 = res.scores[res.scores["fold"] == "subject=s3"].iloc[0]
    assert "test fold has a single class 'rub'" in s3["notes"]
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    p = preds[preds["fold"] == "subject=s3"]
    acc = (p["true_label"] == p["predicted_label"]).mean()
    assert s3["accuracy"] == pytest.approx(acc) and s3["balanced_accuracy"] == pytest.approx(acc)


def test_filter_leaving_a_class_smaller_than_k(tmp_path):
    ds = random_dataset(subjects=("s1", "s2"), gestures=("pat", "rub", "tickle"), per_cell=5,
                        extra={"cover": ["fur", "none"]})
    # keep tickle only on fur for s1 by excluding: tickle has 5 captures < k... make it 2
    meta = ds.meta
    keep = ~((meta["gesture"] == "tickle") & ~((meta["subject"] == "s1") & (meta["cover"] == "fur")))
    keep.iloc[np.flatnonzero((meta["gesture"] == "tickle").to_numpy() & keep.to_numpy())[2:]] = False
    ds = ds.subset(np.flatnonzero(keep.to_numpy()))
    res = run(tmp_path, ds=ds, scheme="{name: kfold, k: 5}", filters="  filters:\n    cover: [fur]\n")
    assert (res.scores["status"] == "ok").all()
    assert any("class 'tickle' has 2 captures, fewer than k=5" in n for n in res.notes)
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert preds["capture_id"].is_unique and len(preds) == (ds.meta["cover"] == "fur").sum()


def _refused(tmp_path, match, **kw):
    with pytest.raises(ProtocolError, match=match):
        run(tmp_path, **kw)
    assert not (tmp_path / "out").exists()  # nothing was written


def test_refused_before_any_work(tmp_path):
    rows = rows_for({"s1": ["pat", "rub"], "s2": ["pat", "rub"], "s3": ["pat", "rub"]})
    _refused(tmp_path, r"extreme.yaml:5: dataset.filters.gesture\[0\]: gesture 'patt' is not in the dataset; did you mean 'pat'",
             rows=rows, filters="  filters:\n    gesture: [patt]\n")
    _refused(tmp_path, r"extreme.yaml:5: dataset.filters.colour: the dataset has no metadata column 'colour'",
             rows=rows, filters="  filters:\n    colour: [red]\n")
    _refused(tmp_path, r"extreme.yaml:2: dataset: the filters leave no captures",
             rows=rows, filters="  filters:\n    gesture: [pat]\n  exclude:\n    gesture: [pat]\n")
    _refused(tmp_path, r"target: after the filters the target 'gesture' has a single value \['pat'\]",
             rows=rows, filters="  filters:\n    gesture: [pat]\n")
    _refused(tmp_path, r"extreme.yaml:\d+: scheme: scheme 'kfold': k=10 folds but only 6 captures",
             rows=rows_for({"s1": ["pat", "rub"], "s2": ["pat"]}), scheme="{name: kfold, k: 10}")
    _refused(tmp_path, r"scheme: scheme 'person-independent': k=4 parties but only 3",
             rows=rows, scheme="{name: person-independent, k: 4}")
    _refused(tmp_path, r"scheme: scheme 'leave-recording-out' needs the metadata column 'session'",
             rows=rows, scheme="leave-recording-out")
    _refused(tmp_path, r"scheme: scheme 'transfer' needs the metadata column 'group'", rows=rows, scheme="transfer")
