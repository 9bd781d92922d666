"""The aeon peers: MiniRocket, MultiRocket, MultiRocket-Hydra, QUANT and RDST on the cell series of raw frames.

The cell-series layout is checked on a capture whose every value names its
frame and cell; the peers are checked against aeon's own classifiers called
directly on series built independently (a loop over cells); scikit-learn's
estimator checks run on a 1 x 1 "grid". aeon is the ``peers`` extra, which
CI installs: without it these tests fail under CI=true and skip elsewhere.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys

import numpy as np
import pytest

if os.environ.get("CI", "").lower() == "true":
    import aeon  # noqa: F401  (CI installs the peers extra: a missing aeon must fail, not skip)
else:
    pytest.importorskip("aeon")

from sklearn.utils.estimator_checks import parametrize_with_checks  # noqa: E402

from touchbench.classifiers import make_classifier  # noqa: E402
from touchbench.classifiers.peers import MIN_TIMEPOINTS, frames_to_series  # noqa: E402
from helpers import SUBPROCESS_HANG_S, slow_fast_rows  # noqa: E402

# one worker of pytest-xdist runs this module whole: numba compiles each peer's aeon kernels once per
# process (most of this module's time when its cache, kept beside aeon, is empty, as in a new
# environment), so two workers taking turns at these tests would compile every kernel twice
pytestmark = pytest.mark.xdist_group("aeon")


def _labelled_capture(frames: int, h: int, w: int) -> np.ndarray:
    """value = 1000 * frame + cell (row-major), flattened frame-major as raw-window does."""
    f = np.arange(frames)[:, None, None] * 1000 + np.arange(h * w).reshape(1, h, w)
    return f.reshape(1, -1).astype(np.float64)


def test_series_layout_cell_by_frame():
    X = _labelled_capture(12, 2, 3)
    S = frames_to_series(X, (2, 3))
    assert S.shape == (1, 6, 12)
    for cell in range(6):
        for frame in range(12):
            assert S[0, cell, frame] == 1000 * frame + cell


def test_short_series_repeat_the_last_frame():
    X = _labelled_capture(3, 1, 2)
    S = frames_to_series(X, (1, 2))
    assert S.shape == (1, 2, MIN_TIMEPOINTS)
    assert S[0, 1].tolist() == [1, 1001, 2001] + [2001] * (MIN_TIMEPOINTS - 3)


def test_frames_must_fill_the_grid():
    with pytest.raises(ValueError, match="2x2 frames"):
        frames_to_series(np.zeros((1, 10)), (2, 2))


_toy = slow_fast_rows  # slow vs fast oscillations, 2 x 2 cells


#: peer -> (aeon module, aeon class, small settings given to both)
AEON = {
    "minirocket": ("convolution_based", "MiniRocketClassifier", dict(n_kernels=84, n_jobs=1)),
    "multirocket": ("convolution_based", "MultiRocketClassifier", dict(n_kernels=84, n_jobs=1)),
    "multirocket-hydra": ("convolution_based", "MultiRocketHydraClassifier", dict(n_groups=4, n_jobs=1)),
    "quant": ("interval_based", "QUANTClassifier", dict(interval_depth=3)),
    "rdst": ("shapelet_based", "RDSTClassifier", dict(max_shapelets=32, n_jobs=1)),
}


@pytest.fixture
def small_multirocket_half(monkeypatch):
    """aeon's MultiRocket-Hydra builds its MultiRocket half with MultiRocket's default 6,250 kernels (about
    50,000 features; its ridge then takes most of these tests' time) and has no parameter to change it:
    here that half gets 84 kernels, as the ``multirocket`` peer's cheap settings do. The code paths, ours
    and aeon's, are the same; aeon called directly below builds its half the same way."""
    from aeon.classification.convolution_based import _mr_hydra

    monkeypatch.setattr(_mr_hydra, "MultiRocket", functools.partial(_mr_hydra.MultiRocket, n_kernels=84))


@pytest.mark.parametrize("name", list(AEON))
def test_same_predictions_as_aeon_called_directly(name, small_multirocket_half):
    import importlib

    module, aeon_class, small = AEON[name]
    X, y = _toy()
    Xt, yt = _toy(seed=1)
    est = make_classifier(name, random_state=7, grid=(2, 2), **small).fit(X, y)
    # the same series built by hand: channel c = cell (c // 2, c % 2) over the frames
    def series(A):
        caps = A.reshape(len(A), -1, 2, 2)
        return np.stack([np.stack([caps[i, :, c // 2, c % 2] for c in range(4)]) for i in range(len(A))])
    cls = getattr(importlib.import_module(f"aeon.classification.{module}"), aeon_class)
    ref = cls(**small, random_state=7).fit(series(X), y)
    assert est.predict(Xt).tolist() == ref.predict(series(Xt)).tolist()
    assert np.allclose(est.predict_proba(Xt), ref.predict_proba(series(Xt)))
    assert np.mean(est.predict(Xt) == yt) >= 0.9  # slow vs fast is easy
    P = est.predict_proba(Xt)
    assert P.shape == (len(Xt), 2) and np.allclose(P.sum(axis=1), 1.0)
    assert list(est.classes_) == ["fast", "slow"]


@pytest.mark.parametrize("name", ["quant", "multirocket-hydra"])
def test_same_seed_same_predictions_across_fits(name, small_multirocket_half):
    """The PyTorch-backed peers are seeded: two fits with one seed predict the same probabilities."""
    X, y = _toy()
    Xt, _ = _toy(seed=2)
    small = AEON[name][2]
    a = make_classifier(name, random_state=3, grid=(2, 2), **small).fit(X, y).predict_proba(Xt)
    b = make_classifier(name, random_state=3, grid=(2, 2), **small).fit(X, y).predict_proba(Xt)
    assert np.array_equal(a, b)


def test_multirocket_hydra_pads_to_ten_frames():
    """Nine frames are too few for MultiRocket-Hydra's difference series (aeon fails on them); ten pass."""
    from touchbench.classifiers.peers import MultiRocketHydraPeer

    X = np.arange(2 * 9 * 4, dtype=np.float64).reshape(2, 36)
    est = MultiRocketHydraPeer(grid=(2, 2))
    est.grid_ = (2, 2)
    assert est._series(X).shape == (2, 4, MIN_TIMEPOINTS + 1)
    rng = np.random.default_rng(0)
    Xs, ys = rng.normal(size=(10, 9 * 4)), np.array(list("ab") * 5)
    pred = make_classifier("multirocket-hydra", random_state=0, grid=(2, 2), n_groups=4).fit(Xs, ys).predict(Xs)
    assert set(pred.tolist()) <= {"a", "b"}


def test_one_class_training_predicts_that_class():
    X, y = _toy(n_per_class=3)
    est = make_classifier("minirocket", random_state=0, grid=(2, 2), n_kernels=84).fit(X, np.full(len(y), "pat"))
    assert est.predict(X[:2]).tolist() == ["pat", "pat"]
    assert est.predict_proba(X[:2]).tolist() == [[1.0], [1.0]]


@parametrize_with_checks([make_classifier(n, random_state=0, grid=(1, 1), **AEON[n][2]) for n in AEON])
def test_sklearn_estimator_checks(estimator, check, small_multirocket_half):
    check(estimator)


_NO_AEON = r"""
import sys, importlib.abc
class _NoAeon(importlib.abc.MetaPathFinder):  # as if aeon were not installed
    def find_spec(self, name, path=None, target=None):
        if name == "aeon" or name.startswith("aeon."):
            raise ModuleNotFoundError(name)
        return None
sys.meta_path.insert(0, _NoAeon())
import numpy as np
from touchbench.classifiers import make_classifier
est = make_classifier("minirocket", random_state=0, grid=(1, 1))
try:
    est.fit(np.arange(40.0).reshape(4, 10), np.array(["a", "b", "a", "b"]))
except Exception as e:
    print(type(e).__name__, e)
"""


def test_without_aeon_the_peer_says_how_to_install():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", _NO_AEON], capture_output=True, text=True, env=env, timeout=SUBPROCESS_HANG_S)
    assert proc.returncode == 0, proc.stderr
    assert "TouchbenchError" in proc.stdout and "pip install 'touchbench[peers]'" in proc.stdout


_NO_TORCH = _NO_AEON.replace('name == "aeon" or name.startswith("aeon.")', 'name == "torch" or name.startswith("torch.")').replace(
    '"minirocket"', '"quant"')


def test_a_peer_aeon_runs_in_pytorch_says_so_without_it():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", _NO_TORCH], capture_output=True, text=True, env=env, timeout=SUBPROCESS_HANG_S)
    assert proc.returncode == 0, proc.stderr
    assert "needs torch" in proc.stdout and "pip install 'touchbench[peers,deep]'" in proc.stdout


def test_listing_does_not_import_aeon_and_marks_the_extra():
    code = ("import sys, json; from click.testing import CliRunner; from touchbench.cli.classifiers import classifiers; "
            "rows = json.loads(CliRunner().invoke(classifiers, ['list', '--json']).output); "
            "print(json.dumps({'aeon': 'aeon' in sys.modules, 'extra': {r['name']: r['extra'] for r in rows}}))")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=SUBPROCESS_HANG_S)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["aeon"] is False
    assert out["extra"]["minirocket"] == out["extra"]["multirocket"] == out["extra"]["rdst"] == "peers"
    assert out["extra"]["quant"] == out["extra"]["multirocket-hydra"] == "peers,deep"
