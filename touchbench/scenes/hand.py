"""The hand: contact primitives, force time profiles, and rendering them
onto a sensor grid.

A primitive is a set of pressure *blobs* (elliptical bell-shaped footprints)
placed relative to the contact point along the hand axis ("along") and
across it ("across"); sizes scale with the person's hand (hand length / 185
mm, the mean of Zhou et al. 2017 Sec. 3.2's participants, 16.5-21.5 cm):

- ``fingertip``: one pad, sd 5 mm (a ~15 mm contact);
- ``fingertips``: ``fingers`` pads in a row across the hand, 19 mm apart;
- ``palm``: one broad blob, sd 30 x 26 mm;
- ``hand``: the flat hand, palm (60 % of the force) and four fingers ahead
  of it (10 % each);
- ``wrap``: the hand wrapping a curved surface: the palm band plus the
  fingers on the far side (across), the whole conforming to the curvature;
- ``pinch``: two opposing fingertips that close on each other;
- ``none``: no contact (notouch).

A blob's force follows the event's time profile: a raised-cosine rise, a
hold and a raised-cosine fall (:func:`force_profile`), optionally modulated
(kneading). :func:`render` integrates each blob over each cell's area
(so a fingertip between two cells is not lost between samples) and sums the
blobs: the value of a cell is the force (N) it carries.

Interpretations: a blob's profile along each axis is the bell whose CDF is
the tanh form of the normal CDF (within 2e-4 of a Gaussian's, and much
cheaper to integrate); rotated ellipses are rendered axis-aligned with the
variances projected on x and y (the cross term is dropped), which keeps the
rendering separable and fast; the footprint does not change with force.
A blob's force may wobble (:func:`wobble`): the pressure under a moving
hand shifts between its parts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .gestures import Events

REFERENCE_HAND_MM = 185.0
FINGER_SPACING_MM = 19.0
_TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class Footprint:
    """Blobs of a primitive: offsets (J, 2) and sds (J, 2) in mm as (along,
    across), force shares (J,) summing to 1, ``conform``: follows a curved
    surface (wrap), ``closing``: sign of each blob's motion when the
    fingers close (pinch)."""

    offsets: np.ndarray
    sds: np.ndarray
    share: np.ndarray
    conform: bool = False
    closing: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.share)


def footprint(primitive: str, hand_scale: float = 1.0, fingers: int = 1) -> Footprint:
    """The blobs of ``primitive`` for a hand ``hand_scale`` times the reference."""
    s = float(hand_scale)
    if primitive == "none":
        z = np.zeros((0, 2))
        return Footprint(z, z, np.zeros(0))
    if primitive == "fingertip":
        return Footprint(np.zeros((1, 2)), np.full((1, 2), 5.0 * s), np.ones(1))
    if primitive == "fingertips":
        across = (np.arange(fingers) - (fingers - 1) / 2) * FINGER_SPACING_MM * s
        off = np.stack([np.zeros(fingers), across], axis=1)
        return Footprint(off, np.full((fingers, 2), 5.5 * s), np.full(fingers, 1.0 / fingers))
    if primitive == "palm":
        return Footprint(np.zeros((1, 2)), np.array([[30.0, 26.0]]) * s, np.ones(1))
    if primitive == "hand":
        across = (np.arange(4) - 1.5) * FINGER_SPACING_MM * s
        off = np.vstack([[0.0, 0.0], np.stack([np.full(4, 70.0 * s), across], axis=1)])
        sds = np.vstack([[28.0 * s, 26.0 * s], np.tile([16.0 * s, 7.0 * s], (4, 1))])
        return Footprint(off, sds, np.array([0.6, 0.1, 0.1, 0.1, 0.1]))
    if primitive == "wrap":
        # palm band at the contact point, fingers on the far side of the
        # curved surface (across), thumb opposite them
        along = (np.arange(4) - 1.5) * FINGER_SPACING_MM * s
        off = np.vstack([[0.0, 0.0], np.stack([along, np.full(4, 75.0 * s)], axis=1), [[0.0, -60.0 * s]]])
        sds = np.vstack([[30.0 * s, 40.0 * s], np.tile([7.0 * s, 16.0 * s], (4, 1)), [[9.0 * s, 12.0 * s]]])
        share = np.array([0.5, 0.1, 0.1, 0.1, 0.1, 0.1])
        return Footprint(off, sds, share, conform=True)
    if primitive == "pinch":
        gap = 30.0 * s
        off = np.array([[0.0, -gap / 2], [0.0, gap / 2]])
        return Footprint(off, np.full((2, 2), 5.0 * s), np.full(2, 0.5), closing=np.array([1.0, -1.0]))
    raise ValueError(f"unknown primitive {primitive!r}")


def force_profile(t: np.ndarray, onset, dur, rise, fall) -> np.ndarray:
    """Force envelope of each event (rows) at times ``t`` (columns), 0..1.

    A raised-cosine rise over ``rise`` s, hold, a raised-cosine fall over
    ``fall`` s ending at ``onset + dur``; zero outside the event.
    """
    tau = np.asarray(t, dtype=np.float64)[None, :] - np.asarray(onset, dtype=np.float64)[:, None]
    d = np.asarray(dur, dtype=np.float64)[:, None]
    r = np.maximum(np.asarray(rise, dtype=np.float64)[:, None], 1e-9)
    f = np.maximum(np.asarray(fall, dtype=np.float64)[:, None], 1e-9)
    m = np.minimum(np.minimum(tau / r, (d - tau) / f), 1.0)
    return np.sin(0.5 * np.pi * np.maximum(m, 0.0)) ** 2


@dataclass
class Tracks:
    """Blobs over time: centres ``cx, cy`` (B, T) in mm, force (B, T) in N,
    sds ``sdx, sdy`` (B,) in mm (axis-aligned), ``conform`` (B,) bool."""

    cx: np.ndarray
    cy: np.ndarray
    force: np.ndarray
    sdx: np.ndarray
    sdy: np.ndarray
    conform: np.ndarray

    def __len__(self) -> int:
        return self.force.shape[0]


def wobble(n: int, t: np.ndarray, amount: float, hz: float, rng: np.random.Generator) -> np.ndarray:
    """Slow independent fluctuation of the force of a primitive's ``n``
    blobs, (n, T) factors around 1 with sd ``amount``: each a sum of three
    sinusoids at random frequencies 0.5..1.5 x ``hz`` and random phases (the
    pressure under a hand shifts between heel, palm and fingers as it
    moves). Clipped at 0."""
    f = hz * rng.uniform(0.5, 1.5, (n, 3))
    ph = rng.uniform(0.0, _TWO_PI, (n, 3))
    s = np.sin(_TWO_PI * f[:, :, None] * t[None, None, :] + ph[:, :, None]).sum(axis=1) / np.sqrt(1.5)
    return np.maximum(1.0 + amount * s, 0.0)


def tracks(ev: Events, fp: Footprint, t: np.ndarray, rng: np.random.Generator | None = None) -> Tracks:
    """The blobs of every event of ``ev`` with footprint ``fp`` at times
    ``t``; ``rng`` draws the wobble (``ev.wobble`` > 0)."""
    T = len(t)
    if len(ev) and T:
        live = (ev.onset < t[-1]) & (ev.onset + ev.dur > t[0])
        if not live.all():
            ev = ev.select(live)
    E, J = len(ev), len(fp)
    if E == 0 or J == 0:
        z = np.zeros((0, T))
        return Tracks(z, z, z, np.zeros(0), np.zeros(0), np.zeros(0, dtype=bool))
    env = force_profile(t, ev.onset, ev.dur, ev.rise, ev.fall)  # (E, T)
    tau = t[None, :] - ev.onset[:, None]
    if np.any(ev.knead_depth > 0):
        k = ev.knead_depth[:, None]
        env = env * (1.0 - k / 2 + (k / 2) * np.cos(_TWO_PI * ev.knead_hz[:, None] * tau + ev.knead_phase[:, None]))
    force_e = ev.peak[:, None] * env
    progress = np.minimum(np.maximum(tau / ev.dur[:, None], 0.0), 1.0)
    osc = ev.osc_amp[:, None] * np.sin(_TWO_PI * ev.osc_hz[:, None] * tau + ev.osc_phase[:, None])
    ux, uy = np.cos(ev.angle), np.sin(ev.angle)  # along
    vx, vy = -uy, ux  # across
    ex = ev.x0[:, None] + ev.gx[:, None] * progress + osc * ux[:, None]  # (E, T)
    ey = ev.y0[:, None] + ev.gy[:, None] * progress + osc * uy[:, None]
    oa, oc = fp.offsets[:, 0], fp.offsets[:, 1]  # (J,)
    # blob centre = event centre + along * u + across * v  -> (E, J, T)
    bx = ex[:, None, :] + (oa[None, :] * ux[:, None] + oc[None, :] * vx[:, None])[:, :, None]
    by = ey[:, None, :] + (oa[None, :] * uy[:, None] + oc[None, :] * vy[:, None])[:, :, None]
    if fp.closing is not None:
        # fingers close over the rise: each moves half of ``closing`` toward the other
        close = np.minimum(np.maximum(tau / np.maximum(ev.rise[:, None], 1e-9), 0.0), 1.0) * (ev.closing[:, None] / 2)
        bx = bx + fp.closing[None, :, None] * close[:, None, :] * vx[:, None, None]
        by = by + fp.closing[None, :, None] * close[:, None, :] * vy[:, None, None]
    force = force_e[:, None, :] * fp.share[None, :, None]
    if ev.wobble > 0 and rng is not None:
        force = force * wobble(J, t, ev.wobble, ev.wobble_hz, rng)[None, :, :]
    sa, sc = fp.sds[:, 0][None, :], fp.sds[:, 1][None, :]
    c2, s2 = (ux**2)[:, None], (uy**2)[:, None]
    sdx = np.sqrt(sa**2 * c2 + sc**2 * s2)
    sdy = np.sqrt(sa**2 * s2 + sc**2 * c2)
    B = E * J
    return Tracks(
        cx=bx.reshape(B, T),
        cy=by.reshape(B, T),
        force=force.reshape(B, T),
        sdx=sdx.reshape(B),
        sdy=sdy.reshape(B),
        conform=np.full(B, fp.conform),
    )


def active(tr: Tracks, threshold: float = 1e-6) -> Tracks:
    """Only the blobs that carry force at some frame."""
    keep = tr.force.max(axis=1, initial=0.0) > threshold if len(tr) else np.zeros(0, dtype=bool)
    if keep.all():
        return tr
    return Tracks(tr.cx[keep], tr.cy[keep], tr.force[keep], tr.sdx[keep], tr.sdy[keep], tr.conform[keep])


_K = float(np.sqrt(2.0 / np.pi))


def normal_cdf(z: np.ndarray) -> np.ndarray:
    """The standard normal CDF to within 2e-4 (the tanh form,
    0.5 (1 + tanh(sqrt(2/pi) (z + 0.044715 z^3)))): monotone, exact at 0
    and in the tails, and an order of magnitude faster than
    ``scipy.special.ndtr``. A footprint is a bell whose CDF this is."""
    return 0.5 + 0.5 * np.tanh(_K * (z + 0.044715 * z * z * z))


def _cell_weights(c: np.ndarray, sd: np.ndarray, n: int) -> np.ndarray:
    """Fraction of each blob's mass over each of ``n`` cells: (N, n).

    ``c`` (N,) and ``sd`` (N,) are in cell units, cell i spans
    [i - 0.5, i + 0.5].
    """
    edges = np.arange(n + 1, dtype=np.float64) - 0.5
    cdf = normal_cdf((edges[None, :] - c[:, None]) / np.maximum(sd, 1e-6)[:, None])
    return cdf[:, 1:] - cdf[:, :-1]


# a blob carrying less than this (N) at a frame is not rendered there
RENDER_FLOOR_N = 1e-4


def render(
    tr: Tracks,
    grid: tuple[int, int],
    pitch_mm: float,
    line_filter: Callable[[np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:
    """Force per cell (N), (T, H, W) float64: each blob integrated over each
    cell's area. Force falling outside the grid is lost (off the sensor).

    Only the (frame, blob) pairs that carry force (above
    :data:`RENDER_FLOOR_N`) are computed: a pat's hand touches a few frames
    of each period, and the rest costs nothing. ``line_filter`` (a linear
    map along the last axis, such as the sensor's line cross-talk) is
    applied to every blob's row and column profiles: the same as applying
    it to the rendered field along both axes, at a fraction of the cost.
    """
    H, W = grid
    T = tr.force.shape[1]
    field = np.zeros((T, H, W))
    if len(tr) == 0:
        return field
    on_t, on_b = np.nonzero(tr.force.T > RENDER_FLOOR_N)  # sorted by frame
    n = on_t.size
    if n == 0:
        return field
    cx = tr.cx[on_b, on_t] / pitch_mm - 0.5
    cy = tr.cy[on_b, on_t] / pitch_mm - 0.5
    wx = np.zeros((n + 1, W))  # a last row of zeros pads frames with fewer blobs
    wy = np.zeros((n + 1, H))
    wx[:n] = _cell_weights(cx, tr.sdx[on_b] / pitch_mm, W)
    wy[:n] = _cell_weights(cy, tr.sdy[on_b] / pitch_mm, H) * tr.force[on_b, on_t][:, None]
    if line_filter is not None:
        wx, wy = line_filter(wx), line_filter(wy)
    # (frame, slot) -> pair index, padded: then one batched matmul over frames
    counts = np.bincount(on_t, minlength=T)
    m = int(counts.max())
    starts = np.cumsum(counts) - counts
    slot = np.arange(n) - starts[on_t]
    idx = np.full((T, m), n)
    idx[on_t, slot] = np.arange(n)
    return np.matmul(wy[idx].transpose(0, 2, 1), wx[idx])  # (T, H, m) @ (T, m, W)
