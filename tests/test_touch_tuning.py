"""Tuning happens inside the training subjects only.

A spy replaces the inner splitter of ``touch-extra-trees-tuned``; a leave-one-subject-out
run of the real engine then records what every inner split received. The
left-out subject's rows and labels must never reach it, and predicting the
test fold must not tune anything.
"""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.model_selection import GroupKFold

import touchbench.classifiers.touch as touch
from touchbench.classifiers import make_classifier
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.features.base import FEATURES
from touchbench.protocols.loading import parse_protocol

SUBJECTS = ("s1", "s2", "s3", "s4")

TEMPLATE = """\
name: tuning-spy
dataset:
  name: {data}
scheme: loso
features:
  - [test-mean]
classifiers:
  - name: touch-extra-trees-tuned
    params: {{n_estimators: 10, grid_keep: [null, 4], inner_folds: 2}}
seed: 3
"""


class SpyGroupKFold(GroupKFold):
    calls: list[dict] = []

    def split(self, X, y=None, groups=None):
        SpyGroupKFold.calls.append({"X": np.array(X, copy=True), "groups": np.asarray(groups).copy(), "n": len(X)})
        return super().split(X, y, groups)


@pytest.fixture(autouse=True)
def env(engine_env, monkeypatch):
    SpyGroupKFold.calls = []
    monkeypatch.setattr(touch, "GroupKFold", SpyGroupKFold)
    yield


def test_inner_splits_never_see_the_left_out_subject(tmp_path):
    ds = random_dataset(subjects=SUBJECTS, gestures=("pat", "rub", "stroke"), per_cell=3, seed=5)
    data = tmp_path / "data.parquet"
    ds.to_parquet(data)
    p = parse_protocol(TEMPLATE.format(data=data), tmp_path / "tuning-spy.yaml")
    res = run_protocol(p, out=tmp_path / "out", jobs=1, progress=False)
    assert (res.scores["status"] == "ok").all()
    calls = SpyGroupKFold.calls
    assert len(calls) == len(SUBJECTS)  # one tuning per outer fold, none at predict time
    # the feature rows of every capture, to recognise a test row if one leaked
    X_all = FEATURES.create("test-mean").fit(ds.captures).transform(ds.captures)
    subj = ds.meta["subject"].to_numpy()
    left_out = []
    for c in calls:
        seen = set(c["groups"].tolist())
        assert len(seen) == len(SUBJECTS) - 1
        (out,) = set(SUBJECTS) - seen
        left_out.append(out)
        assert c["n"] == int((subj != out).sum())  # exactly the training rows
        test_rows = X_all[subj == out]
        for r in c["X"]:
            assert not np.any(np.all(np.isclose(test_rows, r, rtol=0, atol=1e-12), axis=1))
    assert sorted(left_out) == sorted(SUBJECTS)


def test_predict_does_not_tune():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(60, 6))
    y = np.repeat(["a", "b", "c"], 20)
    groups = np.tile(["g1", "g2", "g3"], 20)
    m = make_classifier("touch-extra-trees-tuned", random_state=0, n_estimators=10, grid_keep=(None, 3), inner_folds=3)
    m.fit(X, y, groups=groups)
    n = len(SpyGroupKFold.calls)
    assert n == 1 and SpyGroupKFold.calls[0]["n"] == 60
    m.predict(rng.normal(size=(7, 6)))
    m.predict_proba(rng.normal(size=(1, 6)))
    assert len(SpyGroupKFold.calls) == n
    assert m.best_params_ in m.cv_results_["params"]
    assert len(m.cv_results_["mean_accuracy"]) == 4


def test_groups_must_match_rows():
    m = make_classifier("touch-extra-trees-tuned", random_state=0, n_estimators=5)
    with pytest.raises(ValueError, match="groups"):
        m.fit(np.zeros((10, 2)), np.repeat(["a", "b"], 5), groups=np.array(["g"] * 9))
