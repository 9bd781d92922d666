"""The compiled loops of the five Gaus et al. (2015) sets (numba, touchbench.features.gaus_kernels) give
the values of their numpy path (``compiled.COMPILED = False``) within 1e-9, relative or absolute: on
every real HAART capture (the real-data pattern: fails under CI=true without the data) and on edge
cases (one frame, constant cells, all zero, saturated at 1023, other grids, float and int16 readings,
readings too wide to count). Skipped where numba is not installed (the numpy path is then the only
one)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from helpers import compiled_and_numpy

from touchbench.datasets.haart import HAART_SENSOR
from touchbench.datasets.model import SensorSpec
from touchbench.core import compiled
from touchbench.features import base
from touchbench.features.base import FEATURES

pytest.importorskip("numba")

SETS = ["msd", "sd", "bmh", "smmhh", "lbptop"]
TOL = {"rtol": 1e-9, "atol": 1e-9}


both = compiled_and_numpy


def test_one_switch_chooses_the_numpy_path(monkeypatch):
    assert compiled.kernels("features.gaus_kernels") is not None
    monkeypatch.setattr(compiled, "COMPILED", False)
    assert compiled.kernels("features.gaus_kernels") is None
    assert compiled.kernels("features.touch_kernels") is None
    assert compiled.kernels("classifiers.forest_kernels") is None


@pytest.mark.parametrize("name", SETS)
def test_real_haart_captures_agree_with_the_numpy_path(real_haart, name, monkeypatch):
    fast, plain = both(name, real_haart.captures, real_haart.sensor, monkeypatch)
    assert_allclose(fast, plain, **TOL)


def _edge_captures(t, grid, dtype, top):
    rng = np.random.default_rng(7)
    noisy = rng.integers(0, int(top) + 1, size=(t, *grid))
    touch = np.clip(np.cumsum(rng.integers(-3, 4, size=(t, *grid)), axis=0) + 20, 0, top)
    const = np.full((t, *grid), 17)
    const[:, 0, 0] = 3  # constant cells, two levels
    return [a.astype(dtype) for a in (noisy, touch, const, np.zeros((t, *grid)), np.full((t, *grid), top))]


@pytest.mark.parametrize("name", SETS)
@pytest.mark.parametrize("t, grid, dtype, top", [(432, (8, 8), np.uint16, 1023), (1, (8, 8), np.uint16, 1023),
                                                 (2, (8, 8), np.uint16, 1023), (40, (4, 4), np.uint16, 1023),
                                                 (25, (19, 27), np.uint8, 255), (30, (8, 8), np.float64, 1023),
                                                 (30, (8, 8), np.float32, 1023), (30, (5, 7), np.int16, 1023),
                                                 (30, (8, 8), np.bool_, 1)])
def test_edge_cases_agree_with_the_numpy_path(name, t, grid, dtype, top, monkeypatch):
    sensor = HAART_SENSOR if grid == (8, 8) else SensorSpec(name="edge", grid=grid, frame_rate=54.0,
                                                            value_range=(0.0, float(top)))
    fast, plain = both(name, _edge_captures(t, grid, dtype, top), sensor, monkeypatch)
    assert_allclose(fast, plain, **TOL)


@pytest.mark.parametrize("name", ["msd", "sd", "smmhh", "lbptop"])
def test_fractional_and_wide_readings_agree_with_the_numpy_path(name, monkeypatch):
    """Readings that cannot be counted (fractions; integers spanning more values than the loops count)
    take the numpy path, capture by capture, beside counted ones in the same batch."""
    rng = np.random.default_rng(3)
    counted = rng.integers(0, 1024, size=(12, 8, 8))
    wide = counted * 100000  # a span of 1e8 in 12 frames
    caps = [counted.astype(np.int32), wide.astype(np.int32), counted.astype(np.int32) + 5]
    fast, plain = both(name, caps, HAART_SENSOR, monkeypatch)
    assert_allclose(fast, plain, **TOL)
    frac = [rng.random((12, 8, 8)) * 1023.0, np.full((12, 8, 8), 0.5)]
    fast, plain = both(name, frac, HAART_SENSOR, monkeypatch)
    assert_allclose(fast, plain, **TOL)


def test_cost_preset_and_a_frame_level_sd_agree_with_the_numpy_path(monkeypatch):
    caps = _edge_captures(60, (8, 8), np.uint16, 1023)
    for name, params in [("sd", {"preset": "cost"}), ("sd", {"preset": "haart", "clip": False, "normalize": True}),
                         ("smmhh", {"preset": "cost", "threshold": [2.5, 3.0, 7.0, 0.0]}),
                         ("lbptop", {"n_points": 4, "mapping": "none"}), ("lbptop", {"radius": (2, 1, 3)})]:
        fast, plain = both(name, caps, HAART_SENSOR, monkeypatch, **params)
        assert_allclose(fast, plain, **TOL)


@pytest.mark.parametrize("dtype", [np.uint16, np.uint8, np.int16, np.float32, np.float64, np.bool_, np.float16])
def test_bmh_at_both_levels_and_every_dtype_agrees_with_the_numpy_path(dtype, monkeypatch):
    """Counts: the two paths agree exactly, each frame's own maximum too (float16 keeps numpy's path)."""
    caps = _edge_captures(40, (8, 8), dtype, 1 if dtype is np.bool_ else 255)
    for params in [{}, {"level": "frame"}, {"offset": 0.0, "level": "frame"}, {"offset": 200.0}]:
        fast, plain = both("bmh", caps, HAART_SENSOR, monkeypatch, **params)
        np.testing.assert_array_equal(fast, plain)


def test_bmh_frame_level_on_real_haart_captures_agrees_with_the_numpy_path(real_haart, monkeypatch):
    fast, plain = both("bmh", real_haart.captures, real_haart.sensor, monkeypatch, level="frame")
    np.testing.assert_array_equal(fast, plain)


def _batch_sizes(sets, caps, monkeypatch):
    """The rows of ``sets`` side by side for ``caps``, and the number of captures of each batch."""
    sizes, batch = [], base.FeatureStack._batch

    def spy(self, captures, all_caps, part, *args):
        sizes.append(len(part))
        return batch(self, captures, all_caps, part, *args)

    with monkeypatch.context() as m:
        m.setattr(base.FeatureStack, "_batch", spy)
        return base.FeatureStack(sets).transform(caps), sizes


def test_sets_whose_loops_run_take_larger_chunks_and_the_same_rows(monkeypatch):
    """432 x 8 x 8 captures: the numpy path's bound (131072 values) stacks 4 at a time; the compiled
    loops' (2097152 values) 75. A stack with a set without loops (flagg-stats) keeps the smaller
    bound; one capture per batch gives every row bit for bit."""
    caps = _edge_captures(432, (8, 8), np.uint16, 1023) * 2  # 10 captures
    sets = [FEATURES.create(n, sensor=HAART_SENSOR).fit(caps) for n in SETS]
    rows, sizes = _batch_sizes(sets, caps, monkeypatch)
    assert sizes == [10]
    plain = FEATURES.create("flagg-stats", sensor=HAART_SENSOR).fit(caps)
    assert _batch_sizes(sets + [plain], caps, monkeypatch)[1] == [4, 4, 2]
    monkeypatch.setattr(base, "_LOOP_BATCH_VALUES", 1)
    one_by_one, sizes = _batch_sizes(sets, caps, monkeypatch)
    assert sizes == [1] * 10
    np.testing.assert_array_equal(rows, one_by_one)
    monkeypatch.setattr(compiled, "COMPILED", False)
    assert _batch_sizes(sets, caps, monkeypatch)[1] == [4, 4, 2]


@pytest.mark.parametrize("max_len", [1, 5, 254, 255, 300])
def test_smmhh_runs_longer_than_its_byte_counters_hold(max_len, monkeypatch):
    """A ramp of 2 units a frame moves at every skip on every scale (2 s * 4**k > 3 * 4**k), so each
    pixel has one run of T - s frames: counted once, in the last bin when it reaches ``max_len``
    (else in bin T - s). 600 frames outlast the compiled loop's byte counters (255 frames a block);
    ``max_len`` 255 and more take wider counters. The numpy path agrees."""
    t, skips = 600, (2, 6)
    ramp = np.broadcast_to((2 * np.arange(t))[:, None, None], (t, 8, 8)).astype(np.uint16)
    caps = [ramp, np.ascontiguousarray(ramp[::-1])]
    fast, plain = both("smmhh", caps, HAART_SENSOR, monkeypatch, skips=skips, max_len=max_len)
    np.testing.assert_array_equal(fast, plain)
    expected = np.zeros((4, len(skips), max_len, 85))  # scale blocks laid out as (skip, length, pixel)
    for si, s in enumerate(skips):
        expected[:, si, min(t - s, max_len) - 1] = 1.0
    edges = [0, 64, 80, 84, 85]
    want = np.concatenate([expected[k, :, :, edges[k]:edges[k + 1]].ravel() for k in range(4)])
    np.testing.assert_array_equal(fast, np.stack([want, want]))
