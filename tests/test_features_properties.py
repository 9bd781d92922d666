"""Property tests for every registered feature set: random captures of 1 to
2000 frames with any values in the sensor's range, constant, zero and
saturated captures, on several grids. Each must give finite values of a
fixed length, not depend on the capture's position in the batch, and give
the same answer for float32 input as for the same values in float64.
NaN or infinite input is refused with an error naming the capture."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import make_set
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.features import FEATURES
from touchbench.features.base import FeatureInputError

SETS = FEATURES.names()
GRIDS = [(8, 8), (1, 4), (3, 5), (10, 10)]
KINDS = ["int", "float", "constant", "zero", "saturated", "spiky"]
HI = 1023


def make_capture(kind: str, t: int, grid: tuple[int, int], seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (t, *grid)
    if kind == "int":
        return rng.integers(0, HI + 1, shape).astype(np.uint16)
    if kind == "float":
        a = rng.uniform(0, HI, shape)
        a.ravel()[rng.integers(0, a.size, 3)] = rng.choice([0.0, float(HI)], 3)  # the range's ends too
        return a
    if kind == "constant":
        return np.full(shape, rng.integers(0, HI + 1), dtype=np.uint16)
    if kind == "zero":
        return np.zeros(shape, dtype=np.uint16)
    if kind == "saturated":
        return np.full(shape, HI, dtype=np.uint16)
    a = np.zeros(shape, dtype=np.uint16)  # spiky: a few saturated cells
    a.ravel()[rng.integers(0, a.size, max(1, a.size // 500))] = HI
    return a


@st.composite
def batches(draw):
    """(capture, a same-length neighbour, a different-length neighbour) on one grid."""
    grid = draw(st.sampled_from(GRIDS))
    t = draw(st.one_of(st.integers(1, 12), st.integers(13, 2000)))
    t2 = draw(st.integers(1, 600))
    caps = [make_capture(draw(st.sampled_from(KINDS)), n, grid, draw(st.integers(0, 2**32 - 1))) for n in (t, t, t2)]
    return caps


@pytest.mark.parametrize("name", SETS)
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(caps=batches())
def test_finite_fixed_length_position_invariant(name, caps):
    fs = make_set(name)
    grid = caps[0].shape[1:]
    out = fs.fit_transform(caps)
    assert out.shape == (3, fs.n_features(grid)) and out.dtype == np.float64
    assert np.isfinite(out).all()
    # the capture alone, and last in a reordered batch: the same row
    assert_array_equal(fs.transform([caps[0]])[0], out[0])
    assert_array_equal(fs.transform([caps[2], caps[1], caps[0]])[2], out[0])


@pytest.mark.parametrize("name", SETS)
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(t=st.integers(1, 2000), grid=st.sampled_from(GRIDS), seed=st.integers(0, 2**32 - 1))
def test_float32_agrees_with_float64(name, t, grid, seed):
    a32 = make_capture("float", t, grid, seed).astype(np.float32)
    fs = make_set(name)
    assert_array_equal(fs.fit_transform([a32]), fs.transform([a32.astype(np.float64)]))
    ints = make_capture("int", t, grid, seed)
    assert_array_equal(fs.transform([ints]), fs.transform([ints.astype(np.float32)]))


@pytest.mark.parametrize("name", SETS)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_or_inf_refused_naming_the_capture(name, bad):
    good = np.zeros((5, 8, 8))
    broken = good.copy()
    broken[3, 2, 1] = bad
    fs = make_set(name)
    with pytest.raises(FeatureInputError, match=r"capture 1 .*NaN or infinite.*frame 3, row 2, column 1"):
        fs.fit_transform([good, broken])
    meta = pd.DataFrame({"capture_id": ["ok", "s03-rub-7"], "subject": ["s01", "s03"], "gesture": ["rub", "rub"]})
    ds = TouchDataset("t", [good, broken], meta, SensorSpec("haart", (8, 8), 54.0))
    with pytest.raises(ValueError, match="capture 1 \\('s03-rub-7'\\)"):
        fs.fit_transform(ds)


@pytest.mark.parametrize("name", SETS)
def test_bad_shapes_refused(name):
    fs = make_set(name)
    with pytest.raises(FeatureInputError, match="capture 1 has grid"):
        fs.fit_transform([np.zeros((4, 8, 8)), np.zeros((4, 8, 7))])
    with pytest.raises(FeatureInputError, match="capture 0 has no frames"):
        fs.fit_transform([np.zeros((0, 8, 8))])
    with pytest.raises(FeatureInputError, match="fitted on grid"):
        fs.fit([np.zeros((4, 8, 8))]).transform([np.zeros((4, 4, 4))])
    assert fs.fit([np.zeros((4, 8, 8))]).transform([]).shape == (0, fs.n_features((8, 8)))
