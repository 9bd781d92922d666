"""What the run engine does beside fit and predict keeps its results: the three scores of every task
equal scikit-learn's to the last bit without going through its scorers, the reports merged from
this session's rows in memory are those merged from the fragments, and a dataset read from the
cache is hashed once, at conversion, and trusted only while its file is the one that was hashed."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.metrics import accuracy_score, balanced_accuracy_score, f1_score

from touchbench.evaluation import metrics as metrics_module
from touchbench.evaluation.metrics import metrics

LABELS = st.sampled_from(["a", "b", "c", "d", "e"])


def _sklearn(y_true, y_pred) -> dict[str, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {"accuracy": accuracy_score(y_true, y_pred),
                "balanced_accuracy": balanced_accuracy_score(y_true, y_pred),
                "macro_f1": f1_score(y_true, y_pred, average="macro")}


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(LABELS, LABELS), min_size=1, max_size=60))
def test_the_scores_are_scikit_learns_to_the_last_bit(pairs):
    y_true = np.array([t for t, _ in pairs], dtype=object)
    y_pred = np.array([p for _, p in pairs], dtype=object)
    assert metrics(y_true, y_pred) == _sklearn(y_true, y_pred)  # exact: no tolerance


@pytest.mark.parametrize("y_true, y_pred", [
    (["a", "a", "b", "b"], ["a", "a", "a", "a"]),  # a class never predicted
    (["a", "a", "a"], ["a", "b", "c"]),  # predicted classes absent from the truth
    (["a", "b", "c"], ["a", "b", "c"]),  # perfect
    (["a"], ["b"]),  # one capture, wrong
    (["x", "y", "z", "x", "y", "z", "x"], ["y", "z", "x", "x", "y", "y", "z"]),
])
def test_degenerate_predictions_score_as_scikit_learn(y_true, y_pred):
    assert metrics(np.array(y_true), np.array(y_pred)) == _sklearn(y_true, y_pred)


def test_hand_worked_scores():
    # truth a a b b, predicted a b b c: recall a 1/2, b 1/2 -> balanced 0.5;
    # F1 = 2tp / (2tp + fp + fn): a 2/3, b 2/4, c (predicted, never true) 0
    got = metrics(np.array(["a", "a", "b", "b"]), np.array(["a", "b", "b", "c"]))
    assert got["accuracy"] == 0.5
    assert got["balanced_accuracy"] == 0.5
    assert got["macro_f1"] == pytest.approx((2 / 3 + 2 / 4 + 0) / 3)


def test_the_task_scores_do_not_go_through_scikit_learns_scorers(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a scikit-learn scorer was called for the fixed scores")
    monkeypatch.setattr(metrics_module, "scorer_values", refuse, raising=False)
    import sklearn.metrics
    monkeypatch.setattr(sklearn.metrics, "get_scorer", refuse)
    assert metrics(np.array(["a", "b"]), np.array(["a", "a"]))["accuracy"] == 0.5
