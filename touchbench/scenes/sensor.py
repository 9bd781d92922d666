"""The sensor stack: cover, substrate and curvature act on the contact
blobs; cross-talk, gain, saturation, tension, baseline, noise and the ADC
act on the rendered force field. Each is a small function, applied only
when the scene lists its effect.

Order (top to bottom of the physical stack, then the electronics):

1. cover (:func:`apply_cover`): the pile absorbs ``deadband_n`` newtons,
   transmits a fraction of the rest and blurs the contact (sd added in
   quadrature) - it lowers the peak;
2. substrate (:func:`apply_substrate`): a soft substrate spreads the contact
   and delays the force (first-order lag, time constant ``delay_s``);
3. curvature (:func:`apply_curvature`): a flat contact on a cylinder of
   radius R touches only a strip: its sd round the circumference is
   limited to about 0.35 R; a wrapping hand conforms and keeps its size;
4. render (hand.py) to force per cell;
5. cross-talk (:func:`crosstalk`): neighbouring rows and columns of the
   matrix leak into each other (``c`` from each 4-neighbour, ``c**2`` from
   each diagonal one); applied during rendering, to each blob's row and
   column profiles, which is the same and cheaper;
6. gain to ADC counts; soft saturation ``S (1 - exp(-x / S))``
   (:func:`saturate`): linear for light touch, flattening toward S;
7. tension: a sensor stretched over a curve reads a resting pressure of
   ``tension`` counts on average, through the same line sensitivities as
   the baseline when the scene has one (the real HAART's curved no-touch
   recordings repeat its flat row pattern, about 4x higher), else along
   the crest profile of :func:`tension`; baseline
   (:func:`baseline_pattern`): resting offset per cell; noise
   (:func:`add_noise`): Gaussian read noise of sd ``noise_sd`` counts (white; an AR(1)
   wander along the frames when asked, as the shift augmentation of
   :mod:`touchbench.classifiers.augment` does);
8. ADC (:func:`adc`): round, clip to the value range, cast.

Steps 5-8 run in float32 (counts up to a few thousand keep a resolution
far below one count).

The channel sensor of Flagg (2012, Sec. 4.2) reduces the field to x, y,
pressure and fur readings (:func:`to_channels`).

Interpretations: cross-talk as leakage between neighbouring lines (the
papers give no figures); curvature narrowing at 0.35 R (the chord of a cylinder within
which a flat palm pressed with moderate force stays in contact).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from .hand import Tracks

CURVE_CONTACT = 0.35


def apply_cover(tr: Tracks, transmission: float, blur_mm: float, deadband_n: float = 0.0) -> Tracks:
    """A cover over the sensor: absorbs ``deadband_n`` of each blob's force,
    transmits ``transmission`` of the rest, blurs by ``blur_mm``."""
    force = tr.force
    if deadband_n > 0:
        force = np.maximum(force - deadband_n * _share(tr), 0.0)
    force = force * transmission
    return Tracks(tr.cx, tr.cy, force, np.hypot(tr.sdx, blur_mm), np.hypot(tr.sdy, blur_mm), tr.conform)


def _share(tr: Tracks) -> np.ndarray:
    """Each blob's share of its moment's total force, so a deadband in N
    applies to the hand's total, not to each blob separately."""
    tot = tr.force.sum(axis=0, keepdims=True)
    return np.divide(tr.force, tot, out=np.zeros_like(tr.force), where=tot > 0)


def lag(x: np.ndarray, tau_s: float, frame_rate: float) -> np.ndarray:
    """First-order low-pass along the last axis, time constant ``tau_s``,
    started at rest (zero)."""
    if tau_s <= 0 or x.size == 0:
        return x
    a = float(np.exp(-1.0 / (tau_s * frame_rate)))
    return lfilter([1.0 - a], [1.0, -a], x, axis=-1)


def apply_substrate(tr: Tracks, spread_mm: float, delay_s: float, gain: float, frame_rate: float) -> Tracks:
    """A soft substrate: widens each contact by ``spread_mm``, delays the
    force by a first-order lag of time constant ``delay_s`` (started at
    rest: give the tracks some lead-in before the capture), scales it by
    ``gain``."""
    force = lag(tr.force, delay_s, frame_rate) * gain
    return Tracks(tr.cx, tr.cy, force, np.hypot(tr.sdx, spread_mm), np.hypot(tr.sdy, spread_mm), tr.conform)


def apply_curvature(tr: Tracks, radius_mm: float, axis: str) -> Tracks:
    """Flat contacts on a cylinder whose circumference runs along ``axis``
    narrow round it (sd -> sd / sqrt(1 + (sd / 0.35 R)^2)); conforming
    blobs (a wrapping hand) keep their size. Force is kept."""
    lim = CURVE_CONTACT * radius_mm
    sdx, sdy = tr.sdx, tr.sdy
    flat = ~tr.conform
    if axis == "x":
        sdx = np.where(flat, sdx / np.sqrt(1.0 + (sdx / lim) ** 2), sdx)
    else:
        sdy = np.where(flat, sdy / np.sqrt(1.0 + (sdy / lim) ** 2), sdy)
    return Tracks(tr.cx, tr.cy, tr.force, sdx, sdy, tr.conform)


def crosstalk_lines(w: np.ndarray, c: float) -> np.ndarray:
    """Leakage between neighbouring lines along the last axis: each line
    picks up ``c`` times each neighbour's value."""
    if c <= 0:
        return w
    leak = w * np.asarray(c, dtype=w.dtype)
    out = w.copy()
    out[..., 1:] += leak[..., :-1]
    out[..., :-1] += leak[..., 1:]
    return out


def crosstalk(field: np.ndarray, c: float) -> np.ndarray:
    """Cross-talk of a scanned matrix (T, H, W): leakage ``c`` between
    neighbouring rows and between neighbouring columns, so a cell picks up
    ``c`` of each 4-neighbour and ``c**2`` of each diagonal one. The
    generator applies the same operator to each blob's row and column
    profiles (``render(..., line_filter=...)``), which is equivalent."""
    if c <= 0:
        return field
    return np.swapaxes(crosstalk_lines(np.swapaxes(crosstalk_lines(field, c), -1, -2), c), -1, -2)


def saturate(x: np.ndarray, level: float) -> np.ndarray:
    """Soft saturation ``level * (1 - exp(-x / level))``; slope 1 at 0."""
    lv = np.asarray(level, dtype=x.dtype) if isinstance(x, np.ndarray) else level
    return lv * -np.expm1(-x / lv)


def tension(grid: tuple[int, int], level: float, axis: str) -> np.ndarray:
    """Resting pressure of a sensor stretched round a curve: highest along
    the crest (the middle of the circumference axis), falling to half at
    the edges. (H, W) counts."""
    H, W = grid
    n = W if axis == "x" else H
    u = (np.arange(n) - (n - 1) / 2) / max((n - 1) / 2, 1)
    prof = level * (1.0 - 0.5 * u**2)
    return np.broadcast_to(prof[None, :] if axis == "x" else prof[:, None], (H, W)).copy()


def baseline_pattern(
    grid: tuple[int, int], level: float, spread: float, rng: np.random.Generator, lines: bool = False
) -> np.ndarray:
    """Resting offsets, mean ``level``, (H, W) counts. Per cell: gamma with
    coefficient of variation ``spread``; ``lines``: the product of a row
    and a column factor, each gamma with that spread (a scanned matrix
    sensor's offsets follow its row and column lines, as the real HAART
    no-touch recordings show). ``spread`` 0: uniform."""
    if spread <= 0:
        return np.full(grid, float(level))
    k = 1.0 / spread**2
    if lines:
        rows = rng.gamma(k, 1.0 / k, size=grid[0])
        cols = rng.gamma(k, 1.0 / k, size=grid[1])
        return level * rows[:, None] * cols[None, :]
    return rng.gamma(k, level / k, size=grid)


def add_noise(x: np.ndarray, sd: float, rng: np.random.Generator, ar: float = 0.0) -> np.ndarray:
    """Gaussian read noise of standard deviation ``sd``: white, or with ``0 < ar < 1`` an AR(1)
    process along the first axis (frames), ``e_t = ar e_(t-1) + sqrt(1 - ar^2) w_t``, started
    from its stationary distribution (``e_0 = w_0``), so its standard deviation is ``sd`` at
    every frame and only its spectrum changes (a slow wander for ``ar`` near 1)."""
    if sd <= 0:
        return x
    noise = rng.standard_normal(x.shape, dtype=np.float32)
    if ar > 0 and len(noise) > 1:
        b = np.float32(np.sqrt(1.0 - ar * ar))
        zi = (np.float32(1.0) - b) * noise[:1]  # so that e_0 = w_0
        noise = lfilter([b], [np.float32(1.0), np.float32(-ar)], noise, axis=0, zi=zi)[0].astype(np.float32)
    noise *= np.float32(sd)
    noise += x
    return noise


def adc(x: np.ndarray, value_range: tuple[float, float], dtype: str) -> np.ndarray:
    """Round to integers (integer dtypes), clip to the ADC range, cast."""
    lo, hi = value_range
    dt = np.dtype(dtype)
    if dt.kind in "iu":
        x = np.rint(x)
    return np.clip(x, lo, hi).astype(dt)


# ------------------------------------------------------------ channel sensor
def to_channels(
    field: np.ndarray,
    tr: Tracks,
    *,
    frame_rate: float,
    pressure_gain: float,
    fur_motion_gain: float,
    fur_touch_gain: float,
    contact_n: float,
    rest: dict[str, float],
    value_range: tuple[float, float],
) -> np.ndarray:
    """Flagg's sensor (2012, Sec. 4.2): x, y, pressure, fur; (T, 4) counts
    before noise and ADC.

    - pressure: ``pressure_gain`` x the total force on the fabric, over the
      resting reading (the fur's weight biases it, Sec. 4.2.3);
    - x, y: the force-weighted centroid mapped onto the value range while
      the total force exceeds ``contact_n``, else the resting reading;
    - fur: the conductive fur responds to light touch without pressure and
      to hand motion through it (Sec. 3.2): touch activity A = 1 - prod(1 -
      a_b) with a_b = F_b / (F_b + 0.5 N) for each contact b, times
      (``fur_touch_gain`` + ``fur_motion_gain`` x the force-weighted mean
      speed of the contacts, mm/s).
    """
    T, H, W = field.shape
    lo, hi = value_range
    total = field.sum(axis=(1, 2))
    safe = np.where(total > 0, total, 1.0)
    cxf = (field.sum(axis=1) * np.arange(W)).sum(axis=1) / safe
    cyf = (field.sum(axis=2) * np.arange(H)).sum(axis=1) / safe
    touching = total > contact_n
    x = np.where(touching, lo + (hi - lo) * (cxf + 0.5) / W, rest["x"])
    y = np.where(touching, lo + (hi - lo) * (cyf + 0.5) / H, rest["y"])
    pressure = rest["pressure"] + pressure_gain * total
    fur = np.full(T, rest["fur"], dtype=np.float64)
    if len(tr):
        # touch activity: each contact touches the fur with probability
        # F / (F + 0.5 N); the hand touches it if any contact does
        activity = 1.0 - np.prod(0.5 / (tr.force + 0.5), axis=0)
        if T > 1:
            speed = np.hypot(np.gradient(tr.cx, axis=1), np.gradient(tr.cy, axis=1)) * frame_rate
        else:
            speed = np.zeros_like(tr.cx)
        ftot = tr.force.sum(axis=0)
        mean_speed = np.divide((tr.force * speed).sum(axis=0), ftot, out=np.zeros(T), where=ftot > 0)
        fur = fur + activity * (fur_motion_gain * mean_speed + fur_touch_gain)
    return np.stack([x, y, pressure, fur], axis=1)
