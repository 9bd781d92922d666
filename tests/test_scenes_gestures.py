"""Each gesture's kinematics alone, rendered on a bare ideal sensor
(touchbench.scenes.gestures via generate.simulate)."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.scenes.generate import simulate
from touchbench.scenes.gestures import LIBRARY, Factors, GestureParams
from touchbench.scenes.hand import footprint, tracks

FPS = 54.0


def contacts(field: np.ndarray, frac: float = 0.05) -> int:
    """Number of separate contacts: rising edges of the total force above
    ``frac`` of its maximum."""
    tot = field.sum(axis=(1, 2))
    on = tot > frac * tot.max()
    return int(on[0]) + int(np.sum(on[1:] & ~on[:-1]))


def centroid(field: np.ndarray, pitch: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x mm, y mm, total) per frame."""
    tot = field.sum(axis=(1, 2))
    safe = np.where(tot > 0, tot, 1.0)
    H, W = field.shape[1:]
    x = (field.sum(axis=1) * (np.arange(W) + 0.5) * pitch).sum(axis=1) / safe
    y = (field.sum(axis=2) * (np.arange(H) + 0.5) * pitch).sum(axis=1) / safe
    return x, y, tot


def dominant_hz(x: np.ndarray, fps: float) -> float:
    x = x - x.mean()
    spec = np.abs(np.fft.rfft(x))
    f = np.fft.rfftfreq(len(x), 1.0 / fps)
    return float(f[1 + np.argmax(spec[1:])])


def steady(name: str, **changes) -> GestureParams:
    """The library gesture made regular: no jitter, no duration spread, no
    wobble, no event-to-event force variation."""
    base = dict(jitter=0.0, duration_cv=0.0, wobble=0.0, force_cv=0.0)
    base.update(changes)
    return LIBRARY[name].replace(**base)


@pytest.mark.parametrize("rate,duration,expected", [(3.0, 2.0, 6), (2.0, 2.0, 4), (2.5, 1.6, 4)])
def test_pat_has_as_many_contacts_as_its_rate_says(rate, duration, expected):
    # cut at the touch: round(duration x rate) pats
    field, ev = simulate(steady("pat", rate_hz=rate, duration_s=duration), grid=(8, 8), frame_rate=FPS)
    assert len(ev) == expected
    assert contacts(field) == expected


def test_pat_rate_in_a_fixed_window():
    # 2.5 pats/s over an 8 s window (432 frames at 54 Hz): 20, +-1 for the phase
    field, _ = simulate(steady("pat"), frames=432, grid=(8, 8), frame_rate=FPS, seed=3)
    assert abs(contacts(field) - 20) <= 1


def test_pat_is_brief_palm_contact():
    field, ev = simulate(steady("pat", duration_s=2.0), grid=(8, 8), frame_rate=FPS)
    on = field.sum(axis=(1, 2)) > 0.05 * field.sum(axis=(1, 2)).max()
    # each contact 0.13 s of a 0.4 s period: about a third of the time in contact
    assert 0.2 < on.mean() < 0.5


def test_stroke_centroid_moves_one_way():
    pitch = 15.0
    p = steady("stroke", cycles=1, travel_mm=110.0, angle_deg=90.0)
    field, ev = simulate(p, grid=(20, 20), pitch_mm=pitch, frame_rate=FPS)
    x, y, tot = centroid(field, pitch)
    hold = tot > 0.5 * tot.max()
    # along +y (90 degrees), steadily; x does not move
    dy = np.diff(y[hold])
    assert np.all(dy > 0)
    # between the frames at half force the contact point covers most of its 110 mm
    assert 60.0 < y[hold][-1] - y[hold][0] <= 110.0
    assert np.ptp(x[hold]) < 1.0


def test_stroke_repeats_in_the_same_direction():
    pitch = 15.0
    p = steady("stroke", duration_s=3.75, rate_hz=0.8)  # three strokes
    field, ev = simulate(p, grid=(20, 20), pitch_mm=pitch, frame_rate=FPS)
    assert contacts(field) == 3
    assert np.all(ev.gy > 0) and np.allclose(ev.gy, ev.gy[0])


def test_rub_moves_back_and_forth_at_its_rate():
    pitch = 15.0
    p = steady("rub", osc_hz=1.5, osc_mm=30.0, angle_deg=0.0)
    field, _ = simulate(p, grid=(20, 20), pitch_mm=pitch, frame_rate=FPS, frames=432)
    x, y, tot = centroid(field, pitch)
    # 8 s window, 0.125 Hz bins: the back-and-forth at 1.5 Hz along x
    assert dominant_hz(x, FPS) == pytest.approx(1.5, abs=0.13)
    # amplitude 30 mm: a sinusoid's sd is A / sqrt(2)
    assert np.std(x) == pytest.approx(30.0 / np.sqrt(2), rel=0.1)
    assert np.std(y) < 1.0
    # firm and continuous
    assert np.all(tot > 0.9 * p.force_n)


def test_scratch_is_faster_and_smaller_than_rub():
    pitch = 10.0
    r, _ = simulate(steady("rub", angle_deg=0.0), grid=(20, 20), pitch_mm=pitch, frames=432, frame_rate=FPS)
    s, _ = simulate(steady("scratch", angle_deg=0.0), grid=(20, 20), pitch_mm=pitch, frames=432, frame_rate=FPS)
    rx, _, _ = centroid(r, pitch)
    sx, _, _ = centroid(s, pitch)
    assert dominant_hz(sx, FPS) == pytest.approx(LIBRARY["scratch"].osc_hz, abs=0.13)
    assert dominant_hz(sx, FPS) > 2 * dominant_hz(rx, FPS)
    assert np.std(sx) < 0.5 * np.std(rx)


def test_tickle_is_light_and_irregular():
    tk = LIBRARY["tickle"]
    _, ev = simulate(tk, frames=540, grid=(8, 8), frame_rate=FPS, seed=1)
    _, ev_pat = simulate(steady("pat"), frames=540, grid=(8, 8), frame_rate=FPS, seed=1)
    cv = np.std(np.diff(ev.onset)) / np.mean(np.diff(ev.onset))
    assert cv > 0.3
    assert np.std(np.diff(ev_pat.onset)) == pytest.approx(0.0, abs=1e-12)
    # light: below the pat's force; scattered over the surface
    assert np.median(ev.peak) < LIBRARY["pat"].force_n
    assert np.std(ev.x0) > 15.0


def test_poke_is_one_short_firm_fingertip():
    field, ev = simulate(steady("poke"), frame_rate=FPS, grid=(20, 20), pitch_mm=10.0)
    tot = field.sum(axis=(1, 2))
    assert len(ev) == 1 and contacts(field) == 1
    assert tot.max() == pytest.approx(LIBRARY["poke"].force_n, rel=1e-3)
    assert np.sum(tot > 0.05 * tot.max()) / FPS < 0.6
    # one fingertip: the force sits on a few 10 mm cells
    assert np.sum(field[np.argmax(tot)] > 0.05 * tot.max()) <= 9


def _rise_time(field):
    tot = field.sum(axis=(1, 2))
    a = np.argmax(tot > 0.1 * tot.max())
    b = np.argmax(tot > 0.9 * tot.max())
    return (b - a) / FPS


def test_press_is_slower_than_poke_and_push_is_palm():
    poke, _ = simulate(steady("poke"), grid=(8, 8), frame_rate=FPS)
    press, _ = simulate(steady("press"), grid=(8, 8), frame_rate=FPS)
    push, _ = simulate(steady("push"), frame_rate=FPS, grid=(20, 20), pitch_mm=10.0)
    press20, _ = simulate(steady("press"), frame_rate=FPS, grid=(20, 20), pitch_mm=10.0)
    assert _rise_time(press) > 3 * _rise_time(poke)
    # a palm covers more cells than three fingertips
    frac = 0.02
    area = lambda f: np.sum(f[np.argmax(f.sum(axis=(1, 2)))] > frac * f.max())  # noqa: E731
    assert area(push) > area(press20)


def test_pinch_fingers_close_on_each_other():
    p = steady("pinch", closing_mm=20.0)
    _, ev = simulate(p, grid=(8, 8), frame_rate=FPS)
    t = np.array([ev.onset[0], ev.onset[0] + ev.rise[0] + 0.01])
    tr = tracks(ev, footprint("pinch"), t)
    gap = np.hypot(tr.cx[0] - tr.cx[1], tr.cy[0] - tr.cy[1])
    # 30 mm apart at the start, 20 mm closer once the force is up
    assert gap[0] == pytest.approx(30.0)
    assert gap[1] == pytest.approx(10.0)


def test_squeeze_is_firmer_and_longer_than_grab():
    g, _ = simulate(steady("grab"), frame_rate=FPS, grid=(8, 8), pitch_mm=20.0)
    s, _ = simulate(steady("squeeze"), frame_rate=FPS, grid=(8, 8), pitch_mm=20.0)
    assert s.sum(axis=(1, 2)).max() > 1.3 * g.sum(axis=(1, 2)).max()
    assert len(s) > len(g)


def test_hit_and_slap_are_short_impacts_slap_flat():
    hit, _ = simulate(steady("hit"), frame_rate=135.0, grid=(30, 30), pitch_mm=10.0)
    slap, _ = simulate(steady("slap"), frame_rate=135.0, grid=(30, 30), pitch_mm=10.0)
    for f in (hit, slap):
        tot = f.sum(axis=(1, 2))
        assert np.sum(tot > 0.05 * tot.max()) / 135.0 < 0.2
        assert tot.max() > 20.0
    # the flat hand reaches further than the palm alone
    reach = lambda f: np.sum(f.max(axis=0) > 0.05 * f.max())  # noqa: E731
    assert reach(slap) > reach(hit)


def test_massage_kneads():
    p = steady("massage", knead_hz=1.25, knead_depth=0.7)
    field, _ = simulate(p, frames=432, frame_rate=FPS, grid=(20, 20), pitch_mm=10.0)
    tot = field.sum(axis=(1, 2))
    assert dominant_hz(tot, FPS) == pytest.approx(1.25, abs=0.13)
    # depth 0.7: the force swings between 0.3 and 1 of its peak
    assert tot.min() / tot.max() == pytest.approx(0.3, abs=0.05)


def test_constant_is_still():
    field, _ = simulate(steady("constant"), frames=216, grid=(8, 8), frame_rate=FPS)
    x, y, tot = centroid(field, 25.4)
    assert np.ptp(x) < 1e-6 and np.ptp(y) < 1e-6
    assert np.ptp(tot) < 1e-6 * tot.max()


def test_notouch_is_nothing():
    field, ev = simulate(LIBRARY["notouch"], frames=100, grid=(8, 8), frame_rate=FPS)
    assert len(ev) == 0 and field.shape == (100, 8, 8) and not field.any()


def test_burst_of_three_fixes_the_number_of_movements():
    # Zhou's group A: stroke and scratch as a quick burst of three
    _, ev = simulate(steady("stroke", cycles=3, pace=1.5), grid=(8, 8), frame_rate=50.0)
    assert len(ev) == 3
    s = steady("scratch", cycles=3, pace=1.5)
    _, ev = simulate(s, grid=(8, 8), frame_rate=50.0)
    # three back-and-forth cycles at 1.5 x the scratch rate
    assert ev.dur[0] == pytest.approx(3 / (s.osc_hz * 1.5))


def test_force_and_speed_factors_scale_the_gesture():
    # rough = force x 1.7, speed x 1.25: same draws, so exactly scaled
    p = steady("pat", cycles=5)
    _, normal = simulate(p, grid=(8, 8), frame_rate=FPS, seed=5)
    _, rough = simulate(p, grid=(8, 8), frame_rate=FPS, seed=5, factors=Factors(force=1.7, rate=1.25))
    assert rough.peak / normal.peak == pytest.approx(np.full(len(normal), 1.7))
    # faster: 1.25 x the contacts per second
    assert np.diff(rough.onset)[0] == pytest.approx(np.diff(normal.onset)[0] / 1.25)


def test_left_hand_mirrors_the_motion():
    p = steady("stroke", cycles=1, angle_deg=30.0, scatter_mm=0.0)
    _, right = simulate(p, grid=(8, 8), frame_rate=FPS, factors=Factors(dx=10.0))
    _, left = simulate(p, grid=(8, 8), frame_rate=FPS, factors=Factors(dx=10.0, mirror=True))
    assert left.gx[0] == pytest.approx(-right.gx[0])
    assert left.gy[0] == pytest.approx(right.gy[0])
    centre = 8 * 25.4 / 2
    assert (left.x0[0] + left.gx[0] / 2) - centre == pytest.approx(-((right.x0[0] + right.gx[0] / 2) - centre))


def test_bad_parameter_is_refused():
    with pytest.raises(ValueError, match="must be positive"):
        LIBRARY["pat"].replace(force_n=0)
    with pytest.raises(ValueError, match="primitive"):
        LIBRARY["pat"].replace(primitive="elbow")
