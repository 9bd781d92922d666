"""The five Gaus et al. sets (sd, msd, bmh, lbptop, smmhh) give the values of the code they had before
they were made faster (tests/features_reference_gaus.py), within 1e-9 relative or absolute: on every
real HAART capture (the real-data pattern: fails under CI=true without the data) and on synthetic
captures of other grids, dtypes (uint8, uint16, int16, float32, float64) and lengths (one frame up),
with the parameters each set's branches depend on."""

from __future__ import annotations

import numpy as np
import pytest
from features_reference_gaus import (RefBinaryMotionHistory, RefLBPTOP, RefMotionStatisticalDistribution,
                                     RefSpatialMultiScaleMHH, RefStatisticalDistribution)
from helpers import synthetic_captures
from numpy.testing import assert_allclose

from touchbench.datasets.model import SensorSpec
from touchbench.features.gaus_bmh import BinaryMotionHistory
from touchbench.features.gaus_lbptop import LBPTOP
from touchbench.features.gaus_msd import MotionStatisticalDistribution
from touchbench.features.gaus_sd import StatisticalDistribution
from touchbench.features.gaus_smmhh import SpatialMultiScaleMHH

TOL = {"rtol": 1e-9, "atol": 1e-9}
SD_CLS = (StatisticalDistribution, RefStatisticalDistribution)
MSD_CLS = (MotionStatisticalDistribution, RefMotionStatisticalDistribution)
BMH_CLS = (BinaryMotionHistory, RefBinaryMotionHistory)
LBP_CLS = (LBPTOP, RefLBPTOP)
MHH_CLS = (SpatialMultiScaleMHH, RefSpatialMultiScaleMHH)
# (fast class, reference class, parameters): the defaults and the parameters that change the code path
CASES = [
    (*SD_CLS, {}), (*SD_CLS, {"preset": "cost"}), (*SD_CLS, {"clip": False, "normalize": True}),
    (*SD_CLS, {"touched_fixed": False, "high_offset": 2.0}),
    (*MSD_CLS, {}),
    (*BMH_CLS, {}), (*BMH_CLS, {"level": "frame"}), (*BMH_CLS, {"preset": "cost"}),
    (*LBP_CLS, {}), (*LBP_CLS, {"mapping": "none"}), (*LBP_CLS, {"n_points": 4}), (*LBP_CLS, {"radius": (1, 2, 2)}),
    (*LBP_CLS, {"n_points": 12}),
    (*MHH_CLS, {}), (*MHH_CLS, {"skips": (1, 3), "max_len": 2}), (*MHH_CLS, {"n_scales": 2, "threshold": (0.5, 1.0)}),
]
IDS = [f"{c[0].__name__}-{'-'.join(f'{k}={v}' for k, v in c[2].items()) or 'defaults'}" for c in CASES]
# on all of HAART, every case but 12-point LBP (its reference takes minutes there; synthetic captures check it)
REAL = [(c, i) for c, i in zip(CASES, IDS) if c[2] != {"n_points": 12}]


def both(fast_cls, ref_cls, params, caps, sensor):
    fast = fast_cls(sensor=sensor, **params).fit(caps).transform(caps)
    ref = ref_cls(sensor=sensor, **params).fit(caps).transform(caps)
    assert fast.shape == ref.shape
    return fast, ref


@pytest.mark.parametrize("fast_cls, ref_cls, params", [c for c, _ in REAL], ids=[i for _, i in REAL])
def test_every_real_haart_capture_agrees_with_the_reference(real_haart, fast_cls, ref_cls, params):
    fast, ref = both(fast_cls, ref_cls, params, real_haart.captures, real_haart.sensor)
    assert_allclose(fast, ref, **TOL)


@pytest.mark.parametrize("fast_cls, ref_cls, params", CASES, ids=IDS)
@pytest.mark.parametrize("t, grid, dtype, top", [
    (432, (8, 8), np.uint16, 1023.0),
    (40, (19, 27), np.uint8, 255.0),
    (7, (5, 7), np.float64, 1023.0),
    (5, (3, 4), np.float32, 100.0),
    (3, (8, 8), np.int16, 1023.0),
    (2, (1, 5), np.uint16, 4095.0),
    (1, (4, 3), np.uint8, 255.0),
])
def test_synthetic_captures_agree_with_the_reference(fast_cls, ref_cls, params, t, grid, dtype, top):
    sensor = SensorSpec(name="synthetic", grid=grid, frame_rate=30.0, value_range=(0.0, top))
    caps = synthetic_captures(t, t, grid, dtype, top)
    fast, ref = both(fast_cls, ref_cls, params, caps, sensor)
    assert_allclose(fast, ref, **TOL)


@pytest.mark.parametrize("fast_cls, ref_cls, params", CASES, ids=IDS)
def test_captures_of_several_lengths_in_one_batch_agree_with_the_reference(fast_cls, ref_cls, params):
    sensor = SensorSpec(name="synthetic", grid=(6, 5), frame_rate=30.0, value_range=(0.0, 1023.0))
    caps = [c for t in (1, 2, 4, 9, 60) for c in synthetic_captures(t + 100, t, (6, 5), np.uint16, 1023.0)]
    fast, ref = both(fast_cls, ref_cls, params, caps, sensor)
    assert_allclose(fast, ref, **TOL)
