"""touchbench's own classifiers: raw frames -> own feature sets -> extra-trees / XGBoost.

Each raw-frame method is compared with the same model fitted by hand on
features computed through the feature registry (a separate route), so
the classifier must reshape frames, order feature sets and seed exactly as
documented.
"""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.ensemble import ExtraTreesClassifier

from touchbench.classifiers import make_classifier
from touchbench.classifiers.touch import FEW_ROWS, SelectedExtraTrees
from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES

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
    return np.hstack([FEATURES.create(n, frame_rate=54.0).fit(caps[:1]).transform(caps) for n in names])


def test_touch_et_is_extra_trees_on_the_registry_features():
    caps, y = _captures()
    test, _ = _captures(n_per_class=3, seed=1)
    est = make_classifier("touch-et", random_state=11, sensor=SENSOR_4X4, model_params={"n_estimators": 20})
    est.fit(caps.reshape(len(caps), -1), y)
    ref = ExtraTreesClassifier(n_estimators=20, max_features=0.3, n_jobs=1, random_state=11)
    ref.fit(_registry_features(caps), y)
    got = est.predict_proba(test.reshape(len(test), -1))
    assert np.array_equal(got, ref.predict_proba(_registry_features(test)))
    assert list(est.classes_) == sorted(set(y))
    assert np.mean(est.predict(caps.reshape(len(caps), -1)) == y) == 1.0  # trees fit their training rows


def test_touch_et_fast_uses_touch_rhythm_only_and_100_trees():
    caps, y = _captures()
    est = make_classifier("touch-et-fast", random_state=2, sensor=SENSOR_4X4).fit(caps.reshape(len(caps), -1), y)
    assert est.feature_sets == ("touch-rhythm",)
    assert est.model_.model_.n_estimators == 100
    assert est.model_.model_.n_features_in_ == len(FEATURES.create("touch-rhythm", frame_rate=54.0).feature_names((4, 4)))


def test_touch_xgb_gives_probabilities_of_the_training_classes():
    caps, y = _captures()
    est = make_classifier("touch-xgb", random_state=0, sensor=SENSOR_4X4, model_params={"n_estimators": 20})
    est.fit(caps.reshape(len(caps), -1), y)
    P = est.predict_proba(caps.reshape(len(caps), -1))
    assert P.shape == (len(y), 3) and np.allclose(P.sum(axis=1), 1.0)
    assert np.mean(est.predict(caps.reshape(len(caps), -1)) == y) == 1.0


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
    with pytest.raises(ValueError, match="4x4 frames"):
        make_classifier("touch-et", sensor=SENSOR_4X4).fit(np.zeros((6, 17)), np.array(["a", "b"] * 3))
    caps, y = _captures(n_per_class=2)
    with pytest.raises(ValueError, match="model must be"):
        make_classifier("touch-et", sensor=SENSOR_4X4, model="svm").fit(caps.reshape(len(caps), -1), y)
    with pytest.raises(ValueError, match="feature_sets"):
        make_classifier("touch-et", sensor=SENSOR_4X4, feature_sets=()).fit(caps.reshape(len(caps), -1), y)
