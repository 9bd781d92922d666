"""Adaptation to a new session: ``session-centred`` (classifiers/adapt.py), the ``touch-et-adapt``
method, ``predict`` adapting on a file's subjects and ``stream`` refusing such a model.

The engine's per-subject adaptation and its results column are tested in
tests/test_engine_run.py, the leaderboard's separate table in
tests/test_reports_leaderboard.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.naive_bayes import GaussianNB
from click.testing import CliRunner
from sklearn.utils.estimator_checks import parametrize_with_checks

from touchbench.classifiers import CLASSIFIERS, make_classifier
from touchbench.cli.main import cli
from touchbench.classifiers.adapt import SD_FLOOR, NotAdaptedError, SessionCentred, uses_unlabelled_test
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.deploy.model import fit_model
from touchbench.deploy.predict import adaptation_text, adaptation_warning, predict_dataset
from touchbench.deploy.stream import SlidingRecognizer
from touchbench.engine.testing import random_dataset
from touchbench.methods import METHODS, method_spec
from touchbench.methods.base import ADAPTED, Method

# two sessions of a toy matrix: A (2 rows), B (3 rows)
X_TOY = np.array([[1.0, 10.0, 5.0], [3.0, 30.0, 5.0],
                  [11.0, 0.0, 7.0], [13.0, 4.0, 7.0], [15.0, 2.0, 7.0]])
Y_TOY = np.array([0, 1, 0, 1, 0])
G_TOY = np.array(["A", "A", "B", "B", "B"])


def _nb(**kw) -> SessionCentred:
    """Session-centred Gaussian naive Bayes: its ``theta_`` are the class means of the rows it was fitted on."""
    return make_classifier("session-centred", random_state=0, estimator="jung-naive-bayes", **kw)


# ------------------------------------------------------------------ the registry entry
def test_registered_with_the_unlabelled_test_tag():
    assert CLASSIFIERS.entry("session-centred").tags["unlabelled_test"] is True
    assert uses_unlabelled_test("session-centred")
    assert not uses_unlabelled_test("touch-extra-trees") and not uses_unlabelled_test("no-such-classifier")


def test_touch_et_adapt_is_touch_et_contact_around_the_same_extra_trees():
    adapt, contact = method_spec("touch-et-adapt"), method_spec("touch-et-contact")
    assert adapt.feature_sets == contact.feature_sets
    assert adapt.estimator == "session-centred"
    assert adapt.estimator_params["estimator"] == contact.estimator == "touch-extra-trees"
    assert adapt.estimator_params["params"] == contact.estimator_params == {}
    assert METHODS.entry("touch-et-adapt").tags["estimator"] == "session-centred"
    assert Method("a", adapt, "touch-et-adapt").adaptation == ADAPTED
    assert Method("c", contact, "touch-et-contact").adaptation == ""


def test_the_task_identity_follows_the_inner_classifier_by_name():
    from touchbench.engine.identity import classifier_identity

    spec = method_spec("touch-et-adapt")
    modules = classifier_identity(spec.estimator, spec.estimator_params).modules
    assert {"touchbench.classifiers.adapt", "touchbench.classifiers.touch"} <= set(modules)
    other = classifier_identity(spec.estimator, {**spec.estimator_params, "estimator": "jung-naive-bayes"})
    assert "touchbench.classifiers.jung" in other.modules and "touchbench.classifiers.touch" not in other.modules


# ------------------------------------------------------------------ centring and scaling
def test_each_training_session_is_centred_by_its_own_mean():
    est = _nb().fit(X_TOY, Y_TOY, groups=G_TOY)
    # A's mean (2, 20, 5): rows (-1, -10, 0), (1, 10, 0); B's mean (13, 2, 7): (-2, -2, 0), (0, 2, 0), (2, 0, 0)
    # class 0: (-1, -10, 0), (-2, -2, 0), (2, 0, 0); class 1: (1, 10, 0), (0, 2, 0)
    theta = est.fitted_.estimator.theta_
    np.testing.assert_allclose(theta, [[-1 / 3, -4.0, 0.0], [0.5, 6.0, 0.0]], rtol=0, atol=1e-12)


def test_without_groups_the_training_rows_are_one_session():
    est = _nb().fit(X_TOY, Y_TOY)
    mean = X_TOY.sum(axis=0) / 5  # (8.6, 9.2, 6.2)
    np.testing.assert_allclose(est.fitted_.estimator.theta_[1], ((X_TOY[1] + X_TOY[3]) / 2) - mean, atol=1e-12)


def test_scale_divides_by_the_session_sd_with_a_floor_and_a_single_row_session_is_zero():
    X = np.vstack([X_TOY, [[100.0, 100.0, 100.0]]])
    y, g = np.append(Y_TOY, 1), np.append(G_TOY, "C")
    est = _nb(scale=True).fit(X, y, groups=g)
    s = math.sqrt(8 / 3)  # B's population sd of (11, 13, 15) and of (0, 4, 2); A's are 1 and 10
    # A: (-1, -1, 0), (1, 1, 0); B: (-2/s, -2/s, 0), (0, 2/s, 0), (2/s, 0, 0); C (one row): (0, 0, 0)
    # the third column is constant in every session: sd 0, floored, so it stays 0
    expected = [[-1 / 3, (-1 - 2 / s) / 3, 0.0], [1 / 3, (1 + 2 / s) / 3, 0.0]]
    np.testing.assert_allclose(est.fitted_.estimator.theta_, expected, rtol=0, atol=1e-12)
    est.adapt(np.array([[4.0, 1.0, 9.0], [6.0, 1.0, 9.0]]))
    np.testing.assert_array_equal(est.adapted_mean_, [5.0, 1.0, 9.0])
    np.testing.assert_array_equal(est.adapted_sd_, [1.0, SD_FLOOR, SD_FLOOR])


def test_adapt_stores_the_new_session_statistics_and_predict_uses_them():
    est = _nb().fit(X_TOY, Y_TOY, groups=G_TOY)
    new = np.array([[100.0, 50.0, 0.0], [104.0, 70.0, 0.0]])  # mean (102, 60, 0): centred (-2, -10, 0), (2, 10, 0)
    est.adapt(new)
    np.testing.assert_array_equal(est.adapted_mean_, [102.0, 60.0, 0.0])
    np.testing.assert_array_equal(est.adapted_sd_, [1.0, 1.0, 1.0])
    reference = GaussianNB().fit(est._centred(X_TOY, G_TOY), Y_TOY)  # scikit-learn's own, on the centred rows
    np.testing.assert_array_equal(est.predict(new), reference.predict(new - [102.0, 60.0, 0.0]))
    np.testing.assert_allclose(est.predict_proba(new), reference.predict_proba(new - [102.0, 60.0, 0.0]), atol=1e-12)


def test_predict_is_refused_before_adapt_and_after_a_refit():
    est = _nb().fit(X_TOY, Y_TOY, groups=G_TOY)
    for call in (est.predict, est.predict_proba):
        with pytest.raises(NotAdaptedError, match=r"call adapt\(X\) with the new session's unlabelled rows"):
            call(X_TOY)
    est.adapt(X_TOY[:2]).predict(X_TOY[:2])
    est.fit(X_TOY, Y_TOY, groups=G_TOY)  # a refit forgets the session it was adapted to
    with pytest.raises(NotAdaptedError):
        est.predict(X_TOY)


def test_one_class_and_an_inner_classifier_on_captures_are_defined():
    one = _nb().fit(X_TOY, np.zeros(5, dtype=np.int64), groups=G_TOY).adapt(X_TOY)
    assert one.predict(X_TOY).tolist() == [0] * 5 and one.predict_proba(X_TOY).tolist() == [[1.0]] * 5
    with pytest.raises(TouchbenchError, match="must take a feature matrix"):
        make_classifier("session-centred", estimator="nested-select").fit(X_TOY, Y_TOY)


@settings(max_examples=25, deadline=None)
@given(offset=st.lists(st.integers(-1000, 1000), min_size=3, max_size=3),
       seed=st.integers(0, 2 ** 16))
def test_a_session_offset_changes_no_prediction(offset, seed):
    """Four integer rows per session: every mean is exact, so a shifted session centres to the same rows."""
    rng = np.random.default_rng(seed)
    X = rng.integers(-50, 50, size=(8, 3)).astype(np.float64)
    est = make_classifier("session-centred", random_state=1, params={"n_estimators": 5}).fit(
        X, [0, 1, 0, 1, 1, 0, 1, 0], groups=["a"] * 4 + ["b"] * 4)
    new = rng.integers(-50, 50, size=(4, 3)).astype(np.float64)
    before = est.adapt(new).predict_proba(new)
    after = est.adapt(new + np.array(offset, dtype=np.float64)).predict_proba(new + np.array(offset, dtype=np.float64))
    np.testing.assert_array_equal(before, after)


def test_a_session_offset_defeats_the_plain_trees_and_adaptation_recovers_it():
    """One feature: class 0 at offset - 1, class 1 at offset + 1 in every session (offsets 0 and 3 in
    training, 10 in the new session). Every new row (9 or 11) lies above every training value (at most
    4), so each plain tree sends it to the leaf of the largest training value, class 1: accuracy 1/2.
    Centred by its session's mean (the offset: equal class counts), every row of every session is -1
    or +1, which the trees separate: accuracy 1."""
    def session(offset):
        return np.array([[offset - 1.0], [offset + 1.0]] * 3), np.array([0, 1] * 3)

    (Xa, ya), (Xb, yb), (Xt, yt) = session(0.0), session(3.0), session(10.0)
    X, y, g = np.vstack([Xa, Xb]), np.concatenate([ya, yb]), ["a"] * 6 + ["b"] * 6
    plain = make_classifier("touch-extra-trees", random_state=3, n_estimators=7).fit(X, y)
    assert plain.predict(Xt).tolist() == [1] * 6
    adapted = make_classifier("session-centred", random_state=3, params={"n_estimators": 7}).fit(X, y, groups=g)
    assert adapted.adapt(Xt).predict(Xt).tolist() == yt.tolist()


# ------------------------------------------------------------------ scikit-learn's checks
class _AdaptedToTraining(SessionCentred):
    """For scikit-learn's checks, which predict right after ``fit``: adapted to the training rows."""

    def fit(self, X, y, groups=None):
        return super().fit(X, y, groups).adapt(X)


@parametrize_with_checks([_AdaptedToTraining(params={"n_estimators": 5}, random_state=0)])
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


# ------------------------------------------------------------------ deploy
SENSOR = SensorSpec("test-6x6", (6, 6), 20.0, (0.0, 255.0))


@pytest.fixture(scope="module")
def adapted_model():
    ds = random_dataset(subjects=("s1", "s2"), per_cell=2, frames=(24, 24), sensor=SENSOR, name="six")
    spec = method_spec("touch-et-adapt", params={"n_estimators": 5})
    return fit_model(ds, spec, seed=0), ds


def test_predict_adapts_to_each_subject_of_the_file(adapted_model):
    model, ds = adapted_model
    assert model.adapts_to_session
    table = predict_dataset(model, ds)
    X = model.transform(ds.captures)
    subjects = ds.meta["subject"].astype(str).to_numpy()
    for s in ("s1", "s2"):
        rows = np.flatnonzero(subjects == s)
        centred = X[rows] - X[rows].mean(axis=0)  # by hand: the subject's own mean, unlabelled
        codes = model.estimator.fitted_.predict(centred).astype(np.int64)  # the inner classifier on them
        assert table["predicted_label"].to_numpy()[rows].tolist() == [str(c) for c in model.classes[codes]]
    assert adaptation_text(model, ds).startswith("adapted to the data's unlabelled captures, each of its 2 subjects")


def test_a_one_capture_session_is_said_to_be_centred_to_zeros(adapted_model, tmp_path):
    model, ds = adapted_model
    subjects = ds.meta["subject"].astype(str).to_numpy()
    one = ds.subset([int(np.flatnonzero(subjects == "s1")[0]), *np.flatnonzero(subjects == "s2")])
    assert adaptation_warning(model, ds) is None  # every subject has several captures
    said = adaptation_warning(model, one)
    assert said.startswith("1 of the data's 2 subject(s) have one capture only (s1): one capture cannot give a "
                           "session's statistics, so the model centres it to zeros")
    # what it says, by hand: the one capture centred on its own mean is a row of zeros
    X = model.transform(one.captures[:1])
    assert np.all(X - X.mean(axis=0) == 0)
    # a model fitted here (the fixture's, once it predicted, holds a compiled forest its file would name)
    model_path = fit_model(ds, method_spec("touch-et-adapt", params={"n_estimators": 5}), seed=0).save(
        tmp_path / "m.joblib")
    one.to_parquet(tmp_path / "one.parquet")
    r = CliRunner().invoke(cli, ["predict", str(model_path), str(tmp_path / "one.parquet")])
    assert r.exit_code == 0, r.output
    assert "warning: 1 of the data's 2 subject(s) have one capture only (s1)" in r.stderr


def test_stream_refuses_an_adapted_model(adapted_model):
    model, _ = adapted_model
    with pytest.raises(TouchbenchError, match="a stream has no session to adapt to"):
        SlidingRecognizer(model)
