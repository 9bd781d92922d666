"""live-summary by hand, and its properties."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES, FeatureInputError, SensorNeededError

SENSOR = SensorSpec("toy", (2, 3), 10.0, (0, 10))


def _features(capture, sensor=SENSOR, **params):
    fs = FEATURES.create("live-summary", sensor=sensor, **params)
    return dict(zip(fs.feature_names(sensor.grid), fs.fit_transform([capture])[0]))


def test_live_summary_by_hand():
    # 3 frames of 2 x 3 cells on 0..10: cell (0, 0) rests at 2; cell (1, 2) pressed 0 -> 10 -> 5
    cap = np.zeros((3, 2, 3))
    cap[:, 0, 0] = 2.0
    cap[:, 1, 2] = [0.0, 10.0, 5.0]
    f = _features(cap)
    # x = value / 10; baselines: 0.2 at (0, 0), 0 at (1, 2); p is 0, 1, 0.5 at (1, 2) only
    # level (mean of x over 6 cells): 0.2/6, 1.2/6, 0.7/6
    assert f["level_mean"] == pytest.approx((0.2 + 1.2 + 0.7) / 18)
    assert f["level_delta"] == pytest.approx(0.5 / 6)
    # pressure (mean p): 0, 1/6, 0.5/6; peak: 0, 1, 0.5; area (p > 0.02): 0, 1/6, 1/6
    assert f["pressure_max"] == pytest.approx(1 / 6)
    assert f["peak_mean"] == pytest.approx(0.5) and f["peak_last"] == pytest.approx(0.5)
    assert f["peak_absdiff"] == pytest.approx((1.0 + 0.5) / 2)
    assert f["area_min"] == 0.0 and f["area_max"] == pytest.approx(1 / 6)
    # centroid: 0.5, 0.5 without pressure; then row 1 (the last row), column 1 (the last column)
    assert [f["row_min"], f["row_max"], f["col_last"]] == pytest.approx([0.5, 1.0, 1.0])
    assert f["row_sd_max"] == 0.0 and f["col_sd_max"] == 0.0  # one cell pressed: no spread
    # change (mean |x_t - x_t-1| over cells): 0, 1/6, 0.5/6
    assert f["change_max"] == pytest.approx(1 / 6) and f["change_mean"] == pytest.approx(0.25 / 6 * 2)
    assert f["seconds"] == pytest.approx(0.3)
    # sd of peak (0, 1, 0.5), population: sqrt(((0.5)^2 + (0.5)^2 + 0) / 3)
    assert f["peak_sd"] == pytest.approx(np.sqrt(0.5 / 3))


def test_two_pressed_cells_spread_about_their_centroid():
    cap = np.zeros((1, 2, 3))
    cap[0, 0, 0] = cap[0, 0, 2] = 10.0  # one frame: the pressure is its own baseline: nothing pressed
    assert _features(cap)["pressure_max"] == 0.0
    cap = np.zeros((2, 2, 3))
    cap[1, 0, 0] = cap[1, 0, 2] = 10.0  # columns 0 and 1 (of 0..1), row 0: centroid 0.5, spread 0.5
    f = _features(cap)
    assert [f["col_last"], f["col_sd_last"], f["row_last"], f["row_sd_last"]] == pytest.approx([0.5, 0.5, 0.0, 0.0])


def test_a_sensor_where_lower_means_more_pressure_reads_from_the_top():
    flipped = SensorSpec("toy", (2, 3), 10.0, (0, 10), higher_is_more_pressure=False)
    cap = np.full((2, 2, 3), 10.0)
    cap[1, 1, 2] = 0.0  # full pressure at (1, 2) in the second frame
    assert _features(cap, flipped)["peak_max"] == pytest.approx(1.0)
    assert _features(10.0 - cap)["peak_max"] == pytest.approx(1.0)


def test_live_summary_refuses_what_it_cannot_read():
    with pytest.raises(FeatureInputError, match=r"The 'contact' parameter of live-summary must be a float in the range \(0.0, 1.0\)"):
        _features(np.zeros((2, 2, 3)), contact=1.5)
    with pytest.raises(SensorNeededError, match="value range"):
        FEATURES.create("live-summary").fit_transform([np.zeros((2, 2, 3))])
    strip = SensorSpec("strip", (1, 3), 10.0, (0, 10), channels=("a", "b", "c"))
    with pytest.raises(FeatureInputError, match="channel sensor"):
        _features(np.zeros((2, 1, 3)), strip)
