"""The faster feature sets give the values of their slower reference computation.

touch-rhythm, cell-rhythm, contact-motion, contact-evidence and touch-windows
against the one-statistic-at-a-time (one-window-at-a-time) code they replaced
(tests/features_reference.py);
the radix sort of 8- and 16-bit readings (msd, sd's median, contact-evidence's
levels) against numpy's default sort and ``numpy.median``. On real HAART
captures (the real-data pattern: fails under CI=true without the data), on
short windows of a 19 x 27 skin (the live case) and on synthetic captures of
several dtypes, lengths (padded ones included) and grids. Agreement within
1e-9, relative or absolute: the fast code sums in another order.
"""

from __future__ import annotations

import numpy as np
import pytest
from features_reference import RefCellRhythm, RefContactEvidence, RefContactMotion, RefTouchRhythm, RefTouchWindows
from helpers import synthetic_captures
from numpy.testing import assert_allclose, assert_array_equal

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES
from touchbench.features.contact import ContactEvidence
from touchbench.features.gaus_sd import median_rows
from touchbench.features.numerics import sort_last
from touchbench.features.touch import CellRhythm, ContactMotion, TouchRhythm
from touchbench.features.touch_windows import TouchWindows

PAIRS = [(TouchRhythm, RefTouchRhythm), (CellRhythm, RefCellRhythm), (ContactMotion, RefContactMotion),
         (ContactEvidence, RefContactEvidence)]
SKIN = SensorSpec(name="skin", grid=(19, 27), frame_rate=10.0, value_range=(0.0, 255.0))
FLIPPED = SensorSpec(name="flipped", grid=(5, 7), frame_rate=20.0, value_range=(0.0, 1023.0), higher_is_more_pressure=False)
TOL = {"rtol": 1e-9, "atol": 1e-9}


def both(fast_cls, ref_cls, caps, sensor):
    fast = fast_cls(sensor=sensor).fit(caps).transform(caps)
    ref = ref_cls(sensor=sensor).fit(caps).transform(caps)
    return fast, ref


@pytest.mark.parametrize("fast_cls, ref_cls", PAIRS)
def test_real_haart_captures_agree_with_the_reference(real_haart, fast_cls, ref_cls):
    caps = real_haart.captures[::83]  # ten captures spread over subjects, gestures and substrates
    fast, ref = both(fast_cls, ref_cls, caps, real_haart.sensor)
    assert_allclose(fast, ref, **TOL)


@pytest.mark.parametrize("fast_cls, ref_cls", PAIRS)
@pytest.mark.parametrize("t", [5, 10])
@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_short_skin_windows_agree_with_the_reference(fast_cls, ref_cls, t, dtype):
    caps = synthetic_captures(t, t, SKIN.grid, dtype)
    fast, ref = both(fast_cls, ref_cls, caps, SKIN)
    assert_allclose(fast, ref, **TOL)


@pytest.mark.parametrize("fast_cls, ref_cls", PAIRS)
@pytest.mark.parametrize("t, grid, dtype, sensor", [
    (64, (8, 8), np.uint16, SensorSpec(name="haart", grid=(8, 8), frame_rate=54.0)),
    (31, (5, 7), np.float64, FLIPPED),
    (1, (3, 4), np.int16, SensorSpec(name="tiny", grid=(3, 4), frame_rate=12.0, value_range=(0.0, 255.0))),
])
def test_synthetic_captures_agree_with_the_reference(fast_cls, ref_cls, t, grid, dtype, sensor):
    caps = synthetic_captures(t, t, grid, dtype)
    fast, ref = both(fast_cls, ref_cls, caps, sensor)
    assert_allclose(fast, ref, **TOL)


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int16, np.int32, np.float32, np.float64, np.bool_])
def test_radix_sort_gives_numpys_sorted_values(dtype):
    rng = np.random.default_rng(3)
    x = rng.integers(-300, 1024, (3, 5, 41)).astype(dtype)
    assert_array_equal(sort_last(x), np.sort(x, axis=-1))
    assert_array_equal(median_rows(x.reshape(3, -1)), np.median(x.reshape(3, -1).astype(np.float64), axis=1))


def test_msd_quartiles_are_numpys_hazen_quantiles(real_haart):
    """msd's quartiles come from each cell's value counts (a sort where the counts would be too many):
    numpy's hazen quantiles of the cell series."""
    caps = real_haart.captures[:12]
    msd = FEATURES.create("msd", sensor=real_haart.sensor).fit(caps)
    x = msd.transform(caps).reshape(len(caps), 12, 64)
    series = np.stack(caps).reshape(len(caps), caps[0].shape[0], 64).astype(np.float64)
    q = np.quantile(series, [0.25, 0.5, 0.75], axis=1, method="hazen")
    assert_array_equal(x[:, 3:6], np.moveaxis(q, 0, 1))


@pytest.mark.parametrize("caps_at", [slice(0, 20), slice(None, None, 83)])
def test_touch_windows_agree_with_the_reference_on_real_haart(real_haart, caps_at):
    """touch-windows against its window-at-a-time reference over the reference sets (the first 20
    captures hold ties in a spectrum's peak: the fast code must find the same peak)."""
    caps = real_haart.captures[caps_at]
    fast = TouchWindows(sensor=real_haart.sensor).fit(caps).transform(caps)
    ref = RefTouchWindows(sensor=real_haart.sensor).fit(caps).transform(caps)
    assert_allclose(fast, ref, **TOL)


TINY = SensorSpec(name="tiny", grid=(3, 4), frame_rate=12.0, value_range=(0.0, 255.0))


@pytest.mark.parametrize("t, grid, dtype, sensor, params", [
    # captures shorter than one window: every window is the whole capture
    (64, (8, 8), np.uint16, SensorSpec(name="haart", grid=(8, 8), frame_rate=54.0), {}),
    # windows of 6 frames, shorter than the sets need (padded), on a flipped sensor
    (40, (5, 7), np.float64, FLIPPED, {"n_windows": 3, "window_s": 0.3}),
    # two-frame windows of a large skin, two of the sets in another order
    (10, SKIN.grid, np.uint8, SKIN, {"window_s": 0.2, "sets": ("contact-motion", "touch-rhythm")}),
    # one-frame windows, seven of them overlapping
    (9, (4, 6), np.float32, TINY, {"n_windows": 7, "window_s": 1 / 12}),
    # one window; a capture of one frame
    (30, (4, 6), np.int16, TINY, {"n_windows": 1, "window_s": 1.0, "sets": ("cell-rhythm",)}),
    (1, (3, 4), np.int16, TINY, {}),
])
def test_touch_windows_agree_with_the_reference_on_synthetic_captures(t, grid, dtype, sensor, params):
    caps = synthetic_captures(t, t, grid, dtype)
    fast = TouchWindows(sensor=sensor, **params).fit(caps).transform(caps)
    ref = RefTouchWindows(sensor=sensor, **params).fit(caps).transform(caps)
    assert fast.shape == ref.shape
    assert_allclose(fast, ref, **TOL)
