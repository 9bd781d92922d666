"""touchbench.deploy building blocks: sliding windows, the flat forest walk,
the recogniser's schedule and thresholds, frame parsing.

Expected values are worked out by hand (window starts, decision frames,
probabilities of a hand-made classifier) or come from scikit-learn
(``predict_proba`` of the same forest).
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
from sklearn.linear_model import LogisticRegression

from touchbench.datasets.model import SensorSpec
from touchbench.classifiers.fastforest import compile_forest
from touchbench.classifiers.fitting import FittedEstimator, FittedMethod
from touchbench.deploy.model import SensorMismatchError, TrainedModel, sensor_differences
from touchbench.deploy.stream import SlidingRecognizer, replay, run_stream, text_frames
from touchbench.datasets.windows import cut_windows, seconds_to_frames
from touchbench.streams.recognizer import combine_windows
from touchbench.core.errors import DataError, TouchbenchError

SENSOR = SensorSpec("stub", grid=(2, 2), frame_rate=10.0, value_range=(0.0, 100.0))


# ----------------------------------------------------------------- windows
def test_seconds_to_frames_rounds_to_whole_frames():
    assert seconds_to_frames(2.0, 54.0) == 108
    assert seconds_to_frames(0.5, 54.0) == 27
    assert seconds_to_frames(0.01, 10.0) == 1  # at least one frame
    with pytest.raises(TouchbenchError, match="--hop must be a positive number of seconds, got 0"):
        seconds_to_frames(0, 10.0, "--hop")


def test_cut_windows_starts_and_short_captures():
    a = np.arange(10)[:, None, None] * np.ones((1, 2, 2))
    b = np.arange(3)[:, None, None] * np.ones((1, 2, 2))
    wins, src = cut_windows([a, b], lengths=[4], hops=[3])
    # T=10, L=4, hop 3: starts 0, 3, 6; capture b (3 frames) is shorter: kept whole
    assert [w[0, 0, 0] for w in wins] == [0, 3, 6, 0]
    assert [len(w) for w in wins] == [4, 4, 4, 3]
    assert src.tolist() == [0, 0, 0, 1]
    wins, src = cut_windows([a], lengths=[4, 8], hops=[6, 2])
    # L=4 hop 6: starts 0, 6; L=8 hop 2: starts 0, 2
    assert [(len(w), w[0, 0, 0]) for w in wins] == [(4, 0), (4, 6), (8, 0), (8, 2)]


def test_combine_windows_max_and_mean():
    P = np.array([[0.6, 0.4], [0.1, 0.9], [0.5, 0.5]])
    row, k = combine_windows(P, "max")
    assert k == 1 and row.tolist() == [0.1, 0.9]
    row, k = combine_windows(P, "mean")
    assert k is None and np.allclose(row, [1.2 / 3, 1.8 / 3])
    with pytest.raises(ValueError):
        combine_windows(P, "vote")


# ----------------------------------------------------------------- forest
@pytest.fixture(params=["compiled", "numpy"])
def walk(request, monkeypatch):
    """Each forest test twice: the compiled walk (where numba is installed) and the numpy walk."""
    from touchbench.core import compiled

    if request.param == "compiled":
        pytest.importorskip("numba")
    monkeypatch.setattr(compiled, "COMPILED", request.param == "compiled")
    return request.param


@pytest.mark.parametrize("make", [
    lambda: RandomForestClassifier(n_estimators=60, random_state=3, n_jobs=1),
    lambda: RandomForestClassifier(n_estimators=30, criterion="entropy", max_features=3, random_state=1, n_jobs=1),
    lambda: ExtraTreesClassifier(n_estimators=40, random_state=0, n_jobs=1),
])
def test_compiled_forest_equals_sklearn_exactly(make, walk):
    rng = np.random.default_rng(0)
    X = rng.normal(size=(150, 12))
    y = np.array(["a", "b", "c"])[rng.integers(0, 3, 150)]
    X[:, 0] += (y == "b") * 2.0
    est = make().fit(X, y)
    fast = compile_forest(est)
    assert fast is not None
    Xt = np.vstack([rng.normal(size=(25, 12)) * 3, X[:5]])
    np.testing.assert_array_equal(fast.predict_proba(Xt), est.predict_proba(Xt))
    # one row at a time, as the recogniser calls it
    np.testing.assert_array_equal(fast.predict_proba(Xt[:1]), est.predict_proba(Xt[:1]))


def test_compiled_forest_ties_and_float32_rounding_follow_sklearn(walk):
    """Inputs exactly on a split (a random forest on whole numbers splits at halves: 0.5, 1.5, ...)
    go left, as scikit-learn's ``x <= threshold``; inputs that float32 rounds onto or across a
    split follow scikit-learn's float32 reading; many rows with impure leaves (min_samples_leaf)."""
    rng = np.random.default_rng(5)
    X = rng.integers(0, 6, size=(300, 5)).astype(np.float64)
    y = (X[:, 0] + X[:, 1] + rng.integers(0, 3, 300)) % 4
    est = RandomForestClassifier(n_estimators=50, min_samples_leaf=3, random_state=2, n_jobs=1).fit(X, y)
    halves = rng.integers(0, 12, size=(400, 5)) / 2.0  # on the splits half the time
    near = halves + rng.choice([-1e-9, 0.0, 1e-9], size=halves.shape)  # float32 rounds these onto the split
    Xt = np.vstack([halves, near, rng.uniform(-1, 7, size=(200, 5))])
    fast = compile_forest(est)
    np.testing.assert_array_equal(fast.predict_proba(Xt), est.predict_proba(Xt))
    for row in Xt[:20]:
        np.testing.assert_array_equal(fast.predict_proba(row[None]), est.predict_proba(row[None]))


def test_compiled_forest_nan_falls_back_and_others_unsupported(walk):
    rng = np.random.default_rng(1)
    X = rng.normal(size=(80, 4))
    y = (X[:, 0] > 0).astype(int)
    est = RandomForestClassifier(n_estimators=10, random_state=0).fit(X, y)
    x = np.array([[np.nan, 0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(compile_forest(est).predict_proba(x), est.predict_proba(x))
    assert compile_forest(LogisticRegression().fit(X, y)) is None


@pytest.mark.parametrize("wrapped", ["selected", "tuned"])
def test_compiled_forest_sees_through_touchbench_extra_trees(wrapped, walk):
    from touchbench.classifiers.touch import NestedTunedExtraTrees, SelectedExtraTrees

    rng = np.random.default_rng(2)
    X = rng.normal(size=(120, 9))
    y = (X[:, 4] > 0).astype(int) + (X[:, 6] > 0.5)
    groups = np.repeat(np.arange(4), 30)
    if wrapped == "selected":  # 4 of 9 columns kept by importance: the forest reads a subset
        est = SelectedExtraTrees(n_estimators=25, keep=4, random_state=1).fit(X, y)
        forest, columns = est.model_, est.columns_
        assert len(columns) == 4
    else:
        est = NestedTunedExtraTrees(n_estimators=15, grid_keep=(None, 3), random_state=1).fit(X, y, groups=groups)
        forest, columns = est.model_.model_, est.model_.columns_
    fast = compile_forest(est)
    assert fast is not None
    Xt = rng.normal(size=(7, 9)) * 2
    sk = forest.predict_proba(Xt[:, columns])  # scikit-learn's own walk of the wrapped forest
    np.testing.assert_allclose(fast.predict_proba(Xt), sk, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.predict_proba(Xt[:1]), sk[:1], rtol=0, atol=1e-12)
    # a model file's fast path uses it (not the wrapper's predict_proba)
    model = TrainedModel(FittedMethod([], FittedEstimator(np.array(["a", "b", "c"], dtype=object), est)),
                         {"sensor": SENSOR.to_dict()})
    np.testing.assert_allclose(model.proba_from_features(Xt), sk, rtol=0, atol=1e-12)
    assert isinstance(model.fitted._fast, type(fast))


# ----------------------------------------------------------------- a hand-made model
class _MeanLevel:
    """Feature: the mean of every value of a window (one column)."""

    def transform(self, captures):
        return np.array([[float(np.mean(c))] for c in captures])


class _Linear(ClassifierMixin, BaseEstimator):
    """P(class 1) = feature / 100: probabilities known by hand."""

    def fit(self, X, y):
        self.classes_ = np.array([0, 1])
        return self

    def predict_proba(self, X):
        p = np.clip(np.asarray(X)[:, 0] / 100.0, 0, 1)
        return np.column_stack([1 - p, p])

    def predict(self, X):
        return (self.predict_proba(X)[:, 1] > 0.5).astype(int)


def stub_model(windows=None, dtype="<f8") -> TrainedModel:
    manifest = {
        "sensor": SENSOR.to_dict(), "windows": windows, "capture_frames": {"min": 20, "median": 20.0, "max": 20},
        "capture_dtype": dtype, "features": {"label": "mean"}, "classifier": {"label": "linear"}, "target": "gesture",
    }
    return TrainedModel(FittedMethod([_MeanLevel()], FittedEstimator(np.array(["low", "high"], dtype=object),
                                                                     _Linear().fit(None, None))), manifest)


def frames_at(levels):
    return [(np.full((2, 2), float(v)), 0.0) for v in levels]


def test_recognizer_schedule_threshold_and_windows():
    # windows 1 s and 2 s at 10 Hz: 10 and 20 frames; hop 0.5 s = 5 frames.
    rec = SlidingRecognizer(stub_model(), windows_s=[2.0, 1.0], hop_s=0.5, threshold=0.7)
    levels = [90] * 10 + [10] * 15  # 25 frames
    out = [rec.push(f, a) for f, a in frames_at(levels)]
    made = [(i + 1, d) for i, d in enumerate(out) if d is not None]
    # decisions when 10, 15, 20, 25 frames have arrived
    assert [n for n, _ in made] == [10, 15, 20, 25]
    d10, d15, d20, d25 = (d for _, d in made)
    # frame 10: only the 1-s window (mean 90): high, p = 0.9
    assert d10.label == "high" and d10.probability == pytest.approx(0.9) and d10.window_s == 1.0
    # frame 15: 1-s window = 5 x 90 + 5 x 10 -> mean 50 -> best 0.5 < 0.7 -> none
    assert d15.label == "none" and d15.best in ("low", "high") and d15.probability == pytest.approx(0.5)
    # frame 20: 1 s = ten 10s (low 0.9); 2 s = 10 x 90 + 10 x 10 -> 0.5; max picks the 1-s window
    assert d20.label == "low" and d20.probability == pytest.approx(0.9) and d20.window_s == 1.0
    assert [w["window_s"] for w in d20.windows] == [1.0, 2.0]
    # frame 25: 1 s = low 0.9; 2 s = 5 x 90 + 15 x 10 -> mean 30 -> low 0.7
    assert d25.label == "low" and d25.probability == pytest.approx(0.9)
    assert [w["probability"] for w in d25.windows] == pytest.approx([0.9, 0.7])


def test_recognizer_mean_combination_and_summary():
    rec = SlidingRecognizer(stub_model(), windows_s=[1.0, 2.0], hop_s=1.0, threshold=0.5, combine="mean")
    s = run_stream(rec, frames_at([90] * 10 + [10] * 10))
    # decisions at 10 (1 s: high 0.9) and 20 (mean of 1 s low [0.9, 0.1] and 2 s [0.5, 0.5] -> low 0.7)
    assert s.frames == 20 and s.decisions == 2 and s.labels == {"high": 1, "low": 1}
    assert s.latency_ms_p50 >= 0 and s.latency_ms_p99 >= s.latency_ms_p50


def test_recognizer_buffer_wraps_around():
    rec = SlidingRecognizer(stub_model(), windows_s=[1.0], hop_s=0.1, threshold=0.0)
    levels = list(np.linspace(0, 100, 95))
    decisions = [rec.push(f, a) for f, a in frames_at(levels)]
    last = decisions[-1]
    # the last window holds the last 10 levels, whatever the ring buffer did
    assert last.probability == pytest.approx(max(np.mean(levels[-10:]), 100 - np.mean(levels[-10:])) / 100)


def test_recognizer_defaults_and_refusals():
    rec = SlidingRecognizer(stub_model())
    assert rec.windows_s == [2.0]  # whole captures of 20 frames at 10 Hz
    rec = SlidingRecognizer(stub_model(windows={"lengths_s": [1.0, 0.5]}))
    assert rec.windows_s == [0.5, 1.0]
    with pytest.raises(TouchbenchError, match="threshold"):
        SlidingRecognizer(stub_model(), threshold=1.5)
    with pytest.raises(TouchbenchError, match="none label"):
        SlidingRecognizer(stub_model(), none_label="low")


def test_replay_without_realtime_keeps_order():
    frames = np.arange(12, dtype=float).reshape(3, 2, 2)
    got = [f for f, _ in replay(frames, 10.0, realtime=False)]
    assert [g[0, 0] for g in got] == [0.0, 4.0, 8.0]


# ----------------------------------------------------------------- frames from text
def test_text_frames_parses_and_refuses_bad_lines():
    m = stub_model(dtype="<u2")
    got = list(text_frames(io.StringIO("1,2,3,4\n\n5, 6, 7, 8\n"), m))
    assert [f.tolist() for f, _ in got] == [[[1, 2], [3, 4]], [[5, 6], [7, 8]]]
    assert got[0][0].dtype == np.uint16
    cases = [
        ("1,2,3\n", 1, "3 values"),
        ("1,2,3,4\n1,x,3,4\n", 2, "not a number"),
        ("1,2,3,400\n", 1, "outside"),
        ("1,2,3,4.5\n", 1, "whole number"),
        ("1,2,nan,4\n", 1, "NaN"),
        ("1,2,3,1_0\n", 1, "not a number: '1_0'"),  # Python's float() would read 10
        ("1,2,3,0x1f\n", 1, "not a number: '0x1f'"),
    ]
    for text, line, msg in cases:
        with pytest.raises(DataError, match=msg) as e:
            list(text_frames(io.StringIO(text), m))
        assert e.value.line == line


def test_sensor_differences_ignore_the_name_only():
    other = SensorSpec("custom", grid=(2, 2), frame_rate=10.0, value_range=(0.0, 100.0))
    assert sensor_differences(SENSOR, other) == []
    faster = SensorSpec("stub", grid=(2, 2), frame_rate=20.0, value_range=(0.0, 100.0))
    assert sensor_differences(SENSOR, faster) == ["frame_rate: model 10.0, data 20.0"]
    with pytest.raises(SensorMismatchError, match="frame_rate"):
        stub_model().check_sensor(faster)


def test_a_live_stream_reports_a_malformed_line_and_goes_on():
    m = stub_model(dtype="<u2")
    errors = []
    got = list(text_frames(io.StringIO("1,2,3,4\n1,2,3\n\n5,6,7,1_0\n5,6,7,8\n"), m, on_error=errors.append))
    assert [f.tolist() for f, _ in got] == [[[1, 2], [3, 4]], [[5, 6], [7, 8]]]
    assert [(e.line, "3 values" in str(e) or "'1_0'" in str(e)) for e in errors] == [(2, True), (4, True)]


def test_a_window_whose_frames_would_not_fit_is_refused_up_front():
    import touchbench.deploy.stream as stream

    # an 8 x 8 sensor of 2-byte values at 54 Hz: a window of 100000 s is 5 400 000 frames; the recogniser
    # keeps twice that, 10 800 000 x 128 bytes = 1318 MiB, over 512 MiB; the longest allowed is
    # 512 MiB / (2 x 128 bytes) / 54 Hz = 38836 s (at most: less when a quarter of the free memory is less)
    m = stub_model(dtype="<u2")
    m.manifest["sensor"] = SensorSpec("big", grid=(8, 8), frame_rate=54.0, value_range=(0.0, 1023.0)).to_dict()
    with pytest.raises(TouchbenchError, match=r"--window 100000 s is too long.*1318 MiB.*longest window allowed is") as e:
        SlidingRecognizer(m, windows_s=[100000])
    allowed = float(str(e.value).rsplit("allowed is ", 1)[1].split(" s")[0])
    assert allowed <= 38836 and allowed == round(stream.buffer_limit() / 256 / 54)
    SlidingRecognizer(m, windows_s=[allowed - 1])  # under the limit: built


# ----------------------------------------------------------------- the user docs
def test_readme_and_changelog_name_only_registered_file_formats():
    import re
    from pathlib import Path

    from touchbench.datasets.formats import FORMATS

    root = Path(__file__).resolve().parents[1]
    for doc in ("README.md", "CHANGELOG.md"):
        text = (root / doc).read_text()
        for fmt in re.findall(r"touchbench (?:predict|stream|data \w+) [^\n]*--format[ =]([\w-]+)", text):
            assert fmt == "auto" or fmt in FORMATS, (doc, fmt)
        # the format that became `table` is not described as a reader any more
        assert not re.search(r"\blong\s+(CSV\s+)?format\b|`long`\s+format", text), doc
