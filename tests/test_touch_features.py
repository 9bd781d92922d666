"""touchbench's own feature sets: touch-rhythm, cell-rhythm, contact-motion.

Values worked out by hand on two captures whose every statistic follows
from their construction:

- a constant capture (every cell 5 in every frame): no pressure above the
  baseline, no variation, so every rhythm feature takes its "nothing
  happens" limit;
- one cell tapped as a square wave: cell (2, 5) is 100 in frames
  0-8, 18-26, ... (on for 9 frames, off for 9: period 18 frames = 3 Hz at
  54 frames/s), every other cell 0, 432 frames (24 periods).

Plus hypothesis properties: finite, fixed length, and a capture's row does
not depend on the other captures of its batch or on its position.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import captures_strategy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES
from touchbench.features.touch import CellRhythm, ContactMotion, TouchRhythm

NAMES = ["touch-rhythm", "cell-rhythm", "contact-motion"]
HAART = SensorSpec(name="haart", grid=(8, 8), frame_rate=54.0)


def row(cls, capture, sensor=HAART):
    fs = cls(sensor=sensor).fit([capture])
    x = fs.transform([capture])[0]
    return dict(zip(fs.get_feature_names_out(), x))


def square_wave_capture() -> np.ndarray:
    c = np.zeros((432, 8, 8), dtype=np.uint16)
    on = (np.arange(432) // 9) % 2 == 0
    c[on, 2, 5] = 100
    return c


def test_registered_with_tags():
    for n in NAMES:
        e = FEATURES.entry(n)
        assert e.tags["cost"] == "cheap"
        assert e.obj.fold_dependent is False


# ------------------------------------------------------------ constant capture
def test_constant_capture_touch_rhythm():
    f = row(TouchRhythm, np.full((40, 8, 8), 5, dtype=np.uint16))
    # raw total pressure: 64 cells x 5
    assert f["P_mean"] == pytest.approx(320.0)
    assert f["P_std"] == 0.0 and f["P_max"] == 320.0
    # nothing above the baseline (5): pressure 0, centroid at the grid centre
    assert f["logP_mean"] == 0.0 and f["Pn_mean"] == 0.0
    assert f["cy_mean"] == 3.5 and f["cx_mean"] == 3.5
    assert f["sy_mean"] == 0.0 and f["A_max"] == 0.0
    # no variation: moments at their limits, no spectrum, no crossings
    assert f["P_skew"] == 0.0 and f["P_kurt"] == 3.0
    assert f["P_fpeak"] == 0.0 and f["P_logpow"] == 0.0 and f["P_mcr"] == 0.0
    assert f["P_ac9"] == 0.0 and f["P_cv"] == 0.0
    assert f["base_mean"] == 5.0 and f["base_max"] == 5.0 and f["peak"] == 0.0
    assert f["active_frac"] == 0.0 and f["path"] == 0.0


def test_constant_capture_cell_rhythm_and_contact_motion():
    c = np.full((40, 8, 8), 5, dtype=np.uint16)
    cr = row(CellRhythm, c)
    assert all(v == 0.0 for v in cr.values())
    cm = row(ContactMotion, c)
    assert all(v == 0.0 for v in cm.values())  # includes log(1 + peak 0)


# --------------------------------------------------------- square-wave tapping
def test_square_wave_touch_rhythm_by_hand():
    f = row(TouchRhythm, square_wave_capture())
    # baseline of every cell = 0 (the tapped cell is 0 in half the frames)
    assert f["base_max"] == 0.0
    # P is 100 in 216 of 432 frames
    assert f["P_mean"] == pytest.approx(50.0)
    assert f["P_std"] == pytest.approx(50.0)
    assert f["P_max"] == 100.0 and f["P_p5"] == 0.0 and f["P_p95"] == 100.0
    assert f["P_skew"] == pytest.approx(0.0, abs=1e-12)
    assert f["P_kurt"] == pytest.approx(1.0)  # a symmetric two-point series
    # 47 switches between 431 consecutive pairs
    assert f["P_mcr"] == pytest.approx(47 / 431)
    assert f["P_mad1"] == pytest.approx(47 * 100 / 431)
    # 3 Hz = bin 24 of a 432-point spectrum at 54 Hz
    assert f["P_fpeak"] == pytest.approx(3.0)
    # autocorrelation: half a period (9 frames) exactly opposite, a period (18) equal
    assert f["P_ac9"] == pytest.approx(-(432 - 9) / 432)
    assert f["P_ac18"] == pytest.approx((432 - 18) / 432)
    # area: one cell above 20 % of the peak (100) in half the frames
    assert f["A_mean"] == pytest.approx(0.5)
    assert f["peak"] == 100.0 and f["logpeak"] == pytest.approx(np.log(101.0))
    assert f["active_frac"] == pytest.approx(0.5)
    # cell statistics sorted over cells: all zero but the tapped cell
    assert f["cellmean_r1"] == pytest.approx(50.0) and f["cellmean_r0.9375"] == 0.0
    assert f["cellmean_sum"] == pytest.approx(50.0)
    assert f["cellstd_r1"] == pytest.approx(50.0)


def test_square_wave_cell_rhythm_by_hand():
    f = row(CellRhythm, square_wave_capture())
    # only one cell varies: its spectrum is the pooled one and the sum's
    assert f["cell_fpeak_top"] == pytest.approx(3.0)
    assert f["cell_fpeak"] == pytest.approx(3.0)
    assert f["coherence"] == pytest.approx(1.0)
    assert f["cell_pow_entropy"] == pytest.approx(0.0, abs=1e-12)
    assert f["cell_mcr"] == pytest.approx(47 / 431)
    # neighbours of the tapped cell never vary: no correlation weight
    assert f["ncorr_h"] == 0.0 and f["ncorr_v"] == 0.0
    # one blob of one cell in every pressed frame
    assert f["blobs_mean"] == 1.0 and f["blobs_max"] == 1.0 and f["blob_cells_mean"] == 1.0


def test_square_wave_contact_motion_by_hand():
    f = row(ContactMotion, square_wave_capture())
    for t in ("t10", "t30", "t50"):
        assert f[f"{t}_actfrac"] == pytest.approx(0.5)
        assert f[f"{t}_onsets"] == 23.0  # 24 pressed blocks, the first from frame 0
        assert f[f"{t}_area_mean"] == 1.0 and f[f"{t}_area_max"] == 1.0
        # the contact never moves
        assert f[f"{t}_speed_mean"] == 0.0 and f[f"{t}_path"] == 0.0
        assert f[f"{t}_range_y"] == 0.0 and f[f"{t}_range_x"] == 0.0
        assert f[f"{t}_reversal"] == 0.0
        assert f[f"{t}_act_fpeak"] == pytest.approx(3.0)
    assert f["logpeak_robust"] == pytest.approx(np.log(101.0))


@pytest.mark.parametrize("dtype", [np.float64, np.uint16])
@pytest.mark.parametrize("compiled", [True, False])
def test_a_single_cell_keeps_its_frames_in_order(dtype, compiled, monkeypatch):
    # one cell: ten readings, k = floor(0.05 * 9) = 0, so the baseline is the smallest reading (1) and
    # the pressure is every reading less 1, in the frames' order; the readings are left as they were
    from touchbench.core import compiled as switch
    from touchbench.features.touch import pressure

    monkeypatch.setattr(switch, "COMPILED", compiled)
    readings = np.array([5, 1, 3, 9, 2, 4, 8, 6, 7, 3], dtype=dtype).reshape(1, 10, 1, 1)
    kept = readings.copy()
    s, base = pressure(readings)
    assert base.tolist() == [[1.0]]
    assert s[0, :, 0].tolist() == [4.0, 0.0, 2.0, 8.0, 1.0, 3.0, 7.0, 5.0, 6.0, 2.0]
    assert np.array_equal(readings, kept)


def test_frame_rate_scales_frequencies():
    c = square_wave_capture()
    slow = SensorSpec(name="slow", grid=(8, 8), frame_rate=27.0)
    assert row(TouchRhythm, c, slow)["P_fpeak"] == pytest.approx(1.5)
    assert TouchRhythm(frame_rate=108.0, value_range=(0, 1023)).fit([c]).transform([c])[0][
        list(TouchRhythm().feature_names((8, 8))).index("P_fpeak")] == pytest.approx(6.0)


def test_gain_changes_leave_level_free_features_unchanged():
    c = square_wave_capture()
    a, b = row(TouchRhythm, c), row(TouchRhythm, (c * 3).astype(np.uint16))
    for k in ("Pn_mean", "Pn_std", "P_fpeak", "P_mcr", "P_ac9", "cy_mean", "A_mean"):
        assert a[k] == pytest.approx(b[k])


def test_bad_frame_rate_refused():
    with pytest.raises(ValueError, match="frame_rate"):
        TouchRhythm(frame_rate=-1).fit([square_wave_capture()])


# --------------------------------------------------------------- properties
@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(caps=captures_strategy())
def test_finite_fixed_length_and_batch_invariant(name, caps):
    fs = FEATURES.create(name, sensor=HAART).fit(caps)
    grid = caps[0].shape[1:]
    X = fs.transform(caps)
    assert X.shape == (len(caps), len(fs.feature_names(grid)))
    assert np.isfinite(X).all()
    # each capture alone, and the batch reversed: the same rows
    alone = np.vstack([fs.transform([c]) for c in caps])
    np.testing.assert_allclose(alone, X, rtol=1e-9, atol=1e-9)
    rev = fs.transform(caps[::-1])[::-1]
    np.testing.assert_allclose(rev, X, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=15, deadline=None)
@given(t=st.integers(1, 30), v=st.integers(0, 1023))
def test_float_and_integer_input_agree(name, t, v):
    c = np.full((t, 3, 4), v, dtype=np.uint16)
    c[::2, 1, 2] = min(1023, v + 7)
    fs = FEATURES.create(name, sensor=HAART)
    np.testing.assert_array_equal(fs.fit([c]).transform([c]), fs.transform([c.astype(np.float64)]))


def test_real_haart_rows_finite(real_haart):
    caps = real_haart.captures[:20]
    for n in NAMES:
        X = FEATURES.create(n, sensor=real_haart.sensor).fit(caps).transform(caps)
        assert np.isfinite(X).all() and X.shape[0] == 20
