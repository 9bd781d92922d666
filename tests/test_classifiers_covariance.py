"""The pooled within-class covariance and its condition number (what zhou-lda inverts), against a
hand computation, numpy.linalg.cond and scikit-learn's LDA covariance; and `touchbench features
condition` on a protocol."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis

from touchbench.cli.main import cli
from touchbench.classifiers.covariance import condition_number, pooled_within_class_covariance

# class a: (0, 0), (2, 2): deviations (-1, -1), (1, 1); class b: (0, 1), (0, 3): deviations (0, -1), (0, 1).
# Scatter [[2, 2], [2, 4]], divided by n - K = 2: [[1, 1], [1, 2]], eigenvalues (3 +- sqrt 5) / 2.
X_HAND = np.array([[0.0, 0.0], [2.0, 2.0], [0.0, 1.0], [0.0, 3.0]])
Y_HAND = np.array(["a", "a", "b", "b"])


def test_hand_made_covariance_and_condition_number():
    S = pooled_within_class_covariance(X_HAND, Y_HAND)
    assert S.dtype == np.float64
    assert np.array_equal(S, [[1.0, 1.0], [1.0, 2.0]])
    want = (3 + math.sqrt(5)) / (3 - math.sqrt(5))  # 3.5 + 1.5 sqrt 5
    assert condition_number(S) == pytest.approx(want, rel=1e-12)
    assert condition_number(S) == pytest.approx(np.linalg.cond(S), rel=1e-12)


def test_covariance_matches_scikit_learn_lda():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(30, 4)) * [1.0, 10.0, 0.1, 3.0]
    y = np.repeat(["p", "q", "r"], 10)
    lda = LinearDiscriminantAnalysis(solver="lsqr", store_covariance=True).fit(X, y)
    # scikit-learn's covariance_ is the class covariances (divided by n_k) weighted by the priors n_k / n
    assert np.allclose(pooled_within_class_covariance(X, y) * (30 - 3) / 30, lda.covariance_)
    S = pooled_within_class_covariance(X, y)
    assert condition_number(S) == pytest.approx(np.linalg.cond(S), rel=1e-9)


def test_singular_cases_are_infinite():
    # the second column is constant within each class (1 in a, 5 in b): no spread left in it
    X = np.array([[0.0, 1.0], [2.0, 1.0], [1.0, 5.0], [4.0, 5.0]])
    S = pooled_within_class_covariance(X, ["a", "a", "b", "b"])
    assert np.array_equal(S, [[6.5 / 2, 0.0], [0.0, 0.0]])  # scatter (1 + 1) + (2.25 + 2.25) = 6.5
    assert condition_number(S) == math.inf
    with np.errstate(divide="ignore"):
        assert np.linalg.cond(S) == math.inf
    # one row per class: the zero matrix (numpy: NaN), infinite here
    zero = pooled_within_class_covariance([[1.0, 2.0], [3.0, 4.0]], ["a", "b"])
    assert not zero.any()
    assert condition_number(zero) == math.inf


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="one label per row"):
        pooled_within_class_covariance(X_HAND, ["a"])
    with pytest.raises(ValueError, match="square"):
        condition_number(np.ones((2, 3)))


PROTOCOL = """name: cond-check
dataset: scene:tiny
target: gesture
scheme: {name: kfold, k: 2, stratified: true}
features: [[{name: zhou-basic, params: {descriptors: [D1]}}]]
classifiers: [zhou-lda]
seed: 0
"""


def test_features_condition_prints_the_condition_number_of_the_training_side(tmp_path):
    from touchbench.catalog import load_dataset
    from touchbench.features.base import make_feature_set

    path = tmp_path / "p.yaml"
    path.write_text(PROTOCOL)
    res = CliRunner().invoke(cli, ["features", "condition", str(path), "--json"])
    assert res.exit_code == 0, res.output
    (row,) = json.loads(res.output)
    ds = load_dataset("scene:tiny")  # k-fold trains on every capture at some fold
    y = ds.meta["gesture"].astype(str).to_numpy()
    X = make_feature_set("zhou-basic", {"descriptors": ["D1"]}, ds.sensor).fit(ds.captures, y).transform(ds.captures)
    cov = LinearDiscriminantAnalysis(solver="lsqr", store_covariance=True).fit(X, y).covariance_
    assert (row["captures"], row["classes"], row["columns"]) == (32, 4, X.shape[1])
    assert row["condition"] == pytest.approx(np.linalg.cond(cov), rel=1e-6)
    text = CliRunner().invoke(cli, ["features", "condition", str(path), "--fold", "f0"])
    assert text.exit_code == 0, text.output
    assert text.output.startswith("training part of fold f0: 16 captures, 4 classes")
    assert "condition number" in text.output
    # after a run, the features come from the run's feature cache: the same number
    run = CliRunner().invoke(cli, ["run", str(path), "--out", str(tmp_path / "res")])
    assert run.exit_code == 0, run.output
    again = CliRunner().invoke(cli, ["features", "condition", str(path), "--json"])
    assert json.loads(again.output)[0]["condition"] == pytest.approx(row["condition"], rel=1e-12)
