"""Feature sets of touchbench's own methods: rhythm, cell rhythm, contact motion.

Not from a paper: designed for HAART (docs/research/touch-methods.md has the
inner cross-validation evidence behind each choice). They follow Gaus et al.
2015, Sec. 5, who note that pat, tickle, scratch and stroke
differ in rhythm and movement more than in pressure, and the frame-level
descriptors of Zhou et al. 2017, Sec. 4.1 (total pressure,
contact area, centroid). Three sets, each cheap and vectorised over
captures, frames and cells:

- ``touch-rhythm``: eleven frame-level series (total pressure, its log and
  its level-normalised form, peak cell, contact area, centroid row and
  column, spread along each axis, centroid speed, absolute change of total
  pressure), each summarised by order statistics, moments, first
  differences, mean-crossing rate, normalised band powers of the spectrum,
  spectral peak / centroid / entropy and the autocorrelation at seven lags;
  plus capture scalars (baseline, peak, activity, centroid path) and
  position-free per-cell statistics (cell means, standard deviations and
  mean absolute changes sorted over cells, read at fixed ranks).
- ``cell-rhythm``: every cell's spectrum, pooled with the cells' power as
  weights (band fractions, peak / centroid frequency, mean-crossing rate),
  the coherence of the cells (power of the sum over sum of the powers: a
  contact moving across cells has low coherence), the correlation of
  neighbouring cells' series and the number of contact blobs per frame.
- ``contact-motion``: contact above 10 %, 30 % and 50 % of the capture's
  robust peak: fraction of active frames, touch onsets, area, centroid
  speed, range and path, back-and-forth reversals along the main axis of
  motion, spectrum of the position along that axis and of the on/off
  activity.

Common preprocessing (every set): values as float64; each cell's baseline
is its 5 % lower order statistic over the capture's frames (the value of
rank ``floor(0.05 * (T - 1))``, 0-based; an interpretation: the sensor's
resting level under a cover differs per cell and per substrate/cover, and
a capture is never pressed on every cell all the time); the pressure is
the value above the baseline, clipped at 0. Higher values mean more
pressure (HAART after the reader's ``1023 - value``).

Interpretations and limits shared by the sets:

- Frequencies use the sensor's frame rate (``sensor.frame_rate``; the
  run engine passes the dataset's sensor). An explicit ``frame_rate``
  replaces it (for use from Python without a sensor); with neither, the
  set refuses to run rather than assume one sensor's rate. Band edges are
  in Hz, so a capture's band fractions do not depend on its length;
  spectra use a Hann window on the mean-removed series. Bands above the
  sensor's Nyquist frequency hold no power (0 on a 12 Hz sensor above
  6 Hz); autocorrelation lags and ``MIN_FRAMES`` are frames.
- Contact floors scale with the sensor's value range: the absolute floors
  against noise (``touch-rhythm``'s contact area and ``cell-rhythm``'s
  blobs: 3, ``contact-motion``: 4) were chosen on HAART's 0..1023 and are
  kept as the same fraction of full scale, ``floor * (hi - lo) / 1023``
  (0.29 % and 0.39 %: 0.75 and 1.0 on a 0..255 sensor, so on integer data
  any pressure of 1 counts). The value range is the sensor's
  (``value_range`` replaces it from Python); with neither, the set
  refuses to run. Everything else is relative (fractions of the capture's
  peak, ranks over cells) or in cells of the grid, so the sets serve any
  grid.
- A capture shorter than ``MIN_FRAMES`` (8) frames is padded by repeating
  its last frame (a held pose), so every statistic is defined; its
  features then describe a nearly constant capture.
- Undefined ratios (a series with no variation, no power, no contact)
  take the limit "nothing happens": fractions and correlations 0, peak
  frequencies 0, moments as :mod:`touchbench.features.numerics` (skewness
  0, kurtosis 3). Every feature is finite for finite input.
- No set learns from data (``fold_dependent = False``): a capture's
  features depend on that capture alone, never on its batch.
"""

from __future__ import annotations

import numpy as np

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, SensorNeededError
from .numerics import KURT_CONSTANT, SKEW_CONSTANT, moments

MIN_FRAMES = 8
BASELINE_Q = 0.05
#: the full scale on which the sets' absolute contact floors were chosen (HAART's 0..1023, in raw units)
FLOOR_SCALE = 1023.0
#: spectral bands in Hz, upper edge inclusive; the last one is open-ended
BANDS: tuple[tuple[float, float], ...] = ((0, 1), (1, 2), (2, 3), (3, 4.5), (4.5, 6), (6, 8), (8, 11), (11, 15), (15, np.inf))
AC_LAGS: tuple[int, ...] = (2, 4, 6, 9, 13, 18, 27)
QUANTS: tuple[int, ...] = (5, 25, 50, 75, 95)
CELL_RANKS: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 0.875, 0.9375, 1.0)
SERIES: tuple[str, ...] = ("P", "logP", "Pn", "M", "A", "cy", "cx", "sy", "sx", "speed", "dP")
THRESHOLDS: tuple[float, ...] = (0.1, 0.3, 0.5)
_EPS = 1e-12


def _band_name(lo: float, hi: float) -> str:
    return f"{lo:g}-{hi:g}Hz" if np.isfinite(hi) else f"{lo:g}Hz+"


class _TouchBase(FeatureSet):
    """Frame rate handling and the common preprocessing."""

    paper = "touchbench (docs/research/touch-methods.md), after Gaus et al. 2015 section 5 and Zhou et al. 2017 section 4.1"
    cost = "cheap"
    fold_dependent = False

    def __init__(self, frame_rate: float | None = None, value_range: tuple[float, float] | None = None,
                 sensor: SensorSpec | None = None):
        self.frame_rate = frame_rate
        self.value_range = value_range
        self.sensor = sensor

    def _fs(self) -> float:
        """The frame rate: ``frame_rate`` if given, else the sensor's; neither is refused."""
        if self.frame_rate is not None:
            return float(self.frame_rate)
        if self.sensor is not None:
            return float(self.sensor.frame_rate)
        raise SensorNeededError(
            f"{type(self).__name__}: needs the sensor's frame rate (its spectral bands are in Hz): "
            "pass sensor=SensorSpec(...) or frame_rate=..."
        )

    def _range(self) -> tuple[float, float]:
        """The value range: ``value_range`` if given, else the sensor's; neither is refused."""
        if self.value_range is not None:
            lo, hi = (float(v) for v in self.value_range)
            return lo, hi
        if self.sensor is not None:
            lo, hi = self.sensor.value_range
            return float(lo), float(hi)
        raise SensorNeededError(
            f"{type(self).__name__}: needs the sensor's value range (its contact floors are fractions of full scale): "
            "pass sensor=SensorSpec(...) or value_range=(low, high)"
        )

    def _floor(self, haart_units: float) -> float:
        """A contact floor chosen on HAART's 0..1023, as the same fraction of this sensor's full scale."""
        lo, hi = self._range()
        return haart_units * (hi - lo) / FLOOR_SCALE

    def _check_params(self) -> None:
        fs = self.frame_rate
        if fs is not None and not (isinstance(fs, (int, float)) and np.isfinite(fs) and fs > 0):
            raise FeatureInputError(f"{type(self).__name__}: frame_rate must be a positive number, got {fs!r}")
        vr = self.value_range
        if vr is not None:
            try:
                lo, hi = (float(v) for v in vr)
                ok = np.isfinite(lo) and np.isfinite(hi) and lo < hi
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise FeatureInputError(f"{type(self).__name__}: value_range must be (low, high) with low < high, got {vr!r}")
        self._fs()
        self._range()


def pressure(stack: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(N, T, H, W)`` -> pressure above baseline ``(N, T', H*W)`` float64 and baseline ``(N, H*W)``.

    Captures shorter than ``MIN_FRAMES`` are padded by repeating the last
    frame first (T' = max(T, MIN_FRAMES)).
    """
    n, t, h, w = stack.shape
    c = np.asarray(stack, dtype=np.float64).reshape(n, t, h * w)
    if t < MIN_FRAMES:
        c = np.concatenate([c, np.repeat(c[:, -1:], MIN_FRAMES - t, axis=1)], axis=1)
        t = MIN_FRAMES
    k = int(np.floor(BASELINE_Q * (t - 1)))
    base = np.partition(c, k, axis=1)[:, k]
    s = c - base[:, None, :]
    np.maximum(s, 0.0, out=s)
    return s, base


def _hann(t: int) -> np.ndarray:
    return np.hanning(t) if t > 1 else np.ones(1)


def spectrum(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Power spectrum (DC removed) of the mean-removed, Hann-windowed series along axis -1; frequencies."""
    t = x.shape[-1]
    d = x - x.mean(axis=-1, keepdims=True)
    d[x.max(axis=-1) == x.min(axis=-1)] = 0.0  # a constant series has no spectrum (exactly)
    p = np.abs(np.fft.rfft(d * _hann(t), axis=-1)) ** 2
    f = np.fft.rfftfreq(t, 1.0 / fs)
    return p[..., 1:], f[1:]


def band_sum(p: np.ndarray, f: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Sum of ``p`` over the frequencies in (lo, hi], along the last axis.

    Summed in frequency order (a cumulative sum), so a capture's value never
    depends on how many captures share its batch: numpy's plain ``sum``
    may change its summation order with the array's shape.
    """
    m = np.flatnonzero((f > lo) & (f <= hi))
    if m.size == 0:
        return np.zeros(p.shape[:-1])
    return np.cumsum(p[..., m[0]:m[-1] + 1], axis=-1)[..., -1]


def spectral_summary(p: np.ndarray, f: np.ndarray) -> dict[str, np.ndarray]:
    """Band fractions, peak / centroid frequency, normalised entropy and log power of ``p`` (..., F)."""
    tot = p.sum(axis=-1)
    none = tot <= 0
    safe = np.where(none, 1.0, tot)
    out: dict[str, np.ndarray] = {}
    for lo, hi in BANDS:
        out[f"band{_band_name(lo, hi)}"] = np.where(none, 0.0, band_sum(p, f, lo, hi) / safe)
    if p.shape[-1]:
        out["fpeak"] = np.where(none, 0.0, f[np.argmax(p, axis=-1)])
    else:
        out["fpeak"] = np.zeros(p.shape[:-1])
    out["fcent"] = np.where(none, 0.0, (p * f).sum(axis=-1) / safe)
    q = p / safe[..., None]
    ent = -(q * np.log(np.where(q > 0, q, 1.0))).sum(axis=-1)
    out["fent"] = np.where(none, 0.0, ent / np.log(max(p.shape[-1], 2)))
    out["logpow"] = np.log1p(np.where(none, 0.0, tot))
    return out


def _series_stats(s: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    """Statistics of series ``s`` (N, K, T) -> dict of (N, K) arrays (see the module docstring)."""
    t = s.shape[-1]
    srt = np.sort(s, axis=-1)
    mo = moments(srt.copy(), presorted=True, overwrite=True)
    mu = mo["mean"]
    d = s - mu[..., None]
    sd = np.sqrt(np.einsum("...i,...i->...", d, d) / t)
    out: dict[str, np.ndarray] = {"mean": mu, "std": sd}
    for q in QUANTS:
        out[f"p{q}"] = srt[..., int(round(q / 100 * (t - 1)))]
    out["max"] = srt[..., -1]
    out["skew"] = mo["skew"]
    out["kurt"] = mo["kurt"]
    dd = np.diff(s, axis=-1)
    mad1 = np.abs(dd).mean(axis=-1)
    out["mad1"] = mad1
    out["dstd"] = dd.std(axis=-1)
    flat = sd <= _EPS * (1.0 + np.abs(mu))
    out["cv"] = np.where(flat, 0.0, sd / np.maximum(np.abs(mu), sd * 1e-6 + _EPS))
    out["madn"] = np.where(flat, 0.0, mad1 / np.where(flat, 1.0, sd))
    above = d > 0
    out["mcr"] = np.where(flat, 0.0, (above[..., 1:] != above[..., :-1]).mean(axis=-1))
    p, f = spectrum(s, fs)
    for k, v in spectral_summary(p, f).items():
        out[k] = v
    ac0 = np.einsum("...i,...i->...", d, d)
    safe = np.where(flat, 1.0, ac0)
    for lag in AC_LAGS:
        if lag < t:
            ac = np.einsum("...i,...i->...", d[..., lag:], d[..., :-lag]) / safe
        else:
            ac = np.zeros_like(ac0)
        out[f"ac{lag}"] = np.where(flat, 0.0, ac)
    return out


_STAT_NAMES: list[str] = (
    ["mean", "std"] + [f"p{q}" for q in QUANTS]
    + ["max", "skew", "kurt", "mad1", "dstd", "cv", "madn", "mcr"]
    + [f"band{_band_name(lo, hi)}" for lo, hi in BANDS] + ["fpeak", "fcent", "fent", "logpow"]
    + [f"ac{lag}" for lag in AC_LAGS]
)


def _grid_coords(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    yy, xx = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64), indexing="ij")
    return yy.ravel(), xx.ravel()


@FEATURES.register("touch-rhythm", description="rhythm, level and movement statistics of 11 frame-level series (touchbench)")
class TouchRhythm(_TouchBase):
    """``touch-rhythm``: statistics and spectra of frame-level series, capture scalars, cell ranks.

    Series per frame (pressure ``S`` above baseline, module docstring):
    ``P`` total pressure; ``logP`` = log(1 + P); ``Pn`` = P / mean(P) (level
    free; 0 when the capture has no pressure); ``M`` peak cell; ``A`` contact
    area = cells above max(20 % of the capture's peak, ``AREA_FLOOR``)
    (an absolute floor of 3 ADC units of HAART's 0..1023 against noise, an
    interpretation; scaled to the sensor's range, module docstring);
    ``cy``, ``cx`` pressure-weighted centroid (grid centre for an empty
    frame, as :func:`touchbench.features.numerics.weighted_centroid`);
    ``sy``, ``sx`` spread (weighted standard deviation of the row / column);
    ``speed`` centroid speed (cells per frame, central differences) in frames
    whose total pressure exceeds the area threshold, else 0; ``dP`` absolute
    change of P.

    Per series: mean, std, the 5/25/50/75/95 % order statistics (rank
    ``round(q (T-1))``), max, skewness, kurtosis, mean absolute and std of
    first differences, coefficient of variation, mad1/std, mean-crossing
    rate, nine band fractions, peak and centroid frequency, normalised
    spectral entropy, log power, autocorrelation at lags 2..27 frames.

    Capture scalars: mean and max baseline, peak pressure and its log,
    fraction of frames above 20 % of the peak total pressure, centroid path
    length and net displacement, cell means / stds / mean absolute changes
    sorted over cells and read at ranks 0, 1/4, 1/2, 3/4, 7/8, 15/16, 1 of
    the cells, their sums, spatial gradient energy relative to pressure and
    temporal change relative to pressure.

    Interpretations: the module docstring's (baseline, padding, limits);
    the area floor of 3 ADC units is ours.
    """

    AREA_REL = 0.2
    AREA_FLOOR = 3.0  # HAART units (0..1023), scaled by _floor

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        names = [f"{s}_{k}" for s in SERIES for k in _STAT_NAMES]
        names += ["base_mean", "base_max", "peak", "logpeak", "active_frac", "path", "disp"]
        for c in ("cellmean", "cellstd", "celldiff"):
            names += [f"{c}_r{r:g}" for r in CELL_RANKS] + [f"{c}_sum"]
        names += ["grad_rel", "tdiff_rel"]
        return names

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, _, h, w = stack.shape
        s, base = pressure(stack)
        t = s.shape[1]
        fs = self._fs()
        c = np.asarray(stack, dtype=np.float64).reshape(n, -1, h * w)
        if c.shape[1] < t:
            c = np.concatenate([c, np.repeat(c[:, -1:], t - c.shape[1], axis=1)], axis=1)
        P = c.sum(axis=2)
        ps = s.sum(axis=2)
        M = c.max(axis=2)
        peak = s.max(axis=(1, 2))
        thr = np.maximum(self.AREA_REL * peak, self._floor(self.AREA_FLOOR))
        A = (s > thr[:, None, None]).sum(axis=2).astype(np.float64)
        yy, xx = _grid_coords(h, w)
        empty = ps <= 0
        safe = np.where(empty, 1.0, ps)
        cy = np.where(empty, (h - 1) / 2.0, np.einsum("ntc,c->nt", s, yy) / safe)
        cx = np.where(empty, (w - 1) / 2.0, np.einsum("ntc,c->nt", s, xx) / safe)
        sy = np.sqrt(np.maximum(np.where(empty, 0.0, np.einsum("ntc,c->nt", s, yy * yy) / safe - cy * cy), 0.0))
        sx = np.sqrt(np.maximum(np.where(empty, 0.0, np.einsum("ntc,c->nt", s, xx * xx) / safe - cx * cx), 0.0))
        vy = np.gradient(cy, axis=1)
        vx = np.gradient(cx, axis=1)
        speed = np.hypot(vx, vy) * (ps > thr[:, None])
        mean_ps = ps.mean(axis=1, keepdims=True)
        pn = np.where(mean_ps > 0, ps / np.where(mean_ps > 0, mean_ps, 1.0), 0.0)
        dP = np.abs(np.diff(P, axis=1, prepend=P[:, :1]))
        series = np.stack([P, np.log1p(ps), pn, M, A, cy, cx, sy, sx, speed, dP], axis=1)
        st = _series_stats(series, fs)
        cols = [st[k] for k in _STAT_NAMES]  # each (N, 11)
        block = np.stack(cols, axis=2).reshape(n, -1)  # series-major, matching feature_names
        extra = [base.mean(axis=1), base.max(axis=1), peak, np.log1p(peak)]
        pmax = ps.max(axis=1, keepdims=True)
        extra.append(np.where(pmax[:, 0] > 0, (ps > 0.2 * pmax).mean(axis=1), 0.0))
        extra.append(np.hypot(np.diff(cx, axis=1), np.diff(cy, axis=1)).sum(axis=1))
        extra.append(np.hypot(cx[:, -1] - cx[:, 0], cy[:, -1] - cy[:, 0]))
        ncell = h * w
        ranks = [int(round(r * (ncell - 1))) for r in CELL_RANKS]
        cm = np.sort(s.mean(axis=1), axis=1)
        cs = np.sort(s.std(axis=1), axis=1)
        ds_ = np.abs(np.diff(s, axis=1))
        cd = np.sort(ds_.mean(axis=1), axis=1)
        for v in (cm, cs, cd):
            extra += [v[:, r] for r in ranks] + [v.sum(axis=1)]
        g = s.reshape(n, t, h, w)
        grad = np.abs(np.diff(g, axis=3)).sum(axis=(2, 3)) + np.abs(np.diff(g, axis=2)).sum(axis=(2, 3))
        mp = ps.mean(axis=1)
        has = mp > 0
        extra.append(np.where(has, grad.mean(axis=1) / np.where(has, mp, 1.0), 0.0))
        tot = ps.sum(axis=1)
        extra.append(np.where(tot > 0, ds_.sum(axis=(1, 2)) / np.where(tot > 0, tot, 1.0), 0.0))
        return np.hstack([block, np.column_stack(extra)])


@FEATURES.register("cell-rhythm", description="per-cell spectra pooled by cell power, cell coherence, neighbour correlation, blobs (touchbench)")
class CellRhythm(_TouchBase):
    """``cell-rhythm``: rhythm seen by every cell, pooled without positions.

    Each cell's pressure series (mean removed, Hann window) has a power
    spectrum; the cells are pooled with weights proportional to their total
    (non-DC) power: weighted band fractions (the nine bands of
    ``touch-rhythm``), weighted centroid and peak frequency, the peak
    frequency of the most powerful cell, the weighted mean-crossing rate and
    the entropy of the cell weights (how spread the activity is). Coherence:
    power of the summed series over the sum of the cells' powers (1 when all
    cells move together, about 1/cells for independent cells, 0 for a capture
    without variation). Neighbour correlation: correlation of horizontally /
    vertically adjacent cells' series, weighted by the product of their
    standard deviations. Blobs: cells above max(50 % of the frame's maximum,
    ``BLOB_FLOOR``: 3 of HAART's 0..1023, scaled to the sensor's range) form
    a binary frame; nodes minus 4-neighbour edges approximates its
    number of connected components (exact for blobs without holes or
    2 x 2 squares, an interpretation kept for speed); mean over active
    frames and maximum, plus the mean number of such cells.

    Interpretations: the module docstring's (baseline, padding, limits);
    the blob count approximation above.
    """

    BLOB_FLOOR = 3.0  # HAART units (0..1023), scaled by _floor

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        return ([f"cell_band{_band_name(lo, hi)}" for lo, hi in BANDS]
                + ["cell_fcent", "cell_fpeak", "cell_fpeak_top", "coherence", "cell_pow_entropy", "cell_mcr",
                   "ncorr_h", "ncorr_v", "blobs_mean", "blobs_max", "blob_cells_mean"])

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, _, h, w = stack.shape
        s, _ = pressure(stack)
        t = s.shape[1]
        fs = self._fs()
        cells = np.swapaxes(s, 1, 2)  # (N, C, T)
        p, f = spectrum(cells, fs)  # (N, C, F)
        pw = p.sum(axis=2)  # (N, C)
        tot = pw.sum(axis=1)
        none = tot <= 0
        wc = np.where(none[:, None], 0.0, pw / np.where(none, 1.0, tot)[:, None])
        cellpow = np.where(pw > 0, pw, 1.0)
        feats = []
        for lo, hi in BANDS:
            feats.append((band_sum(p, f, lo, hi) / cellpow * wc).sum(axis=1))
        fc = (p * f).sum(axis=2) / cellpow
        feats.append((fc * wc).sum(axis=1))
        fp = f[np.argmax(p, axis=2)] if p.shape[2] else np.zeros(pw.shape)
        feats.append((fp * wc).sum(axis=1))
        feats.append(np.where(none, 0.0, fp[np.arange(n), np.argmax(pw, axis=1)]))
        d = cells - cells.mean(axis=2, keepdims=True)
        psum, _ = spectrum(d.sum(axis=1), fs)
        feats.append(np.where(none, 0.0, psum.sum(axis=1) / np.where(none, 1.0, tot)))
        feats.append(-(wc * np.log(np.where(wc > 0, wc, 1.0))).sum(axis=1))
        above = d > 0
        mcr = (above[:, :, 1:] != above[:, :, :-1]).mean(axis=2)
        feats.append((mcr * wc).sum(axis=1))
        g = d.reshape(n, h, w, t)
        sd = np.sqrt((g * g).sum(axis=3))
        for a, b in (((slice(None), slice(None), slice(1, None)), (slice(None), slice(None), slice(None, -1))),
                     ((slice(None), slice(1, None), slice(None)), (slice(None), slice(None, -1), slice(None)))):
            num = (g[a] * g[b]).sum(axis=3)
            wgt = sd[a] * sd[b]
            ok = wgt > 0
            corr = np.where(ok, num / np.where(ok, wgt, 1.0), 0.0)
            wsum = wgt.sum(axis=(1, 2)) if wgt.size else np.zeros(n)
            feats.append(np.where(wsum > 0, (corr * wgt).sum(axis=(1, 2)) / np.where(wsum > 0, wsum, 1.0), 0.0))
        fm = s.max(axis=2, keepdims=True)
        blob = (s > np.maximum(0.5 * fm, self._floor(self.BLOB_FLOOR))).reshape(n, t, h, w)
        nodes = blob.sum(axis=(2, 3))
        edges = (blob[:, :, :, 1:] & blob[:, :, :, :-1]).sum(axis=(2, 3)) + (blob[:, :, 1:, :] & blob[:, :, :-1, :]).sum(axis=(2, 3))
        act = nodes > 0
        comp = np.where(act, nodes - edges, 0)
        nact = np.maximum(act.sum(axis=1), 1)
        feats += [comp.sum(axis=1) / nact, comp.max(axis=1).astype(np.float64), nodes.sum(axis=1) / nact]
        return np.column_stack(feats)


@FEATURES.register("contact-motion", description="contact above 10/30/50 % of the peak: activity, area, speed, reversals, position spectrum (touchbench)")
class ContactMotion(_TouchBase):
    """``contact-motion``: how the contact moves, robust to the noise floor.

    The capture's robust peak is the 95 % order statistic (rank
    ``round(0.95 (T-1))``) of its per-frame maximum pressure. For each
    relative threshold r in 10 %, 30 %, 50 % (absolute floor
    ``CONTACT_FLOOR``: 4 ADC units of HAART's 0..1023, an interpretation
    against the sensor noise seen under fur, scaled to the sensor's range
    as the module docstring says), a frame is
    active when some cell exceeds the threshold; the contact weights are
    the pressure minus the threshold, clipped at 0. Per threshold: fraction
    of active frames, touch onsets (inactive -> active), mean area over
    active frames and maximum area, centroid speed (mean over consecutive
    active frames and its 90 % order statistic over all frame pairs, 0 when
    not both active), 5-95 % range of the centroid row and column (inactive
    frames take the mean active position, or the grid centre), path length,
    rate of direction reversals along the axis with the larger range, and
    the spectrum of the position along that axis (peak and centroid
    frequency, four band fractions 0-1.5, 1.5-3, 3-6, 6+ Hz) and of the
    on/off activity (peak and centroid frequency). Plus log(1 + robust peak).

    Interpretations: the module docstring's (baseline, padding, limits);
    the robust peak, the floor of 4 ADC units and the choice of the axis of
    larger range as the axis of motion are ours.
    """

    POS_BANDS: tuple[tuple[float, float], ...] = ((0, 1.5), (1.5, 3), (3, 6), (6, np.inf))
    CONTACT_FLOOR = 4.0  # HAART units (0..1023), scaled by _floor

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        names = []
        for r in THRESHOLDS:
            tag = f"t{int(round(r * 100))}"
            names += [f"{tag}_{k}" for k in ("actfrac", "onsets", "area_mean", "area_max", "speed_mean", "speed_p90",
                                             "range_y", "range_x", "path", "reversal", "pos_fpeak", "pos_fcent")]
            names += [f"{tag}_pos_band{_band_name(lo, hi)}" for lo, hi in self.POS_BANDS]
            names += [f"{tag}_act_fpeak", f"{tag}_act_fcent"]
        return names + ["logpeak_robust"]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, _, h, w = stack.shape
        s, _ = pressure(stack)
        t = s.shape[1]
        fs = self._fs()
        fmax = s.max(axis=2)
        peak = np.sort(fmax, axis=1)[:, int(round(0.95 * (t - 1)))]
        yy, xx = _grid_coords(h, w)
        rank = lambda a, q: np.sort(a, axis=1)[:, int(round(q * (a.shape[1] - 1)))]  # noqa: E731
        floor = self._floor(self.CONTACT_FLOOR)
        feats = []
        for r in THRESHOLDS:
            thr = np.maximum(r * peak, floor)
            wt = np.maximum(s - thr[:, None, None], 0.0)
            ws = wt.sum(axis=2)
            act = ws > 0
            safe = np.where(act, ws, 1.0)
            cy = np.einsum("ntc,c->nt", wt, yy) / safe
            cx = np.einsum("ntc,c->nt", wt, xx) / safe
            nact = act.sum(axis=1)
            any_act = nact > 0
            my = np.where(any_act, (cy * act).sum(axis=1) / np.maximum(nact, 1), (h - 1) / 2.0)
            mx = np.where(any_act, (cx * act).sum(axis=1) / np.maximum(nact, 1), (w - 1) / 2.0)
            cy = np.where(act, cy, my[:, None])
            cx = np.where(act, cx, mx[:, None])
            area = (wt > 0).sum(axis=2).astype(np.float64)
            both = act[:, 1:] & act[:, :-1]
            vy = np.diff(cy, axis=1)
            vx = np.diff(cx, axis=1)
            sp = np.hypot(vx, vy) * both
            nb = np.maximum(both.sum(axis=1), 1)
            ry = rank(cy, 0.95) - rank(cy, 0.05)
            rx = rank(cx, 0.95) - rank(cx, 0.05)
            major_y = (ry >= rx)[:, None]
            vmaj = np.where(major_y, vy, vx) * both
            sg = np.sign(vmaj)
            nz = (sg != 0).sum(axis=1)
            rev = ((sg[:, 1:] * sg[:, :-1]) < 0).sum(axis=1)
            feats += [act.mean(axis=1), (np.diff(act.astype(np.int8), axis=1) == 1).sum(axis=1).astype(np.float64),
                      area.sum(axis=1) / np.maximum(nact, 1), area.max(axis=1), sp.sum(axis=1) / nb, rank(sp, 0.9),
                      ry, rx, sp.sum(axis=1), np.where(nz > 0, rev / np.maximum(nz, 1), 0.0)]
            pos = np.where(major_y, cy, cx)
            pp, f = spectrum(pos, fs)
            summ = _local_bands(pp, f, self.POS_BANDS)
            feats += [summ["fpeak"], summ["fcent"]] + summ["bands"]
            pa, f = spectrum(act.astype(np.float64), fs)
            summ = _local_bands(pa, f, ())
            feats += [summ["fpeak"], summ["fcent"]]
        feats.append(np.log1p(peak))
        return np.column_stack(feats)


def _local_bands(p: np.ndarray, f: np.ndarray, bands) -> dict:
    tot = p.sum(axis=-1)
    none = tot <= 0
    safe = np.where(none, 1.0, tot)
    fpeak = np.where(none, 0.0, f[np.argmax(p, axis=-1)]) if p.shape[-1] else np.zeros(p.shape[:-1])
    fcent = np.where(none, 0.0, (p * f).sum(axis=-1) / safe)
    out = []
    for lo, hi in bands:
        out.append(np.where(none, 0.0, band_sum(p, f, lo, hi) / safe))
    return {"fpeak": fpeak, "fcent": fcent, "bands": out}


__all__ = ["TouchRhythm", "CellRhythm", "ContactMotion", "pressure", "spectrum", "spectral_summary",
           "SKEW_CONSTANT", "KURT_CONSTANT"]
