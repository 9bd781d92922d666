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

import functools
from numbers import Real
from typing import Any

import numpy as np

from sklearn.utils._param_validation import Interval

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, SensorNeededError, SharedPrep
from ..core.compiled import kernels
from .numerics import KURT_CONSTANT, SKEW_CONSTANT, gradient, moment_coords, same_row
from .touch_spectra import (AC_LAGS, BANDS, QUANTS, _STAT_NAMES, _band_name, _local_bands, band_slices, band_sums,
                            _hann_freqs, centred_spectrum, series_block, spectral_summary, spectrum, windowed_power)

MIN_FRAMES = 8
BASELINE_Q = 0.05
#: the full scale on which the sets' absolute contact floors were chosen (HAART's 0..1023, in raw units)
FLOOR_SCALE = 1023.0
CELL_RANKS: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 0.875, 0.9375, 1.0)
SERIES: tuple[str, ...] = ("P", "logP", "Pn", "M", "A", "cy", "cx", "sy", "sx", "speed", "dP")
THRESHOLDS: tuple[float, ...] = (0.1, 0.3, 0.5)


class _TouchBase(FeatureSet):
    """Frame rate handling and the common preprocessing."""

    paper = "touchbench (docs/research/touch-methods.md), after Gaus et al. 2015 section 5 and Zhou et al. 2017 section 4.1"
    cost = "cheap"
    fold_dependent = False

    _parameter_constraints = {"frame_rate": [Interval(Real, 0, None, closed="neither"), None],
                              "value_range": ["array-like", None]}

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

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        return self._from_pressure(stack.shape[2:], *_pressure(stack))

    def _batch_rows(self, stack: np.ndarray, shared: SharedPrep) -> np.ndarray:
        """:meth:`_transform_batch`, the stack's :func:`_pressure` computed once for the touch sets of
        a :class:`FeatureStack` (``_from_pressure`` never writes into it)."""
        if type(self)._transform_batch is not _TouchBase._transform_batch:
            return self._transform_batch(stack)
        return self._from_pressure(stack.shape[2:], *shared.get("pressure", lambda: _pressure(stack)))

    def _from_pressure(self, grid: tuple[int, int], s: np.ndarray, base: np.ndarray, c: np.ndarray) -> np.ndarray:
        """The features from :func:`_pressure`'s ``(s, base, c)`` of captures of ``grid`` (so a caller
        computing several sets on the same captures, ``touch-windows``, computes the pressure once)."""
        raise NotImplementedError


@functools.lru_cache(maxsize=32)
def _cell_ranks(cells: int) -> np.ndarray:
    """The ranks over ``cells`` cells at which ``touch-rhythm`` reads its sorted cell statistics."""
    return np.array([int(round(r * (cells - 1))) for r in CELL_RANKS], dtype=np.intp)


def pressure(stack: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(N, T, H, W)`` -> pressure above baseline ``(N, T', H*W)`` float64 and baseline ``(N, H*W)``.

    Captures shorter than ``MIN_FRAMES`` are padded by repeating the last
    frame first (T' = max(T, MIN_FRAMES)).
    """
    s, base, _ = _pressure(stack)
    return s, base


def _pressure(stack: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`pressure`, plus the padded values themselves ``(N, T', H*W)`` float64."""
    n, t, h, w = stack.shape
    x = np.asarray(stack).reshape(n, t, h * w)
    if t < MIN_FRAMES:
        x = np.concatenate([x, np.repeat(x[:, -1:], MIN_FRAMES - t, axis=1)], axis=1)
        t = MIN_FRAMES
    k = int(np.floor(BASELINE_Q * (t - 1)))
    kern = kernels("features.touch_kernels")
    if kern is not None and x.dtype.kind in "iuf":  # one pass: the baseline by selection, cell by cell
        c, s, base = np.empty((n, t, h * w)), np.empty((n, t, h * w)), np.empty((n, h * w))
        kern.pressure(np.ascontiguousarray(x), k, x.dtype.kind in "iu", c, s, base)
        return s, base, c
    c = np.ascontiguousarray(x, dtype=np.float64)  # C order: sums never depend on the layout
    # the order statistic of the readings themselves (fewer bytes to move than in float64; the same
    # value, as float64 represents every reading exactly and keeps their order); a partition along
    # the frames is faster contiguous. A copy always: with one cell the swapped axes are already
    # contiguous, and partitioning a view would reorder the readings (and ``c``, itself a view of
    # float64 readings) in place
    cells = np.array(np.swapaxes(x if x.dtype.kind in "iuf" else c, 1, 2), order="C")
    cells.partition(k, axis=2)
    base = cells[:, :, k].astype(np.float64)
    s = c - base[:, None, :]
    np.maximum(s, 0.0, out=s)
    return s, base, c


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

    def n_features(self, grid: tuple[int, int]) -> int:
        return len(SERIES) * len(_STAT_NAMES) + 7 + 3 * (len(CELL_RANKS) + 1) + 2

    def _from_pressure(self, grid: tuple[int, int], s: np.ndarray, base: np.ndarray, c: np.ndarray) -> np.ndarray:
        (h, w), kern = grid, kernels("features.touch_kernels")
        if kern is None:
            series, extra = self._frames(grid, s, base, c)
        else:
            series, extra = kern.rhythm_frames(s, c, base, h, w, self._floor(self.AREA_FLOOR), self.AREA_REL,
                                               _cell_ranks(h * w))
        block = series_block(series, self._fs()).reshape(len(s), -1)  # series-major, matching feature_names
        return np.hstack([block, extra])

    def _frames(self, grid: tuple[int, int], s: np.ndarray, base: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The eleven frame series ``(N, 11, T)`` and the capture scalars ``(N, 33)``: the numpy path
        of :func:`touchbench.features.touch_kernels.rhythm_frames`."""
        (n, t, _), (h, w) = s.shape, grid
        P = c.sum(axis=2)
        ps = s.sum(axis=2)
        M = c.max(axis=2)
        peak = s.max(axis=(1, 2))
        thr = np.maximum(self.AREA_REL * peak, self._floor(self.AREA_FLOOR))
        A = np.count_nonzero(s > thr[:, None, None], axis=2).astype(np.float64)
        empty = ps <= 0
        # pressure-weighted row, column and their squares: one pass over the cells
        mom = np.einsum("ntc,kc->nkt", s, moment_coords(h, w)) / np.where(empty, 1.0, ps)[:, None, :]
        cyx = np.where(empty[:, None, :], np.array([(h - 1) / 2.0, (w - 1) / 2.0])[:, None], mom[:, :2])
        syx = np.sqrt(np.maximum(np.where(empty[:, None, :], 0.0, mom[:, 2:] - cyx * cyx), 0.0))
        v = gradient(cyx)
        speed = np.hypot(v[:, 1], v[:, 0]) * (ps > thr[:, None])
        mean_ps = ps.mean(axis=1, keepdims=True)
        pn = np.where(mean_ps > 0, ps / np.where(mean_ps > 0, mean_ps, 1.0), 0.0)
        dP = np.zeros_like(P)
        np.abs(P[:, 1:] - P[:, :-1], out=dP[:, 1:])
        series = np.stack([P, np.log1p(ps), pn, M, A, cyx[:, 0], cyx[:, 1], syx[:, 0], syx[:, 1], speed, dP], axis=1)
        pmax = ps.max(axis=1, keepdims=True)
        step = np.diff(cyx, axis=2)
        extra = [base.mean(axis=1), base.max(axis=1), peak, np.log1p(peak),
                 np.where(pmax[:, 0] > 0, (ps > 0.2 * pmax).mean(axis=1), 0.0),
                 np.hypot(step[:, 1], step[:, 0]).sum(axis=1),
                 np.hypot(cyx[:, 1, -1] - cyx[:, 1, 0], cyx[:, 0, -1] - cyx[:, 0, 0])]
        ranks = [int(round(r * (h * w - 1))) for r in CELL_RANKS]
        cell_mean = s.sum(axis=1) / t
        dev = s - cell_mean[:, None, :]
        ds_ = np.subtract(s[:, 1:], s[:, :-1])
        np.abs(ds_, out=ds_)
        cell_sd = np.sqrt(np.einsum("ntc,ntc->nc", dev, dev) / t)
        cells = np.sort(np.stack([cell_mean, cell_sd, ds_.sum(axis=1) / (t - 1)], axis=1), axis=2)
        at = cells[:, :, ranks]
        for k in range(3):
            extra += [at[:, k, i] for i in range(len(ranks))] + [cells[:, k].sum(axis=1)]
        # spatial gradient on the flat cells (contiguous): neighbours along a row are 1 apart (the
        # pairs across a row's end weighted 0), along a column w apart
        grad = np.zeros(n)
        for lag, weight in ((1, same_row(h, w)), (w, None)):
            if lag < h * w:
                step_ = np.subtract(s[..., lag:], s[..., :-lag])
                np.abs(step_, out=step_)
                grad += np.einsum("ntc,c->n", step_, weight) if weight is not None else step_.sum(axis=(1, 2))
        mp = ps.mean(axis=1)
        has = mp > 0
        extra.append(np.where(has, grad / t / np.where(has, mp, 1.0), 0.0))
        tot = ps.sum(axis=1)
        extra.append(np.where(tot > 0, ds_.sum(axis=(1, 2)) / np.where(tot > 0, tot, 1.0), 0.0))
        return series, np.column_stack(extra)


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

    def _from_pressure(self, grid: tuple[int, int], s: np.ndarray, base: np.ndarray, c: np.ndarray) -> np.ndarray:
        (n, t, _), (h, w) = s.shape, grid
        fs = self._fs()
        cells = np.swapaxes(s, 1, 2)  # (N, C, T)
        kern = kernels("features.cell_kernels")
        if kern is not None:  # the cells' spectra numpy's (their peaks), the rest in two loops
            hann, f = _hann_freqs(t, float(fs))
            mean, dw = np.empty((n, h * w)), np.empty((n, h * w, t))
            kern.cell_series(s, hann, mean, dw)
            out = np.empty((n, len(BANDS) + 11))
            kern.cell_pool(s, mean, np.abs(np.fft.rfft(dw, axis=-1)), f, *band_slices(f, BANDS), hann, h, w,
                           self._floor(self.BLOB_FLOOR), out)
            return out
        mean = cells.mean(axis=2, keepdims=True)
        d = cells - mean
        p, f = centred_spectrum(d, cells.max(axis=2) == cells.min(axis=2), fs)  # (N, C, F)
        pw = p.sum(axis=2)  # (N, C)
        tot = pw.sum(axis=1)
        none = tot <= 0
        safe = np.where(none, 1.0, tot)
        wc = np.where(none[:, None], 0.0, pw / safe[:, None])
        # a cell's band fraction weighted by its share of the power is its band power over the total:
        # the bands and centroid of the cells' summed spectrum
        pooled = p.sum(axis=1)
        feats = list(np.where(none, 0.0, band_sums(pooled, f, BANDS).T / safe))
        feats.append(np.where(none, 0.0, np.einsum("nf,f->n", pooled, f) / safe))
        fp = f[np.argmax(p, axis=2)] if p.shape[2] else np.zeros(pw.shape)
        feats.append((fp * wc).sum(axis=1))
        feats.append(np.where(none, 0.0, fp[np.arange(n), np.argmax(pw, axis=1)]))
        psum, _ = spectrum(d.sum(axis=1), fs)
        feats.append(np.where(none, 0.0, psum.sum(axis=1) / safe))
        feats.append(-(wc * np.log(np.where(wc > 0, wc, 1.0))).sum(axis=1))
        above = d > 0
        mcr = (above[:, :, 1:] != above[:, :, :-1]).mean(axis=2)
        feats.append((mcr * wc).sum(axis=1))
        g = d.reshape(n, h, w, t)
        sd = np.sqrt(np.einsum("nhwt,nhwt->nhw", g, g))
        for a, b in (((slice(None), slice(None), slice(1, None)), (slice(None), slice(None), slice(None, -1))),
                     ((slice(None), slice(1, None), slice(None)), (slice(None), slice(None, -1), slice(None)))):
            num = np.einsum("nhwt,nhwt->nhw", g[a], g[b])
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

    def _from_pressure(self, grid: tuple[int, int], s: np.ndarray, base: np.ndarray, c: np.ndarray) -> np.ndarray:
        (n, t, _), (h, w) = s.shape, grid
        kern = kernels("features.touch_kernels")
        if kern is not None:
            return self._compiled(kern, grid, s)
        peak = np.sort(s.max(axis=2), axis=1)[:, int(round(0.95 * (t - 1)))]
        # every threshold at once: axis 1 of the arrays below is the threshold
        thr = np.maximum(np.multiply.outer(peak, THRESHOLDS), self._floor(self.CONTACT_FLOOR))
        wt = np.subtract(s[:, None], thr[:, :, None, None])  # (N, R, T, C)
        np.maximum(wt, 0.0, out=wt)
        ws = wt.sum(axis=3)
        act = ws > 0
        cyx = np.einsum("nrtc,kc->nrkt", wt, moment_coords(h, w)[:2]) / np.where(act, ws, 1.0)[:, :, None]
        nact = act.sum(axis=2)
        centre = np.array([(h - 1) / 2.0, (w - 1) / 2.0])
        mean_pos = np.where((nact > 0)[..., None], (cyx * act[:, :, None]).sum(axis=3) / np.maximum(nact, 1)[..., None], centre)
        cyx = np.where(act[:, :, None], cyx, mean_pos[..., None])  # (N, R, 2, T)
        area = np.count_nonzero(wt, axis=3).astype(np.float64)  # wt >= 0
        both = act[..., 1:] & act[..., :-1]
        v = np.diff(cyx, axis=3)
        sp = np.hypot(v[:, :, 1], v[:, :, 0]) * both
        srt = np.sort(cyx, axis=3)
        rng = srt[..., int(round(0.95 * (t - 1)))] - srt[..., int(round(0.05 * (t - 1)))]  # (N, R, 2): row, column
        major_y = rng[..., 0] >= rng[..., 1]
        vmaj = np.where(major_y[..., None], v[:, :, 0], v[:, :, 1]) * both
        sg = np.sign(vmaj)
        nz = (sg != 0).sum(axis=2)
        rev = ((sg[..., 1:] * sg[..., :-1]) < 0).sum(axis=2)
        nonzero_act = np.maximum(nact, 1)
        spsum = sp.sum(axis=2)
        pp, f = spectrum(np.where(major_y[..., None], cyx[:, :, 0], cyx[:, :, 1]), self._fs())
        pos = _local_bands(pp, f, self.POS_BANDS)
        pa, f = spectrum(act.astype(np.float64), self._fs())
        onoff = _local_bands(pa, f, ())
        cols = [act.mean(axis=2), (act[..., 1:] & ~act[..., :-1]).sum(axis=2).astype(np.float64),
                area.sum(axis=2) / nonzero_act, area.max(axis=2), spsum / np.maximum(both.sum(axis=2), 1),
                np.sort(sp, axis=2)[..., int(round(0.9 * (t - 2)))], rng[..., 0], rng[..., 1], spsum,
                np.where(nz > 0, rev / np.maximum(nz, 1), 0.0), pos["fpeak"], pos["fcent"]]
        cols += pos["bands"] + [onoff["fpeak"], onoff["fcent"]]
        per_threshold = np.stack(cols, axis=2)  # (N, R, 18), threshold-major like feature_names
        return np.hstack([per_threshold.reshape(n, -1), np.log1p(peak)[:, None]])

    def _compiled(self, kern: Any, grid: tuple[int, int], s: np.ndarray) -> np.ndarray:
        """:meth:`_from_pressure` by the compiled loops: the peak, weights and areas elementwise as
        numpy computes them, the weights' sums in numpy's order (the reversals count signs of rounding), the
        position and activity spectra numpy's (their peaks), the rest in the loops of motion_kernels."""
        (n, t, nc), (h, w), nr = s.shape, grid, len(THRESHOLDS)
        wt, area, peak, ws = np.empty((n * nr * t, nc)), np.empty((n, nr, t)), np.empty(n), np.empty((n, nr, t))
        m = kern.contact_weights(s, int(round(0.95 * (t - 1))), np.asarray(THRESHOLDS),
                                 self._floor(self.CONTACT_FLOOR), wt, area, peak, ws)
        tracks, pos_act = np.zeros((n, nr, 10)), np.empty((2,) + ws.shape)
        # numpy's weighted rows and columns of the frames with contact alone (each the same dot
        # product over the cells as in the numpy path's einsum, so the same numbers)
        kern.contact_tracks(ws, np.einsum("mc,kc->mk", wt[:m], moment_coords(h, w)[:2]), area, h, w, tracks, *pos_act)
        p, f = windowed_power(kern, pos_act, self._fs())
        out = np.empty((n, nr * 18 + 1))
        kern.contact_spectra(p[..., 1:], f, *band_slices(f, self.POS_BANDS), tracks, peak, out)
        return out


__all__ = ["TouchRhythm", "CellRhythm", "ContactMotion", "pressure", "spectrum", "spectral_summary",
           "SKEW_CONSTANT", "KURT_CONSTANT", "AC_LAGS", "BANDS", "QUANTS"]
