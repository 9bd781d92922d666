"""gaus-boost-oob: SAMME boosting of forests fitted on weighted resamples, each weighed by its
out-of-bag error, so that forests which fit their training set perfectly still boost."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.datasets import load_iris

from touchbench.classifiers import make_classifier
from touchbench.classifiers.boosting import ResampledBoostingClassifier


class _FixedRule(ClassifierMixin, BaseEstimator):
    """A weak learner whose predictions do not depend on what it is fitted on: row ``i`` (its only
    column) gets ``PRED[i]``; it records the rows it was fitted on."""

    PRED = np.array([0, 1, 1, 1, 2, 0, 2, 2])

    def fit(self, X, y):
        self.bag_ = X[:, 0].astype(int)
        self.classes_ = np.arange(3)
        return self

    def predict(self, X):
        return self.PRED[X[:, 0].astype(int)]


class _Boost(ResampledBoostingClassifier):
    def _weak_learner(self):
        return _FixedRule()


X8 = np.arange(8, dtype=float).reshape(-1, 1)
Y8 = np.array([0, 0, 1, 1, 2, 2, 2, 2])  # the rule misses rows 1 and 5


def test_plain_boosting_stops_at_one_forest_where_the_variant_boosts_on():
    X, y = load_iris(return_X_y=True)
    plain = make_classifier("gaus-boost", random_state=0, n_trees=30, n_estimators=6).fit(X, y)
    assert (plain.n_iterations_, plain.stop_reason_) == (1, "perfect_fit")
    oob = make_classifier("gaus-boost-oob", random_state=0, n_trees=30, n_estimators=6).fit(X, y)
    assert (oob.n_iterations_, oob.stop_reason_) == (6, "n_estimators")
    assert np.all(oob.estimator_errors_ > 0) and np.all(oob.estimator_errors_ < 2 / 3)
    assert np.mean(oob.predict(X) == y) > 0.9


def test_errors_and_weights_by_hand_from_the_recorded_resamples():
    b = _Boost(n_estimators=4, random_state=3).fit(X8, Y8)
    assert b.n_iterations_ >= 2
    miss = np.array([False, True, False, False, False, True, False, False])
    w = np.full(8, 1 / 8)
    for est, err, alpha in zip(b.estimators_, b.estimator_errors_, b.estimator_weights_):
        assert len(est.bag_) == 8  # a resample of the training set's size
        oob = np.ones(8, dtype=bool)
        oob[est.bag_] = False
        want = w[oob & miss].sum() / w[oob].sum()
        assert err == pytest.approx(want)
        assert alpha == pytest.approx(math.log((1 - want) / want) + math.log(3 - 1))
        w = w * np.where(miss, math.exp(alpha), 1.0)
        w = w / w.sum()


def test_rows_of_zero_weight_are_never_drawn():
    weights = np.array([1, 1, 0, 1, 1, 0, 1, 1], dtype=float)
    b = _Boost(n_estimators=5, random_state=1).fit(X8, Y8, sample_weight=weights)
    for est in b.estimators_:
        assert not np.isin(est.bag_, [2, 5]).any()


def test_one_row_has_nothing_out_of_bag_and_keeps_its_one_learner():
    # one row: every resample is that row, nothing is out of bag, no error can be measured
    b = make_classifier("gaus-boost-oob", random_state=0, n_trees=3, n_estimators=4).fit([[1.0, 2.0]], ["a"])
    assert (b.n_iterations_, b.stop_reason_) == (1, "no_out_of_bag")
    assert list(b.estimator_weights_) == [1.0] and np.isnan(b.estimator_errors_[0])
    assert b.predict([[0.0, 0.0]])[0] == "a"


def test_unknown_parameter_is_refused():
    with pytest.raises(Exception, match="weak_error"):
        make_classifier("gaus-boost-oob", weak_error="train")
