"""The sensor stack alone: cover, substrate, curvature, cross-talk,
saturation, baseline, noise, ADC and the channel sensor
(touchbench.scenes.sensor)."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.scenes import sensor as S
from touchbench.scenes.hand import Tracks, render


def blob(force=5.0, sd=10.0, x=100.0, y=100.0, T=1, conform=False):
    return Tracks(
        cx=np.full((1, T), x),
        cy=np.full((1, T), y),
        force=np.full((1, T), force),
        sdx=np.array([sd]),
        sdy=np.array([sd]),
        conform=np.array([conform]),
    )


def test_cover_lowers_the_peak():
    bare = render(blob(), (8, 8), 25.0)
    covered = render(S.apply_cover(blob(), transmission=0.7, blur_mm=10.0), (8, 8), 25.0)
    assert covered.max() < 0.7 * bare.max()
    # it transmits 70 % of the force, spread wider
    assert covered.sum() == pytest.approx(0.7 * bare.sum(), rel=1e-3)
    tr = S.apply_cover(blob(), transmission=0.7, blur_mm=10.0)
    assert tr.sdx[0] == pytest.approx(np.hypot(10.0, 10.0))


def test_cover_deadband_swallows_light_touch():
    light = S.apply_cover(blob(force=0.4), transmission=1.0, blur_mm=0.0, deadband_n=0.5)
    firm = S.apply_cover(blob(force=2.0), transmission=1.0, blur_mm=0.0, deadband_n=0.5)
    assert light.force.max() == 0.0
    assert firm.force.max() == pytest.approx(1.5)


def test_substrate_delay_is_a_first_order_lag():
    fps, tau = 100.0, 0.1
    step = np.ones((1, 50))
    out = S.lag(step, tau, fps)
    # after tau (10 frames, the 11th sample) a first-order lag reaches 1 - 1/e
    assert out[0, 9] == pytest.approx(1 - np.exp(-1.0), rel=1e-9)
    assert out[0, 0] == pytest.approx(1 - np.exp(-0.1))
    assert np.all(np.diff(out[0]) > 0)


def test_substrate_spreads_and_delays():
    tr = blob(T=20)
    tr.force[:, :5] = 0.0
    out = S.apply_substrate(tr, spread_mm=8.0, delay_s=0.05, gain=1.0, frame_rate=100.0)
    assert out.sdx[0] == pytest.approx(np.hypot(10.0, 8.0))
    assert out.force[0, 5] < tr.force[0, 5]  # delayed
    assert render(out, (8, 8), 25.0)[-1].max() < render(tr, (8, 8), 25.0)[-1].max()


def test_curvature_narrows_flat_contact_but_not_a_wrapping_hand():
    flat = S.apply_curvature(blob(sd=30.0), radius_mm=45.0, axis="x")
    wrap = S.apply_curvature(blob(sd=30.0, conform=True), radius_mm=45.0, axis="x")
    lim = 0.35 * 45.0
    assert flat.sdx[0] == pytest.approx(30.0 / np.sqrt(1 + (30.0 / lim) ** 2))
    assert flat.sdy[0] == 30.0  # along the cylinder: unchanged
    assert wrap.sdx[0] == 30.0


def test_crosstalk_reaches_the_neighbours():
    f = np.zeros((1, 5, 5))
    f[0, 2, 2] = 10.0
    out = S.crosstalk(f, 0.05)
    assert out[0, 2, 2] == 10.0
    for r, c in [(1, 2), (3, 2), (2, 1), (2, 3)]:
        assert out[0, r, c] == pytest.approx(0.5)  # c x 10
    for r, c in [(1, 1), (1, 3), (3, 1), (3, 3)]:
        assert out[0, r, c] == pytest.approx(0.025)  # c^2 x 10
    assert out[0, 0, 2] == 0.0 and out[0, 0, 0] == 0.0


def test_crosstalk_while_rendering_equals_crosstalk_of_the_field():
    tr = blob(force=3.0, sd=12.0, x=60.0, y=130.0, T=3)
    plain = render(tr, (8, 8), 25.0)
    leaky = render(tr, (8, 8), 25.0, line_filter=lambda w: S.crosstalk_lines(w, 0.04))
    np.testing.assert_allclose(leaky, S.crosstalk(plain, 0.04), rtol=1e-12, atol=1e-15)


def test_saturation():
    x = np.array([0.0, 1e-6, 1000 * np.log(2), 1e9])
    y = S.saturate(x, 1000.0)
    assert y[0] == 0.0
    assert y[1] == pytest.approx(1e-6)  # slope 1 at 0
    assert y[2] == pytest.approx(500.0)  # S (1 - e^-ln2) = S / 2
    assert y[3] == pytest.approx(1000.0)


def test_adc_rounds_and_clips():
    x = np.array([-3.0, 0.4, 0.6, 1022.5, 5000.0])
    out = S.adc(x, (0.0, 1023.0), "uint16")
    assert out.dtype == np.uint16
    assert out.tolist() == [0, 0, 1, 1022, 1023]  # round half to even


def test_noise_has_the_stated_level():
    rng = np.random.default_rng(0)
    x = S.add_noise(np.zeros((2000, 8, 8)), 3.0, rng)
    assert np.std(x) == pytest.approx(3.0, rel=0.01)
    assert abs(np.mean(x)) < 0.03  # 4 standard errors (3 / sqrt(128000))


def test_baseline_pattern_level_and_spread():
    rng = np.random.default_rng(1)
    b = S.baseline_pattern((100, 100), 40.0, 0.25, rng)
    assert b.mean() == pytest.approx(40.0, rel=0.02)
    assert b.std() / b.mean() == pytest.approx(0.25, rel=0.05)
    lines = S.baseline_pattern((8, 8), 40.0, 0.25, rng, lines=True)
    # a row factor times a column factor: rank one
    assert np.linalg.matrix_rank(lines, tol=1e-9) == 1
    assert np.all(S.baseline_pattern((3, 3), 5.0, 0.0, rng) == 5.0)


def test_tension_is_highest_on_the_crest():
    t = S.tension((4, 9), 6.0, "x")
    assert t[0, 4] == 6.0 and t[0, 0] == pytest.approx(3.0) and t[0, 8] == pytest.approx(3.0)
    assert np.all(t == t[0])


def test_channel_sensor_reads_position_pressure_and_fur():
    T, pitch = 30, 10.0
    x_mm = np.linspace(50.0, 150.0, T)[None, :]
    tr = Tracks(cx=x_mm, cy=np.full((1, T), 75.0), force=np.full((1, T), 4.0),
                sdx=np.array([8.0]), sdy=np.array([8.0]), conform=np.zeros(1, dtype=bool))
    field = render(tr, (15, 20), pitch)
    rest = {"x": 500.0, "y": 500.0, "pressure": 60.0, "fur": 200.0}
    out = S.to_channels(field, tr, frame_rate=50.0, pressure_gain=10.0, fur_motion_gain=0.5,
                        fur_touch_gain=30.0, contact_n=0.3, rest=rest, value_range=(0.0, 1023.0))
    x, y, p, fur = out.T
    # x follows the touch across the 200 mm width: 50 mm -> 1023 * 50 / 200
    assert x[0] == pytest.approx(1023 * 50.0 / 200.0, rel=0.01)
    assert x[-1] == pytest.approx(1023 * 150.0 / 200.0, rel=0.01)
    assert y[5] == pytest.approx(1023 * 75.0 / 150.0, rel=0.01)
    assert p[5] == pytest.approx(60.0 + 10.0 * 4.0, rel=1e-3)
    # one contact of 4 N: activity 4 / 4.5; moving 100 mm in 29 frames at 50 Hz
    speed = 100.0 / ((T - 1) / 50.0)
    assert fur[5] == pytest.approx(200.0 + (4 / 4.5) * (0.5 * speed + 30.0), rel=1e-3)
    # two contacts of 1 N: activity 1 - (1/3)^2 = 8/9, standing still
    two = Tracks(cx=np.full((2, 3), 100.0), cy=np.full((2, 3), 75.0), force=np.ones((2, 3)),
                 sdx=np.full(2, 8.0), sdy=np.full(2, 8.0), conform=np.zeros(2, dtype=bool))
    out2 = S.to_channels(render(two, (15, 20), pitch), two, frame_rate=50.0, pressure_gain=10.0, fur_motion_gain=0.5,
                         fur_touch_gain=30.0, contact_n=0.3, rest=rest, value_range=(0.0, 1023.0))
    assert out2[1, 3] == pytest.approx(200.0 + (8 / 9) * 30.0)
    still = S.to_channels(np.zeros((3, 15, 20)), Tracks(*(np.zeros((0, 3)),) * 3, np.zeros(0), np.zeros(0), np.zeros(0, bool)),
                          frame_rate=50.0, pressure_gain=10.0, fur_motion_gain=0.5, fur_touch_gain=30.0,
                          contact_n=0.3, rest=rest, value_range=(0.0, 1023.0))
    assert still.tolist() == [[500.0, 500.0, 60.0, 200.0]] * 3
