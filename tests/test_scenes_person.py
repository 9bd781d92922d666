"""The person alone: hand size, force, tempo, handedness and a style that
persists across a person's captures (touchbench.scenes.person)."""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.scenes import load_scene
from touchbench.scenes.generate import generate
from touchbench.scenes.person import STYLE_DIMS, capture_factors, make_people, spread_vector
from touchbench.scenes.loading import parse_spec

BASE = {
    "name": "people",
    "description": "a scene to test people",
    "effects": ["style", "noise"],
    "sensor": {"grid": [8, 8], "pitch_mm": 25.4, "frame_rate": 54, "gain": 60, "noise_sd": 0.8},
    "population": {"subjects": 40, "hand_length_mm": [185, 10], "style": {"sd": 0.4, "angle_deg": 20, "location_mm": 20}},
    "gestures": {"pat": None, "stroke": None, "rub": None},
    "protocol": {"repetitions": 2, "segmentation": {"mode": "fixed", "frames": 54}},
}


def scene(**changes):
    raw = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BASE.items()}
    for path, value in changes.items():
        d = raw
        keys = path.split(".")
        for k in keys[:-1]:
            d[k] = dict(d[k])
            d = d[k]
        d[keys[-1]] = value
    return parse_spec(raw)


def test_people_are_drawn_independently_of_each_other():
    spec = scene()
    a = make_people(spec, seed=3)
    b = make_people(scene(**{"population.subjects": 5}), seed=3)
    for p, q in zip(a[:5], b):
        assert p.hand_scale == q.hand_scale and p.force == q.force
        assert all(np.array_equal(p.style[g], q.style[g]) for g in spec.gestures)


def test_hand_size_force_and_tempo_spread_as_stated():
    spec = scene(**{"population.subjects": 400, "population.force_sd": 0.3, "population.tempo_sd": 0.2})
    people = make_people(spec, seed=0)
    hands = np.array([p.hand_scale for p in people]) * 185.0
    assert hands.mean() == pytest.approx(185.0, abs=1.5)
    assert hands.std() == pytest.approx(10.0, rel=0.12)
    assert np.std(np.log([p.force for p in people])) == pytest.approx(0.3, rel=0.12)
    assert np.std(np.log([p.tempo for p in people])) == pytest.approx(0.2, rel=0.12)


def test_style_persists_within_a_person_and_differs_between_people():
    spec = scene(**{"population.subjects": 300})
    people = make_people(spec, seed=0)
    rng = np.random.default_rng(0)
    # the same person's captures share the style: log force factors of two
    # captures differ only by repetition noise (sd 0.1 each -> 0.141 apart)
    p = people[0]
    f = [np.log(capture_factors(spec, p, "pat", session=1, repetition=r, variant=None, rng=rng).force / p.force) for r in range(400)]
    assert np.std(f) == pytest.approx(0.1, rel=0.12)
    assert np.mean(f) == pytest.approx(p.style["pat"][0], abs=0.02)
    # between people the style spreads with sd 0.4 on each log factor
    styles = np.array([q.style["pat"] for q in people])
    assert styles[:, 0].std() == pytest.approx(0.4, rel=0.12)
    assert np.rad2deg(styles[:, STYLE_DIMS.index("angle")].std()) == pytest.approx(20.0, rel=0.12)
    assert styles[:, STYLE_DIMS.index("dx")].std() == pytest.approx(20.0, rel=0.12)
    # and each gesture has its own
    assert not np.allclose(styles[:, 0], np.array([q.style["rub"][0] for q in people]))


def test_without_the_style_effect_everyone_performs_alike():
    spec = scene(effects=["noise"], **{"population.style": None})
    for p in make_people(spec, seed=0):
        assert all(not v.any() for v in p.style.values())


def test_spread_multiplier_per_gesture():
    spec = scene(gestures={"pat": {"spread": 2.0}, "rub": None})
    s = spec.population.style
    people = make_people(scene(gestures={"pat": {"spread": 2.0}, "rub": None}, **{"population.subjects": 300}), seed=0)
    assert np.array([p.style["pat"][0] for p in people]).std() == pytest.approx(2 * s.sd, rel=0.12)
    assert spread_vector(s, 2.0)[0] == 2 * s.sd


def test_handedness_and_alternating_hands():
    spec = scene(effects=["style", "handedness", "noise"], **{"population.left_handed": 0.5, "population.subjects": 200})
    people = make_people(spec, seed=0)
    assert 0.4 < np.mean([p.left_handed for p in people]) < 0.6
    rng = np.random.default_rng(0)
    righty = next(p for p in people if not p.left_handed)
    assert not capture_factors(spec, righty, "pat", session=1, repetition=1, variant=None, rng=rng).mirror
    righty.hands = "both"  # Zhou's group A: both hands in turn
    hands = [capture_factors(spec, righty, "pat", session=1, repetition=r, variant=None, rng=rng).mirror for r in (1, 2, 3, 4)]
    assert hands == [False, True, False, True]


def test_session_drift_is_a_fraction_of_the_style():
    spec = scene(effects=["style", "session", "noise"], **{"protocol.sessions": 2, "protocol.session_sd": 0.3, "population.subjects": 300})
    people = make_people(spec, seed=0)
    d = np.array([p.drift[(2, "pat")][0] for p in people])
    assert d.std() == pytest.approx(0.3 * 0.4, rel=0.12)
    assert not np.allclose(d, [p.drift[(1, "pat")][0] for p in people])


def _quick_features(ds):
    """Per capture: mean/sd/max of the total, contact fraction, centroid
    path length and spread, dominant frequency of the total."""
    out = []
    for c in ds.captures:
        x = c.astype(float)
        tot = x.sum(axis=(1, 2))
        w = np.clip(x - 10, 0, None)
        ws = w.sum(axis=(1, 2))
        ok = ws > 0
        s = np.where(ok, ws, 1)
        cy = (w.sum(axis=2) * np.arange(8)).sum(1) / s
        cx = (w.sum(axis=1) * np.arange(8)).sum(1) / s
        spec = np.abs(np.fft.rfft(tot - tot.mean()))
        out.append([tot.mean(), tot.std(), tot.max(), ok.mean(), np.abs(np.diff(cx[ok])).sum() if ok.sum() > 1 else 0,
                    np.abs(np.diff(cy[ok])).sum() if ok.sum() > 1 else 0, cx[ok].mean() if ok.any() else -1,
                    cy[ok].mean() if ok.any() else -1, np.argmax(spec[1:])])
    return np.array(out)


def test_leave_one_subject_out_is_harder_than_random_kfold():
    """Flagg Sec. 4.4 / Zhou Sec. 4: a persistent personal style makes a
    stranger harder to recognise than a known person's other captures."""
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.model_selection import GroupKFold, StratifiedKFold, cross_val_score

    spec = scene(
        **{
            "population.subjects": 8,
            "population.style": {"sd": 0.6, "angle_deg": 40, "location_mm": 40},
            "protocol.repetitions": 8,
        },
        gestures={"pat": None, "stroke": None, "rub": None, "scratch": None, "tickle": None},
    )
    ds = generate(spec, seed=2)
    X, y, g = _quick_features(ds), ds.labels, ds.meta["subject"].to_numpy()
    rf = RandomForestClassifier(n_estimators=60, random_state=0, n_jobs=1)
    loso = cross_val_score(rf, X, y, groups=g, cv=GroupKFold(n_splits=8)).mean()
    kfold = cross_val_score(rf, X, y, cv=StratifiedKFold(n_splits=8, shuffle=True, random_state=0)).mean()
    assert loso < kfold - 0.05


def test_shipped_people_counts():
    assert len(make_people(load_scene("haart-like"), 0)) == 10
    assert len(make_people(load_scene("fur-like"), 0)) == 16
    people = make_people(load_scene("tpm-like"), 0)
    assert [p.group for p in people].count("A") == 24 and [p.group for p in people].count("B") == 5
    assert {p.sessions for p in people if p.group == "A"} == {2}
    assert {p.hands for p in people if p.group == "B"} == {"dominant"}
