"""Spectra and series statistics of touchbench's own feature sets (:mod:`touchbench.features.touch`).

The spectrum of a series is its power (DC removed) with a Hann window on the mean-removed series;
band edges are in Hz, upper edge inclusive (the module docstring of :mod:`touchbench.features.touch`
has the interpretations). :func:`series_block` gives ``touch-rhythm``'s statistics of many series at
once: by the compiled loops of :mod:`touchbench.features.touch_kernels` and
:mod:`touchbench.features.series_kernels` when numba is installed, else
by the vectorised numpy code here (the two agree within 1e-9).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..core.compiled import kernels
from .numerics import moments

#: spectral bands in Hz, upper edge inclusive; the last one is open-ended
BANDS: tuple[tuple[float, float], ...] = ((0, 1), (1, 2), (2, 3), (3, 4.5), (4.5, 6), (6, 8), (8, 11), (11, 15), (15, np.inf))
AC_LAGS: tuple[int, ...] = (2, 4, 6, 9, 13, 18, 27)
QUANTS: tuple[int, ...] = (5, 25, 50, 75, 95)
_EPS = 1e-12


def _band_name(lo: float, hi: float) -> str:
    return f"{lo:g}-{hi:g}Hz" if np.isfinite(hi) else f"{lo:g}Hz+"


@functools.lru_cache(maxsize=128)
def _band_slices(n_freq: int, f0: float, bands: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) indices of each band in the frequencies ``f0 * (1..n_freq)`` (those of
    :func:`spectrum`); an empty band is (0, 0)."""
    f = f0 * np.arange(1, n_freq + 1, dtype=np.float64)
    starts, ends = np.zeros(len(bands), dtype=np.intp), np.zeros(len(bands), dtype=np.intp)
    for i, (lo, hi) in enumerate(bands):
        m = np.flatnonzero((f > lo) & (f <= hi))
        if m.size:
            starts[i], ends[i] = m[0], m[-1] + 1
    return starts, ends


def band_slices(f: np.ndarray, bands: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) indices of each band in the frequencies ``f`` (those of :func:`spectrum`)."""
    if not f.size:
        return np.zeros(len(bands), dtype=np.intp), np.zeros(len(bands), dtype=np.intp)
    return _band_slices(f.size, float(f[0]), tuple(bands))


def band_sums(p: np.ndarray, f: np.ndarray, bands: tuple[tuple[float, float], ...]) -> np.ndarray:
    """Sums of ``p`` (..., F) over the frequencies ``f`` (those of :func:`spectrum`) in each band
    (lo, hi] -> (..., len(bands)); 0 for a band without frequencies.

    Read off one cumulative sum in frequency order, so a capture's value never depends on how many
    captures share its batch (numpy's plain ``sum`` may change its summation order with the array's
    shape). The cumulative sum never decreases (``p >= 0``), so no band sum is negative.
    """
    if not f.size:
        return np.zeros(p.shape[:-1] + (len(bands),))
    starts, ends = _band_slices(f.size, float(f[0]), tuple(bands))
    c = np.zeros(p.shape[:-1] + (p.shape[-1] + 1,))
    np.cumsum(p, axis=-1, out=c[..., 1:])
    return c[..., ends] - c[..., starts]


@functools.lru_cache(maxsize=128)
def _hann_freqs(t: int, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """The Hann window of ``t`` frames and the positive rfft frequencies (read-only, cached)."""
    hann = np.hanning(t) if t > 1 else np.ones(1)
    f = np.fft.rfftfreq(t, 1.0 / fs)[1:]
    hann.flags.writeable = False
    f.flags.writeable = False
    return hann, f


def spectrum(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Power spectrum (DC removed) of the mean-removed, Hann-windowed series along axis -1; frequencies."""
    return centred_spectrum(x - x.mean(axis=-1, keepdims=True), x.max(axis=-1) == x.min(axis=-1), fs)


def centred_spectrum(d: np.ndarray, const: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`spectrum` of series whose mean is removed already (``d``), ``const`` marking the
    constant ones (they have no spectrum, exactly)."""
    hann, f = _hann_freqs(d.shape[-1], float(fs))
    dw = d * hann
    dw[const] = 0.0
    p = np.abs(np.fft.rfft(dw, axis=-1)) ** 2
    return p[..., 1:], f


#: the keys of :func:`spectral_summary`'s band fractions, named once
_BAND_KEYS: tuple[str, ...] = tuple(f"band{_band_name(lo, hi)}" for lo, hi in BANDS)


def spectral_summary(p: np.ndarray, f: np.ndarray) -> dict[str, np.ndarray]:
    """Band fractions, peak / centroid frequency, normalised entropy and log power of ``p`` (..., F)."""
    tot = p.sum(axis=-1)
    none = tot <= 0
    safe = np.where(none, 1.0, tot)
    fr = band_sums(p, f, BANDS) / safe[..., None]
    fr[none] = 0.0
    out: dict[str, np.ndarray] = {key: fr[..., i] for i, key in enumerate(_BAND_KEYS)}
    out["fpeak"] = np.where(none, 0.0, f[np.argmax(p, axis=-1)]) if p.shape[-1] else np.zeros(p.shape[:-1])
    out["fcent"] = np.where(none, 0.0, np.einsum("...i,i->...", p, f) / safe)
    q = p / safe[..., None]
    ent = -np.einsum("...i,...i->...", q, np.log(np.where(q > 0, q, 1.0)))
    out["fent"] = np.where(none, 0.0, ent / np.log(max(p.shape[-1], 2)))
    out["logpow"] = np.log1p(np.where(none, 0.0, tot))
    return out


def _series_stats(s: np.ndarray, fs: float) -> dict[str, np.ndarray]:
    """Statistics of series ``s`` (N, K, T) -> dict of (N, K) arrays (see the module docstring)."""
    t = s.shape[-1]
    srt = np.sort(s, axis=-1)
    order = srt[..., [int(round(q / 100 * (t - 1))) for q in QUANTS] + [t - 1]]
    mo = moments(srt, presorted=True, overwrite=True)
    mu = mo["mean"]
    d = s - mu[..., None]
    ac0 = np.einsum("...i,...i->...", d, d)
    sd = np.sqrt(ac0 / t)
    out: dict[str, np.ndarray] = {"mean": mu, "std": sd}
    for i, q in enumerate(QUANTS):
        out[f"p{q}"] = order[..., i]
    out["max"] = order[..., -1]
    out["skew"] = mo["skew"]
    out["kurt"] = mo["kurt"]
    dd = s[..., 1:] - s[..., :-1]
    mad1 = np.abs(dd).mean(axis=-1)
    out["mad1"] = mad1
    out["dstd"] = dd.std(axis=-1)
    flat = sd <= _EPS * (1.0 + np.abs(mu))
    out["cv"] = np.where(flat, 0.0, sd / np.maximum(np.abs(mu), sd * 1e-6 + _EPS))
    out["madn"] = np.where(flat, 0.0, mad1 / np.where(flat, 1.0, sd))
    above = d > 0
    out["mcr"] = np.where(flat, 0.0, (above[..., 1:] != above[..., :-1]).mean(axis=-1))
    out.update(spectral_summary(*centred_spectrum(s - s.mean(axis=-1, keepdims=True), mo["min"] == mo["max"], fs)))
    safe = np.where(flat, 1.0, ac0)
    ac = np.zeros(ac0.shape + (len(AC_LAGS),))
    for i, lag in enumerate(AC_LAGS):
        if lag < t:
            ac[..., i] = np.einsum("...i,...i->...", d[..., lag:], d[..., :-lag])
    ac /= safe[..., None]
    ac[flat] = 0.0
    for i, lag in enumerate(AC_LAGS):
        out[f"ac{lag}"] = ac[..., i]
    return out


_STAT_NAMES: list[str] = (
    ["mean", "std"] + [f"p{q}" for q in QUANTS]
    + ["max", "skew", "kurt", "mad1", "dstd", "cv", "madn", "mcr"]
    + [f"band{_band_name(lo, hi)}" for lo, hi in BANDS] + ["fpeak", "fcent", "fent", "logpow"]
    + [f"ac{lag}" for lag in AC_LAGS]
)



def _local_bands(p: np.ndarray, f: np.ndarray, bands) -> dict:
    tot = p.sum(axis=-1)
    none = tot <= 0
    safe = np.where(none, 1.0, tot)
    fpeak = np.where(none, 0.0, f[np.argmax(p, axis=-1)]) if p.shape[-1] else np.zeros(p.shape[:-1])
    fcent = np.where(none, 0.0, np.einsum("...i,i->...", p, f) / safe)
    fr = np.where(none[..., None], 0.0, band_sums(p, f, tuple(bands)) / safe[..., None])
    return {"fpeak": fpeak, "fcent": fcent, "bands": [fr[..., i] for i in range(len(bands))]}


def series_block(series: np.ndarray, fs: float) -> np.ndarray:
    """:func:`_series_stats` of ``series`` (N, K, T) as ``(N, K, len(_STAT_NAMES))``, columns in the
    order of ``_STAT_NAMES``."""
    kern = kernels("features.touch_kernels")
    if kern is None:
        st = _series_stats(series, fs)
        return np.stack([st[k] for k in _STAT_NAMES], axis=2)
    t = series.shape[-1]
    series = np.ascontiguousarray(series)
    p, f = windowed_power(kern, series, fs)
    srt = np.sort(series, axis=-1)
    return kernels("features.series_kernels").series_stats(
        series, srt, srt.sum(axis=-1) / t, p, f, *band_slices(f, BANDS), *_ranks_lags(t))


def windowed_power(kern: Any, x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`spectrum` of the series ``x`` (..., T) by the compiled loops ``kern``
    (:mod:`touchbench.features.touch_kernels`), the DC bin kept first: the windowed series built in
    one loop elementwise as :func:`centred_spectrum` builds them (numpy's mean, summed in numpy's
    order), so numpy's FFT of them gives the same numbers; and the frequencies (DC left out)."""
    t = x.shape[-1]
    hann, f = _hann_freqs(t, float(fs))
    rows = np.ascontiguousarray(x, dtype=np.float64).reshape(1, -1, t)
    dw = np.empty(rows.shape)
    kern.windowed(rows, hann, dw)
    return (np.abs(np.fft.rfft(dw, axis=-1)) ** 2).reshape(x.shape[:-1] + (t // 2 + 1,)), f


@functools.lru_cache(maxsize=128)
def _ranks_lags(t: int) -> tuple[np.ndarray, np.ndarray]:
    """The ranks of the order statistics of a ``t``-frame series and the autocorrelation lags."""
    return (np.array([int(round(q / 100 * (t - 1))) for q in QUANTS], dtype=np.intp),
            np.array(AC_LAGS, dtype=np.intp))
