"""Nested design as a method (``nested-select``): candidates scored inside the training subjects only.

The inner accuracies are recomputed here with scikit-learn's own splitters
and estimators on the same features, the choice is their argmax, and the
refitted model predicts what the chosen candidate fitted by hand on all
training captures predicts. Through the engine: a protocol names
registered methods as candidates, every task's notes say what was chosen,
and the task identity covers the candidates' code.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.model_selection import LeaveOneGroupOut, StratifiedKFold

from touchbench.classifiers import make_classifier
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.engine import run_protocol
from touchbench.engine.identity import classifier_identity
from touchbench.engine.testing import SENSOR, random_dataset
from touchbench.methods import expand_candidates, method_spec

MEAN_LOGREG = {"label": "mean-logreg", "features": ["test-mean"], "estimator": "test-logreg"}
CENTER_FOREST = {"label": "centered-forest", "features": ["test-centered"], "estimator": "test-forest",
                 "params": {"n_estimators": 5}}


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _data(n_subjects=4, seed=0):
    ds = random_dataset(subjects=[f"s{i}" for i in range(n_subjects)], per_cell=3, seed=seed)
    return ds.captures, ds.meta["gesture"].to_numpy(), ds.meta["subject"].to_numpy()


def _by_hand(cand, caps, y, splits):
    """Inner accuracies of a candidate, each inner part's features and model built from scratch."""
    from touchbench.classifiers import make_classifier as mk
    from touchbench.features.base import make_feature_set

    out = []
    for tr, te in splits:
        fs = make_feature_set(cand["features"][0], {}, SENSOR).fit([caps[i] for i in tr])
        Xtr, Xte = fs.transform([caps[i] for i in tr]), fs.transform([caps[i] for i in te])
        classes, codes = np.unique(y[tr], return_inverse=True)
        est = mk(cand["estimator"], random_state=3, **cand.get("params", {})).fit(Xtr, codes)
        out.append(float(np.mean(classes[est.predict(Xte)] == y[te])))
    return out


def test_inner_scores_are_leave_one_training_subject_out_and_the_best_is_refitted():
    caps, y, groups = _data()
    est = make_classifier("nested-select", random_state=3, sensor=SENSOR, candidates=[MEAN_LOGREG, CENTER_FOREST])
    est.fit(caps, y, groups=groups)
    splits = list(LeaveOneGroupOut().split(np.zeros((len(y), 1)), y, groups))
    assert len(splits) == 4
    for cand in (MEAN_LOGREG, CENTER_FOREST):
        assert est.cv_results_[cand["label"]] == pytest.approx(_by_hand(cand, caps, y, splits))
    means = {k: np.mean(v) for k, v in est.cv_results_.items()}
    assert est.chosen_ == max(means, key=means.get)
    assert est.selection_note_.startswith(f"nested-select chose {est.chosen_} by inner CV (one training subject left out")
    # the refit: the chosen candidate fitted by hand on every training capture
    chosen = MEAN_LOGREG if est.chosen_ == "mean-logreg" else CENTER_FOREST
    test_caps, _, _ = _data(seed=1)
    from touchbench.features.base import make_feature_set

    fs = make_feature_set(chosen["features"][0], {}, SENSOR).fit(caps)
    classes, codes = np.unique(y, return_inverse=True)
    ref = make_classifier(chosen["estimator"], random_state=3, **chosen.get("params", {})).fit(fs.transform(caps), codes)
    assert est.predict(test_caps).tolist() == classes[ref.predict(fs.transform(test_caps))].tolist()
    P = est.predict_proba(test_caps)
    assert P.shape == (len(test_caps), 3) and np.allclose(P.sum(axis=1), 1.0)


def test_without_subjects_the_inner_folds_are_stratified():
    caps, y, _ = _data(n_subjects=2)
    est = make_classifier("nested-select", random_state=3, sensor=SENSOR, candidates=[MEAN_LOGREG, CENTER_FOREST],
                          inner_folds=3).fit(caps, y)
    splits = list(StratifiedKFold(n_splits=3, shuffle=True, random_state=3).split(np.zeros((len(y), 1)), y))
    assert est.cv_results_["mean-logreg"] == pytest.approx(_by_hand(MEAN_LOGREG, caps, y, splits))
    assert "3 stratified folds" in est.selection_note_


def test_a_candidate_the_sensor_refuses_is_left_out_and_none_left_is_refused():
    long_window = {"label": "windows", "features": [{"name": "touch-windows", "params": {"window_s": 5.0}}],
                   "estimator": "test-logreg"}
    caps, y, groups = _data()  # 8..12 frames at 10 Hz: shorter than one 5-s window
    est = make_classifier("nested-select", random_state=0, sensor=SENSOR, candidates=[long_window, MEAN_LOGREG])
    assert est.check_sensor(SENSOR, 8) is None
    est.fit(caps, y, groups=groups)
    assert est.chosen_ == "mean-logreg" and "left out for this sensor: windows (" in est.selection_note_
    alone = make_classifier("nested-select", random_state=0, sensor=SENSOR, candidates=[long_window])
    assert alone.check_sensor(SENSOR, 8).startswith("no candidate serves this sensor: windows:")


def test_a_method_name_is_written_out_by_the_methods_layer_only():
    with pytest.raises(TouchbenchError, match="registered method's name is written out"):
        make_classifier("nested-select", sensor=SENSOR, candidates=["touch-et"]).fit(*_data()[:2])
    params = expand_candidates("nested-select", {"candidates": ["touch-et-fast", MEAN_LOGREG]})
    fast = method_spec("touch-et-fast")
    assert params["candidates"][0] == {"label": "touch-et-fast", "features": [["touch-rhythm", {}]],
                                       "estimator": fast.estimator, "params": dict(fast.estimator_params)}
    assert params["candidates"][1] == MEAN_LOGREG
    with pytest.raises(TouchbenchError, match="'no-such' is not a registered method"):
        expand_candidates("nested-select", {"candidates": ["no-such"]})
    # the identity of the search covers its candidates' feature sets and estimators
    ident = classifier_identity("nested-select", params)
    assert "touchbench.features.touch" in ident.modules and "touchbench.classifiers.touch" in ident.modules


def test_through_the_engine_every_task_says_what_it_chose(tmp_path):
    data = tmp_path / "d.parquet"
    random_dataset(subjects=("s1", "s2", "s3", "s4"), per_cell=2).to_parquet(data)
    p = tmp_path / "nested.yaml"
    p.write_text(f"""name: nested
dataset: {data}
scheme: loso
methods:
  - name: nested-select
    label: searched
    params:
      candidates:
        - {{label: mean-logreg, features: [test-mean], estimator: test-logreg}}
        - {{label: centered-forest, features: [test-centered], estimator: test-forest, params: {{n_estimators: 5}}}}
""")
    res = run_protocol(p, out=tmp_path / "results", progress=False)
    s = res.scores
    assert (s["status"] == "ok").all() and len(s) == 4
    # each outer fold chose among its 3 training subjects only (3 inner folds)
    assert all("by inner CV (one training subject left out at a time)" in n for n in s["notes"])
    chosen = s["notes"].str.extract(r"nested-select chose (\S+)")[0]
    assert set(chosen) <= {"mean-logreg", "centered-forest"}
    preds = pd.read_parquet(res.out / "predictions.parquet")
    assert len(preds) == int(s["n_test"].sum())


def test_touch_select_is_the_search_over_the_touch_methods():
    m = method_spec("touch-select")
    assert m.estimator == "nested-select" and not m.feature_sets
    assert [c["label"] for c in m.estimator_params["candidates"]] == ["touch-et", "touch-xgb", "touch-et-win", "touch-et-fast"]
    socialtouch_like = SensorSpec("short", (4, 4), 12.0, (0, 255))
    est = make_classifier("nested-select", sensor=socialtouch_like, **m.estimator_params)
    assert est.check_sensor(socialtouch_like, 3) is None  # touch-et-win is left out there, the others serve


def test_a_candidate_that_fails_inside_is_not_chosen_and_said():
    caps, y, groups = _data()  # 27 training captures per inner part: 40 neighbours cannot be found
    knn = {"label": "knn-40", "features": ["test-mean"], "estimator": "zhou-knn", "params": {"n_neighbors": 40}}
    est = make_classifier("nested-select", random_state=0, sensor=SENSOR, candidates=[knn, MEAN_LOGREG]).fit(caps, y, groups=groups)
    assert est.chosen_ == "mean-logreg" and "failed in the inner folds: knn-40 (ValueError" in est.selection_note_
    with pytest.raises(TouchbenchError, match="every candidate failed"):
        make_classifier("nested-select", random_state=0, sensor=SENSOR, candidates=[knn, {**knn, "label": "again"}]).fit(
            caps, y, groups=groups)
