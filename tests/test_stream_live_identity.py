"""A live decision on the 19 x 27 skin is the plain computation's, exactly.

The recogniser's live path computes the windows' features through one kept
``FeatureStack`` (captures checked once, the touch sets' pressure shared,
the sets' parameters checked once) and the forest's probabilities by the
flat walk. Here a synthetic 19 x 27 stream at 10 Hz is pushed one frame at a
time through a ``WindowRecognizer`` (windows 0.5 s + 1 s, hop 0.1 s) over a
fitted ``touch-et`` and ``touch-et-fast``, and every decision is compared,
bit for bit, with the one worked out the plain way: each window's features by
each set's own ``_transform_batch`` (its own pressure), one window at a time,
put side by side, the probabilities by scikit-learn's ``predict_proba`` on the
forest's columns, the deciding window the one with the highest best
probability (the shorter on a tie) and the label the max rule's.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import synthetic_captures

from touchbench.classifiers.fitting import FittedMethod
from touchbench.datasets.model import SensorSpec
from touchbench.methods import METHODS
from touchbench.methods.fitting import fit_method
from touchbench.streams.recognizer import WindowRecognizer

SKIN = SensorSpec(name="skin", grid=(19, 27), frame_rate=10.0, value_range=(0.0, 255.0))
LENGTHS = (5, 10)  # 0.5 s and 1 s at 10 Hz


def _stream(seed: int) -> tuple[np.ndarray, list[np.ndarray], list[str]]:
    """A stream of touches and rest, and training windows of both lengths labelled by what they hold."""
    caps = synthetic_captures(seed, 30, SKIN.grid, np.float32)
    rest = np.random.default_rng(seed).uniform(0, 4, (40, *SKIN.grid)).astype(np.float32)
    stream = np.concatenate([rest[:20], caps[0], rest[20:], caps[1], caps[2][:15]])
    windows, labels = [], []
    for name, c in (("touch-a", caps[0]), ("touch-b", caps[1]), ("touch-b", caps[3]), ("idle", rest)):
        for L in LENGTHS:
            for e in range(L, len(c) + 1, 3):
                windows.append(c[e - L:e])
                labels.append(name)
    return stream, windows, labels


def _plain_proba(fm: FittedMethod, window: np.ndarray) -> np.ndarray:
    """One window's probabilities over ``fm.classes``: each set's rows computed on its own, then
    scikit-learn's forest."""
    stack = window[None]
    X = np.hstack([np.asarray(fs._transform_batch(stack), dtype=np.float64) for fs in fm.sets])
    forest, columns = fm.estimator.forest_and_columns()
    raw = forest.predict_proba(X if columns is None else X[:, columns])
    P = np.zeros(len(fm.classes))
    P[np.asarray(forest.classes_).astype(np.int64)] = raw[0]
    return P


@pytest.mark.parametrize("method", ["touch-et-fast", "touch-et"])
def test_live_decisions_are_the_plain_computation_bit_for_bit(method):
    stream, windows, labels = _stream(3)
    fm = fit_method(METHODS.create(method), 0, windows, labels, sensor=SKIN)
    classes = [str(c) for c in fm.classes]
    rec = WindowRecognizer(fm.window_proba, classes, SKIN, (0.5, 1.0), dtype=stream.dtype, hop_s=0.1, threshold=0.5)
    decided = [(i + 1, d) for i, f in enumerate(stream) if (d := rec.push(f)) is not None]
    assert [n for n, _ in decided] == list(range(5, len(stream) + 1))  # the first at 5 frames, then every frame
    for n, d in decided:
        full = [L for L in LENGTHS if n >= L]
        P = np.stack([_plain_proba(fm, stream[n - L:n]) for L in full])
        k = int(np.argmax(P.max(axis=1)))
        best = int(np.argmax(P[k]))
        assert d.probability == P[k, best]
        assert d.best == classes[best]
        assert d.label == (classes[best] if P[k, best] >= 0.5 else "none")
        assert d.window_s == full[k] / 10.0
        assert [w["probability"] for w in d.windows] == [float(p.max()) for p in P]
    assert len({d.best for _, d in decided}) > 1  # the stream is not decided alike throughout


def test_a_kept_stack_gives_the_rows_of_a_fresh_one():
    """Batches of several windows of both lengths, mixed: the kept stack's rows are each set's own
    ``transform`` side by side, in input order."""
    stream, windows, labels = _stream(5)
    fm = fit_method(METHODS.create("touch-et"), 0, windows, labels, sensor=SKIN)
    fm.transform(windows[:2])  # the stack is kept from here on
    batch = [stream[e - L:e] for e in (12, 30, 47) for L in (10, 5)]
    expected = np.hstack([fs.transform(batch) for fs in fm.sets])
    assert np.array_equal(fm.transform(batch), expected)
    assert np.array_equal(fm.transform(batch[3:4]), expected[3:4])
