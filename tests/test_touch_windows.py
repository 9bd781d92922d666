"""``touch-windows``: the own feature sets' mean and sd over windows of a capture.

Hand-worked capture: cell (2, 5) taps as a 3 Hz square wave (on 9 frames,
off 9, at 54 frames/s) during the first quarter of a 432-frame capture and
is 0 afterwards. The four 2-s windows are the four quarters (108 frames);
the first holds 6 periods, so its total-pressure spectrum peaks at 3 Hz
(a bin: 108 frames give 0.5 Hz steps); the three others are constant, so
their peak frequency takes the limit 0. Over the windows: mean 3/4 Hz,
population sd sqrt(9/4 - 9/16) = sqrt(27)/4 Hz.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import captures_strategy
from hypothesis import HealthCheck, given, settings

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES
from touchbench.features.touch_windows import TouchWindows

HAART = SensorSpec(name="haart", grid=(8, 8), frame_rate=54.0)


def tap_then_rest() -> np.ndarray:
    c = np.zeros((432, 8, 8), dtype=np.uint16)
    t = np.arange(108)
    c[t[(t // 9) % 2 == 0], 2, 5] = 100
    return c


def test_quarters_of_a_haart_capture():
    fs = TouchWindows(sensor=HAART).fit([tap_then_rest()])
    row = dict(zip(fs.get_feature_names_out(), fs.transform([tap_then_rest()])[0]))
    assert row["win_mean_P_fpeak"] == pytest.approx(0.75)
    assert row["win_sd_P_fpeak"] == pytest.approx(np.sqrt(27) / 4)
    # active fraction of frames (touch-rhythm): 1/2 in the tapping window, 0 when nothing happens
    assert row["win_mean_active_frac"] == pytest.approx(0.125)
    # the names: every inner feature twice, mean then sd
    inner = sum(len(FEATURES.create(n, sensor=HAART).feature_names((8, 8))) for n in ("touch-rhythm", "cell-rhythm", "contact-motion"))
    assert len(row) == 2 * inner


@pytest.mark.parametrize("t,starts,length", [(432, [0, 108, 216, 324], 108), (200, [0, 31, 61, 92], 108),
                                             (100, [0, 0, 0, 0], 100), (1, [0, 0, 0, 0], 1)])
def test_window_starts(t, starts, length):
    got, n = TouchWindows(sensor=HAART).window_starts(t)
    assert got.tolist() == starts and n == length


def test_each_window_is_its_own_capture():
    rng = np.random.default_rng(0)
    cap = rng.integers(0, 1024, size=(150, 3, 4)).astype(np.uint16)
    fs = TouchWindows(n_windows=3, window_s=1.0, sets=("cell-rhythm",), sensor=HAART).fit([cap])
    # windows of 54 frames starting at 0, 48, 96: the inner set on each slice, by the registry
    inner = FEATURES.create("cell-rhythm", sensor=HAART).fit([cap])
    W = np.vstack([inner.transform([cap[s:s + 54]]) for s in (0, 48, 96)])
    np.testing.assert_allclose(fs.transform([cap])[0], np.concatenate([W.mean(axis=0), W.std(axis=0)]), rtol=1e-12, atol=1e-12)


def test_shorter_than_a_window_has_no_spread():
    cap = np.random.default_rng(1).integers(0, 1024, size=(30, 8, 8)).astype(np.uint16)
    fs = TouchWindows(sensor=HAART).fit([cap])
    x = fs.transform([cap])[0]
    half = len(x) // 2
    np.testing.assert_allclose(x[half:], 0.0, atol=1e-9)
    whole = np.hstack([FEATURES.create(n, sensor=HAART).fit([cap]).transform([cap])[0]
                       for n in ("touch-rhythm", "cell-rhythm", "contact-motion")])
    np.testing.assert_allclose(x[:half], whole, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("params,field", [({"n_windows": 0}, "n_windows"), ({"window_s": -2.0}, "window_s"),
                                          ({"sets": ("msd",)}, "sets")])
def test_bad_parameters_refused(params, field):
    with pytest.raises(ValueError, match=field):
        TouchWindows(**params, sensor=HAART).fit([tap_then_rest()])


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(caps=captures_strategy(max_frames=150))
def test_finite_fixed_length_and_batch_invariant(caps):
    fs = TouchWindows(sensor=HAART).fit(caps)
    X = fs.transform(caps)
    assert X.shape == (len(caps), len(fs.feature_names(caps[0].shape[1:])))
    assert np.isfinite(X).all()
    half = X.shape[1] // 2
    assert (X[:, half:] >= 0).all()  # standard deviations
    alone = np.vstack([fs.transform([c]) for c in caps])
    np.testing.assert_allclose(alone, X, rtol=1e-9, atol=1e-9)
