"""Fusion as a method (``fusion``, ``touch-rocket-fusion``): parts' probabilities summed with weights chosen
inside the training subjects only.

Stub parts read their probabilities from the captures themselves (a row of
the first frame holds them, one value per class), so every fused
probability and every weight vector's pooled inner accuracy below is worked
out by hand. The end-to-end test fits real cheap parts (flagg-stats ->
zhou-lda, a small MiniRocket) and recomputes the inner accuracies and the
fused probabilities with the parts fitted directly, by scikit-learn's own
splitter.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.model_selection import LeaveOneGroupOut

from helpers import run_loso_method

from touchbench.classifiers import CLASSIFIERS, make_classifier
from touchbench.classifiers.fitting import FittedEstimator, labels_are_argmax
from touchbench.classifiers.fusion import default_weights, pooled_accuracies, weight_grid
from touchbench.classifiers.inner import proba_over
from touchbench.core.errors import TouchbenchError
from touchbench.core.introspect import sensor_problem
from touchbench.datasets.model import SensorSpec
from touchbench.engine.testing import SENSOR, random_dataset
from touchbench.features.base import make_feature_set
from touchbench.methods import expand_candidates, method_spec

STUB_SENSOR = SensorSpec("stub-3x4", (3, 4), 10.0, (0.0, 1.0))


class StubProba(ClassifierMixin, BaseEstimator):
    """Takes captures; its probability for class code k of capture c is ``c[0, row, g_k]``, ``g_k`` the
    class index written in the training captures (``c[0, 2, 0]``); ``ignore``: a class index it
    acts as if it never saw (no column for it)."""

    def __init__(self, row=0, ignore=-1, random_state=None):
        self.row = row
        self.ignore = ignore
        self.random_state = random_state

    def fit(self, X, y):
        codes = np.asarray(y)
        index = {int(k): int(round(c[0, 2, 0])) for c, k in zip(X, codes)}
        self.classes_ = np.array([k for k in sorted(index) if index[k] != self.ignore])
        self.index_ = [index[k] for k in self.classes_]
        return self

    def predict_proba(self, X):
        return np.array([[c[0, self.row, g] for g in self.index_] for c in X], dtype=np.float64)

    def predict(self, X):
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]


def _stub(random_state=None, row=0, ignore=-1):
    return StubProba(row=row, ignore=ignore, random_state=random_state)


@pytest.fixture
def stub():
    """``stub-proba`` registered for the test only."""
    CLASSIFIERS.names()  # the real entries first
    CLASSIFIERS.register("stub-proba", description="test only: probabilities read from the capture",
                         input="captures")(_stub)
    try:
        yield
    finally:
        CLASSIFIERS._entries.pop("stub-proba", None)


A = {"label": "A", "features": [], "estimator": "stub-proba", "params": {"row": 0}}
B = {"label": "B", "features": [], "estimator": "stub-proba", "params": {"row": 1}}
LABELS = ("a", "b", "c")


def capture(true: int, pa, pb) -> np.ndarray:
    """One 1-frame capture: part A's probabilities in row 0, part B's in row 1, the class index in row 2."""
    c = np.zeros((1, 3, 4))
    c[0, 0, :len(pa)], c[0, 1, :len(pb)], c[0, 2, 0] = pa, pb, true
    return c


#: two classes (a, b); which weight w on A (w, 1 - w) labels each capture right, by hand:
#: 1: a = 0.2 + 0.7w vs b = 0.8 - 0.7w: right for w > 3/7 (0.5, 0.75, 1)
#: 2: a = 0.1 + 0.5w vs b = 0.9 - 0.5w: right (b) for w < 0.8 (0, 0.25, 0.5, 0.75)
#: 3: a = 0.7 - 0.5w vs b = 0.3 + 0.5w: right for w < 0.4 (0, 0.25)
#: 4: a = 0.55 - 0.15w vs b = 0.45 + 0.15w: right (b) for w > 1/3 (0.5, 0.75, 1)
#: 5: a = 0.6 - 0.15w vs b = 0.4 + 0.15w: right (b) for w > 2/3 (0.75, 1)
DESIGN = [(0, (0.9, 0.1), (0.2, 0.8)), (1, (0.6, 0.4), (0.1, 0.9)), (0, (0.2, 0.8), (0.7, 0.3)),
          (1, (0.4, 0.6), (0.55, 0.45)), (1, (0.45, 0.55), (0.6, 0.4))]
#: right answers per w in 0, 0.25, 0.5, 0.75, 1 over the five captures: 2, 2, 3, 4, 3
BY_HAND_5 = [2 / 5, 2 / 5, 3 / 5, 4 / 5, 3 / 5]
#: over the first four: 2, 2, 3, 3, 2 (0.5 and 0.75 tie)
BY_HAND_4 = [2 / 4, 2 / 4, 3 / 4, 3 / 4, 2 / 4]


def design(n: int = 5):
    """The design's captures twice, once per subject (each subject holds both classes)."""
    caps = [capture(t, pa, pb) for t, pa, pb in DESIGN[:n]] * 2
    y = np.array([LABELS[t] for t, _, _ in DESIGN[:n]] * 2)
    return caps, y, np.repeat(["s1", "s2"], n)


def test_default_weight_grids():
    assert default_weights(2) == [(0.0, 1.0), (0.25, 0.75), (0.5, 0.5), (0.75, 0.25), (1.0, 0.0)]
    assert default_weights(3) == [(1 / 3, 1 / 3, 1 / 3), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    assert weight_grid([(1, 3), (2, 0)], 2).tolist() == [[0.25, 0.75], [1.0, 0.0]]
    for bad in ([(1, 2, 3)], [(-1, 2)], [(0, 0)], [(np.nan, 1)]):
        with pytest.raises(TouchbenchError, match="weight"):
            weight_grid(bad, 2)
    # no vector at all: outside the declared domain, refused when the fusion is fitted
    with pytest.raises(TouchbenchError, match=r"'weights' parameter of Fusion must be None or a non-empty list"):
        make_classifier("fusion", weights=[]).fit([np.zeros((4, 2, 2))] * 2, ["a", "b"])


def test_the_weight_with_the_best_pooled_inner_accuracy_is_chosen(stub):
    caps, y, groups = design()
    est = make_classifier("fusion", random_state=0, sensor=STUB_SENSOR, parts=[A, B]).fit(caps, y, groups=groups)
    assert est.cv_results_["accuracy"] == pytest.approx(BY_HAND_5)
    assert est.weights_.tolist() == [0.75, 0.25]
    assert est.selection_note_ == ("fusion chose weights 0.75/0.25 (A / B) by pooled inner CV (one training subject "
                                   "left out at a time): 0/1 40.0 %, 0.25/0.75 40.0 %, 0.5/0.5 60.0 %, "
                                   "0.75/0.25 80.0 %, 1/0 60.0 %")
    # the fused probabilities: 0.75 * A + 0.25 * B, by hand
    new = [capture(0, (0.9, 0.1), (0.2, 0.8)), capture(1, (0.3, 0.7), (1.0, 0.0))]
    assert est.predict_proba(new) == pytest.approx(np.array([[0.725, 0.275], [0.475, 0.525]]))
    assert est.predict(new).tolist() == ["a", "b"]


def test_equal_inner_accuracies_go_to_the_weight_listed_first(stub):
    caps, y, groups = design(4)
    est = make_classifier("fusion", sensor=STUB_SENSOR, parts=[A, B]).fit(caps, y, groups=groups)
    assert est.cv_results_["accuracy"] == pytest.approx(BY_HAND_4)
    assert est.weights_.tolist() == [0.5, 0.5]
    listed = make_classifier("fusion", sensor=STUB_SENSOR, parts=[A, B], weights=[(1, 3), (3, 1), (1, 1)])
    assert listed.fit(caps, y, groups=groups).weights_.tolist() == [0.75, 0.25]  # 3/4 each for (3, 1) and (1, 1)


def test_a_class_a_part_never_saw_gets_nothing_from_it(stub):
    caps = [capture(t, (0.2, 0.3, 0.5), (0.6, 0.4, 0.0)) for t in (0, 1, 2, 0, 1, 2)]
    y, groups = np.array([LABELS[t] for t in (0, 1, 2, 0, 1, 2)]), np.repeat(["s1", "s2"], 3)
    blind = {**B, "params": {"row": 1, "ignore": 2}}  # part B has no column for class c
    est = make_classifier("fusion", sensor=STUB_SENSOR, parts=[A, blind], weights=[(1, 1)]).fit(caps, y, groups=groups)
    new = capture(0, (0.1, 0.2, 0.7), (0.3, 0.6, 0.9))  # B's 0.9 for c is never read
    assert est.predict_proba([new]) == pytest.approx(np.array([[0.5 * 0.1 + 0.5 * 0.3, 0.5 * 0.2 + 0.5 * 0.6, 0.5 * 0.7]]))
    assert est.predict([new]).tolist() == ["b"]  # 0.4 against 0.35 for c and 0.2 for a
    # the shared piece on its own: a one-class part and a part without probabilities
    classes = np.array(["a", "b", "c"])
    assert proba_over(FittedEstimator(np.array(["b"]), None), np.zeros((2, 1)), classes).tolist() == [[0, 1, 0]] * 2


def test_without_inner_folds_the_first_weights_listed_are_taken(stub):
    caps, y, _ = design(2)  # one capture per class and no subjects: no inner folds
    est = make_classifier("fusion", sensor=STUB_SENSOR, parts=[A, B]).fit(caps[:2], y[:2])
    assert est.weights_.tolist() == [0.0, 1.0] and np.isnan(est.cv_results_["accuracy"]).all()
    assert est.selection_note_.startswith("fusion took the first weights listed, 0/1 (A / B): no inner folds")


def test_a_part_the_sensor_refuses_refuses_the_fusion_and_is_named():
    long_window = {"label": "windows", "features": [{"name": "touch-windows", "params": {"window_s": 5.0}}],
                   "estimator": "zhou-lda"}
    stats = {"label": "stats", "features": ["flagg-stats"], "estimator": "zhou-lda"}
    est = make_classifier("fusion", sensor=SENSOR, parts=[stats, long_window])
    problem = sensor_problem(est, SENSOR, 8)  # 5-s windows at 10 Hz: 50 frames
    assert problem.startswith("part windows: touch-windows: ") and "shortest capture (8 frames)" in problem
    assert sensor_problem(make_classifier("fusion", sensor=SENSOR, parts=[stats, stats | {"label": "again"}]),
                          SENSOR, 8) is None
    ds = random_dataset(subjects=("s1", "s2"), per_cell=2)
    with pytest.raises(TouchbenchError, match="fusion cannot serve this data: part windows: touch-windows"):
        est.fit(ds.captures, ds.meta["gesture"].to_numpy(), groups=ds.meta["subject"].to_numpy())
    with pytest.raises(TouchbenchError, match="fusion needs at least 2 parts, got 1"):
        make_classifier("fusion", sensor=SENSOR, parts=[stats]).fit(ds.captures, ds.meta["gesture"].to_numpy())


CHEAP = [{"label": "lda", "features": ["flagg-stats"], "estimator": "zhou-lda"},
         {"label": "rocket", "features": [], "estimator": "minirocket", "params": {"n_kernels": 84}}]


def _fit_by_hand(tr_caps, tr_y, seed):
    """Both cheap parts fitted directly on their own input (codes of the sorted classes)."""
    classes, codes = np.unique(tr_y, return_inverse=True)
    fs = make_feature_set("flagg-stats", {}, SENSOR).fit(tr_caps)
    lda = make_classifier("zhou-lda", random_state=seed).fit(fs.transform(tr_caps), codes)
    rocket = make_classifier("minirocket", random_state=seed, sensor=SENSOR, n_kernels=84).fit(tr_caps, codes)

    def proba(caps):  # over ``classes``; the ridge's one-hot of its prediction for MiniRocket
        onehot = np.eye(len(classes))[rocket.predict(caps)]
        return lda.predict_proba(fs.transform(caps)), onehot

    return classes, proba


def test_cheap_real_parts_end_to_end():
    pytest.importorskip("aeon")
    ds = random_dataset(subjects=("s1", "s2", "s3"), per_cell=3, seed=2)
    caps, y, groups = ds.captures, ds.meta["gesture"].to_numpy(), ds.meta["subject"].to_numpy()
    est = make_classifier("fusion", random_state=4, sensor=SENSOR, parts=CHEAP).fit(caps, y, groups=groups)
    # inner accuracies: every part fitted by hand on each training-subject split, pooled
    P_lda, P_rocket = np.zeros((len(y), 3)), np.zeros((len(y), 3))
    for tr, te in LeaveOneGroupOut().split(np.zeros((len(y), 1)), y, groups):
        _, proba = _fit_by_hand([caps[i] for i in tr], y[tr], 4)
        P_lda[te], P_rocket[te] = proba([caps[i] for i in te])
    classes = np.unique(y)
    for w, acc in zip((0.0, 0.25, 0.5, 0.75, 1.0), est.cv_results_["accuracy"]):
        assert acc == pytest.approx(np.mean(classes[np.argmax(w * P_lda + (1 - w) * P_rocket, axis=1)] == y))
    # the refit: both parts on every training capture, weighed with the chosen weights
    test = random_dataset(subjects=("s9",), per_cell=2, seed=3).captures
    _, proba = _fit_by_hand(caps, y, 4)
    lda_p, rocket_p = proba(test)
    w = est.weights_
    assert est.predict_proba(test) == pytest.approx(w[0] * lda_p + w[1] * rocket_p)
    assert np.allclose(est.predict_proba(test).sum(axis=1), 1.0)
    assert set(est.predict(test)) <= set(classes)
    assert labels_are_argmax(est)  # the engine asks once for labels and probabilities
    assert est.predict(test).tolist() == classes[np.argmax(w[0] * lda_p + w[1] * rocket_p, axis=1)].tolist()
    # same data and seed: bit-identical
    again = make_classifier("fusion", random_state=4, sensor=SENSOR, parts=CHEAP).fit(caps, y, groups=groups)
    assert np.array_equal(again.predict_proba(test), est.predict_proba(test))
    assert again.selection_note_ == est.selection_note_


def test_touch_rocket_fusion_is_touch_et_contact_and_minirocket():
    m = method_spec("touch-rocket-fusion")
    contact = method_spec("touch-et-contact")
    assert m.estimator == "fusion" and not m.feature_sets
    first, second = m.estimator_params["parts"]
    assert first == {"label": "touch-et-contact", "features": [[n, dict(p)] for n, p in contact.feature_sets],
                     "estimator": contact.estimator, "params": dict(contact.estimator_params)}
    assert second == {"label": "minirocket", "features": [], "estimator": "minirocket", "params": {}}
    assert make_classifier("fusion", **m.estimator_params).weights is None  # the default grid
    with pytest.raises(TouchbenchError, match="'zhou-lda' is not a registered method"):
        expand_candidates("fusion", {"parts": ["zhou-lda"]})  # takes a feature matrix, not captures


def test_through_the_engine_every_task_says_which_weights(tmp_path, engine_env):
    s = run_loso_method(tmp_path, """\
  - name: fusion
    params:
      parts:
        - {label: mean-logreg, features: [test-mean], estimator: test-logreg}
        - {label: centered-forest, features: [test-centered], estimator: test-forest, params: {n_estimators: 5}}
""").scores
    assert (s["status"] == "ok").all() and len(s) == 4
    assert all("by pooled inner CV (one training subject left out at a time)" in n for n in s["notes"])
    assert set(s["notes"].str.extract(r"fusion chose weights (\S+)")[0]) <= {"0/1", "0.25/0.75", "0.5/0.5",
                                                                              "0.75/0.25", "1/0"}


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 4), st.integers(2, 4), st.integers(1, 6), st.data())
def test_pooled_accuracy_is_the_argmax_of_the_weighted_sum_row_by_row(k, n_classes, n, data):
    unit = st.sampled_from([i / 8 for i in range(9)])  # eighths: every weighted sum below is exact in float64
    probas = [data.draw(arrays(np.float64, (n, n_classes), elements=unit)) for _ in range(k)]
    W = data.draw(arrays(np.float64, (3, k), elements=st.sampled_from([0.0, 0.25, 0.5, 0.75, 1.0])))
    codes = data.draw(arrays(np.int64, n, elements=st.integers(0, n_classes - 1)))
    got = pooled_accuracies(probas, codes, np.ones(n, dtype=bool), W)
    for m in range(3):
        right = 0
        for i in range(n):
            scores = [sum(W[m, j] * probas[j][i, c] for j in range(k)) for c in range(n_classes)]
            best = max(range(n_classes), key=lambda c: (scores[c], -c))  # the first of equal sums
            right += best == codes[i]
        assert got[m] == pytest.approx(right / n)
