"""The person: hand size, force, tempo, handedness and a personal style.

Flagg (2012, Sec. 4.4) found that "while people vary widely in their
individual interpretations of a given gesture, they are likely to stick to
their respective interpretations": per-person models reached 94 % against
86 % pooled. We model that as a *style*: for every gesture, each person
draws once a set of deviations (log-factors on force, rate, contact time,
amplitude and oscillation frequency; an angle of the hand; a preferred
location) that all of that person's captures share. Each capture adds a
smaller repetition deviation, and a second session (``session`` effect) a
drift of the style. Because the style is shared within a person but not
between people, a classifier that has seen a person's other captures does
better than one tested on a stranger: leave-one-subject-out is harder than
random k-fold, as in the papers.

A person also has a hand length (Zhou et al. 2017 Sec. 3.2: 16.5 to 21.5
cm; it scales the contact footprint), an overall force and tempo, and may
be left-handed (``handedness``: the left hand mirrors the kinematics).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .gestures import Factors
from .hand import REFERENCE_HAND_MM
from .spec import SceneSpec, Spread, subject_ids

# the dimensions of a style vector
STYLE_DIMS = ("force", "rate", "contact", "amplitude", "osc", "angle", "dx", "dy")
_LOG_DIMS = 5
PERSON_STREAM = 1_000_003


@dataclass
class Person:
    subject: str
    index: int
    group: str | None
    sessions: int
    hands: str  # "dominant" or "both"
    hand_scale: float
    force: float
    tempo: float
    left_handed: bool
    style: dict[str, np.ndarray] = field(default_factory=dict)  # gesture -> (8,)
    drift: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)  # (session, gesture) -> (8,)


def spread_vector(s: Spread, scale: float = 1.0) -> np.ndarray:
    """Standard deviations of the eight style dimensions."""
    return scale * np.array([s.sd] * _LOG_DIMS + [np.deg2rad(s.angle_deg), s.location_mm, s.location_mm])


def make_people(spec: SceneSpec, seed: int) -> list[Person]:
    """Everyone in the scene, each drawn from its own seeded stream
    ``(seed, PERSON_STREAM, index)`` so a person does not depend on the
    others."""
    pop, pro = spec.population, spec.protocol
    fx = set(spec.effects)
    ids = subject_ids(spec)
    groups: list[tuple[str | None, int, str]] = []  # (group, sessions, hands) per person
    if pro.groups is None:
        groups = [(None, pro.sessions, "dominant")] * len(ids)
    else:
        for gname, grp in pro.groups.items():
            groups += [(gname, grp.sessions, grp.hands)] * grp.subjects
    gestures = list(spec.gestures)
    people = []
    for i, sid in enumerate(ids):
        rng = np.random.default_rng([seed, PERSON_STREAM, i])
        hl_mean, hl_sd = pop.hand_length_mm
        hand = max(hl_mean + hl_sd * rng.standard_normal(), 0.5 * hl_mean)
        force = float(np.exp(pop.force_sd * rng.standard_normal()))
        tempo = float(np.exp(pop.tempo_sd * rng.standard_normal()))
        lefty = bool(rng.random() < pop.left_handed) if ("handedness" in fx and pop.left_handed) else False
        group, sessions, hands = groups[i]
        p = Person(sid, i, group, sessions, hands, hand / REFERENCE_HAND_MM, force, tempo, lefty)
        for g in gestures:
            z = rng.standard_normal(len(STYLE_DIMS))
            d = rng.standard_normal((sessions, len(STYLE_DIMS)))
            if "style" in fx:
                sd = spread_vector(pop.style, spec.gesture_params(g).spread)  # type: ignore[arg-type]
                p.style[g] = z * sd
                if "session" in fx and sessions > 1:
                    for s in range(sessions):
                        p.drift[(s + 1, g)] = d[s] * sd * pro.session_sd
            else:
                p.style[g] = np.zeros(len(STYLE_DIMS))
        people.append(p)
    return people


def capture_factors(
    spec: SceneSpec,
    person: Person,
    gesture: str,
    *,
    session: int,
    repetition: int,
    variant: tuple[float, float] | None,
    rng: np.random.Generator,
) -> Factors:
    """The factors of one capture: person x style x session drift x
    repetition noise x variant (force, speed)."""
    v = person.style[gesture].copy()
    drift = person.drift.get((session, gesture))
    if drift is not None:
        v += drift
    v += rng.standard_normal(len(STYLE_DIMS)) * spread_vector(spec.population.repetition)
    f_force, f_speed = variant if variant is not None else (1.0, 1.0)
    left = person.left_handed
    if person.hands == "both" and repetition % 2 == 0:
        left = not left  # alternate hands, dominant first
    return Factors(
        force=person.force * f_force * float(np.exp(v[0])),
        rate=person.tempo * f_speed * float(np.exp(v[1])),
        contact=float(np.exp(v[2])),
        amplitude=float(np.exp(v[3])),
        osc=float(np.exp(v[4])),
        angle=float(v[5]),
        dx=float(v[6]),
        dy=float(v[7]),
        mirror=left,
    )
