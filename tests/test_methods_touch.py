"""touchbench's own methods: captures -> own feature sets -> extra-trees / XGBoost.

Each ``touch-*`` method is compared with the same model fitted by hand on
features computed through the feature registry (a separate route), so the
method must order its feature sets, encode labels and seed exactly as
documented.
"""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.ensemble import ExtraTreesClassifier

from touchbench.classifiers.touch import FEW_ROWS, SelectedExtraTrees
from touchbench.core.errors import TouchbenchError
from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES
from touchbench.methods import FeaturePipeline, MethodSpec, method_spec

OWN = ("touch-rhythm", "cell-rhythm", "contact-motion")

SENSOR_4X4 = SensorSpec("test-4x4", (4, 4), 54.0)  # the rate the reference features use


def _captures(n_per_class=8, frames=60, seed=0):
    """(n, frames, 4, 4) captures of three kinds: a held press, a 9 Hz tap of one cell, a moving contact."""
    rng = np.random.default_rng(seed)
    caps, y = [], []
    t = np.arange(frames)
    for label in ("press", "tap", "move"):
        for _ in range(n_per_class):
            c = rng.normal(10, 1, size=(frames, 4, 4))
            if label == "press":
                c[:, 1:3, 1:3] += rng.uniform(50, 150)
            elif label == "tap":
                c[(t // 3) % 2 == 0, rng.integers(4), rng.integers(4)] += rng.uniform(50, 150)
            else:
                c[t, 1, (t // 6) % 4] += rng.uniform(50, 150)
            caps.append(np.clip(c, 0, None))
            y.append(label)
    return np.stack(caps), np.array(y)


def _registry_features(caps, names=OWN):
    return np.hstack([FEATURES.create(n, frame_rate=54.0, value_range=SENSOR_4X4.value_range).fit(caps[:1]).transform(caps) for n in names])


def _proba(pipe, caps):
    """The pipeline's probabilities as a matrix, columns in the order of its classes."""
    P = pipe.predict_proba(list(caps))
    return np.column_stack([P[str(c)] for c in pipe.classes_])


def test_touch_et_is_extra_trees_on_the_registry_features():
    caps, y = _captures()
    test, _ = _captures(n_per_class=3, seed=1)
    est = FeaturePipeline(method_spec("touch-et", n_estimators=20), random_state=11, sensor=SENSOR_4X4)
    est.fit(list(caps), y)
    ref = ExtraTreesClassifier(n_estimators=20, max_features=0.3, n_jobs=1, random_state=11)
    ref.fit(_registry_features(caps), y)
    got = _proba(est, test)
    assert np.array_equal(got, ref.predict_proba(_registry_features(test)))
    assert list(est.classes_) == sorted(set(y))
    assert np.mean(est.predict(list(caps)) == y) == 1.0  # trees fit their training rows


def test_touch_et_fast_uses_touch_rhythm_only_and_100_trees():
    caps, y = _captures()
    est = FeaturePipeline(method_spec("touch-et-fast"), random_state=2, sensor=SENSOR_4X4).fit(list(caps), y)
    assert est.spec.feature_names == ["touch-rhythm"]
    model = est.fitted_.estimator
    assert model.model_.n_estimators == 100
    assert model.model_.n_features_in_ == len(FEATURES.create("touch-rhythm", frame_rate=54.0, value_range=(0, 1023)).feature_names((4, 4)))


def test_touch_xgb_gives_probabilities_of_the_training_classes():
    caps, y = _captures()
    est = FeaturePipeline(method_spec("touch-xgb", n_estimators=20), random_state=0, sensor=SENSOR_4X4)
    est.fit(list(caps), y)
    P = _proba(est, caps)
    assert P.shape == (len(y), 3) and np.allclose(P.sum(axis=1), 1.0)
    assert np.mean(est.predict(list(caps)) == y) == 1.0


def test_selected_extra_trees_keeps_the_most_important_columns():
    rng = np.random.default_rng(0)
    n = 120
    y = rng.integers(0, 2, n)
    X = rng.normal(size=(n, 10))
    X[:, 7] = y + rng.normal(0, 0.05, n)  # the only informative columns
    X[:, 2] = -y + rng.normal(0, 0.05, n)
    m = SelectedExtraTrees(n_estimators=20, keep=2, random_state=0).fit(X, y)
    assert m.columns_.tolist() == [2, 7]
    assert SelectedExtraTrees(n_estimators=5, keep=50, random_state=0).fit(X, y).columns_.tolist() == list(range(10))


def test_few_rows_go_through_the_compiled_forest_with_the_same_probabilities():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(80, 6))
    y = (X[:, 0] + X[:, 1] > 0).astype(int) + (X[:, 2] > 1)
    m = SelectedExtraTrees(n_estimators=30, random_state=3).fit(X, y)
    few = rng.normal(size=(FEW_ROWS, 6))
    assert np.array_equal(m.predict_proba(few), m.model_.predict_proba(few))
    assert m._compiled  # the compiled walk was used
    many = rng.normal(size=(FEW_ROWS + 1, 6))
    assert np.array_equal(m.predict_proba(many), m.model_.predict_proba(many))


def test_bad_input_is_refused():
    caps, y = _captures(n_per_class=2)
    with pytest.raises(TouchbenchError, match="unknown parameter"):
        FeaturePipeline(method_spec("touch-et", model="svm"), sensor=SENSOR_4X4).fit(list(caps), y)
    with pytest.raises(TouchbenchError, match="at least one feature set"):
        MethodSpec("empty", (), "touch-extra-trees")
    with pytest.raises(TouchbenchError, match="random_state is derived"):
        method_spec("touch-et", random_state=3)


def test_a_pipeline_with_memory_computes_the_features_of_its_training_captures_once(tmp_path, monkeypatch):
    """As scikit-learn's Pipeline(memory=...): a second fit on the same captures reads the features
    back (the feature set is not called again) and labels the captures as a pipeline without memory."""
    from touchbench.features.touch import TouchRhythm

    caps, y = _captures(n_per_class=4)
    want = FeaturePipeline(method_spec("touch-et-fast", n_estimators=10), random_state=3,
                           sensor=SENSOR_4X4).fit(list(caps), y).predict(list(caps))
    calls = []
    original = TouchRhythm.transform
    monkeypatch.setattr(TouchRhythm, "transform", lambda self, c: calls.append(len(c)) or original(self, c))
    for _ in range(2):
        piped = FeaturePipeline(method_spec("touch-et-fast", n_estimators=10), random_state=3, sensor=SENSOR_4X4,
                                memory=tmp_path / "memory").fit(list(caps), y)
    assert calls == [len(caps)]  # computed by the first fit only; the second read it back
    np.testing.assert_array_equal(piped.predict(list(caps)), want)


def test_touch_et_contact_is_touch_et_plus_contact_evidence():
    """The four sets in this order, fitted through the registry by hand, give the method's
    probabilities; the contact columns come last, after touch-et's."""
    caps, y = _captures()
    test, _ = _captures(n_per_class=3, seed=1)
    sets = (*OWN, "contact-evidence")
    est = FeaturePipeline(method_spec("touch-et-contact", n_estimators=20), random_state=5, sensor=SENSOR_4X4)
    est.fit(list(caps), y)
    assert est.spec.feature_names == list(sets)

    def by_hand(c):
        return np.hstack([_registry_features(c), FEATURES.create("contact-evidence", sensor=SENSOR_4X4).fit(caps[:1]).transform(c)])

    X = by_hand(caps)
    assert X.shape[1] == est.fitted_.estimator.model_.n_features_in_
    assert X.shape[1] == _registry_features(caps).shape[1] + 19  # contact-evidence's 19 columns
    ref = ExtraTreesClassifier(n_estimators=20, max_features=0.3, n_jobs=1, random_state=5).fit(X, y)
    assert np.array_equal(_proba(est, test), ref.predict_proba(by_hand(test)))
