"""Reference implementations for tests/test_features_speed_values.py: touchbench's own feature sets
as they were computed before they were made faster (one statistic at a time, one threshold at a
time, one band at a time), kept here unchanged so the fast code is checked against them.

Each reference class subclasses the fast one and replaces only ``_transform_batch``, so both see the
same parameters, input checks and sensor. Not collected by pytest (no ``test_`` prefix).
"""

from __future__ import annotations

import numpy as np

from touchbench.features.contact import MAD_TO_SD, NOISE_UNITS, QUIET_SHARE, ContactEvidence
from touchbench.features.numerics import moments
from touchbench.features.touch import (AC_LAGS, BANDS, BASELINE_Q, CELL_RANKS, MIN_FRAMES, QUANTS, THRESHOLDS, CellRhythm,
                                       ContactMotion, TouchRhythm, _band_name)
from touchbench.features.touch_windows import TouchWindows


_EPS = 1e-12


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



class RefTouchRhythm(TouchRhythm):
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



class RefCellRhythm(CellRhythm):
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



class RefContactMotion(ContactMotion):
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




def noise_floor(u: np.ndarray, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """Rest level and noise floor ``(N,)`` of heights ``u`` ``(N, T, C)``: every cell's median and MAD,
    then the quiet cells' median level and 1.4826 x their median MAD, at least ``floor``."""
    n, _, c = u.shape
    med = np.median(u, axis=1)
    mad = np.median(np.abs(u - med[:, None, :]), axis=1)
    q = max(1, int(np.floor(QUIET_SHARE * c)))
    quiet = np.argsort(med, axis=1, kind="stable")[:, :q]
    rest = np.median(np.take_along_axis(med, quiet, axis=1), axis=1)
    noise = MAD_TO_SD * np.median(np.take_along_axis(mad, quiet, axis=1), axis=1)
    return rest, np.maximum(noise, floor)


class RefContactEvidence(ContactEvidence):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        u, full = self._heights(stack)
        n, t, c = u.shape
        flat = np.sort(u.reshape(n, t * c), axis=1)
        cell_mean = u.mean(axis=1)
        level = [flat.mean(axis=1), flat[:, round(0.5 * (t * c - 1))], flat[:, round(0.95 * (t * c - 1))],
                 flat[:, -1], cell_mean.min(axis=1), cell_mean.max(axis=1)]
        rest, noise = noise_floor(u, self.min_noise * full)
        cols = [v / full for v in level]
        for k in NOISE_UNITS:
            above = u > (rest + k * noise)[:, None, None]
            cols += [above.reshape(n, -1).mean(axis=1), above.any(axis=2).mean(axis=1),
                     (cell_mean > (rest + k * noise)[:, None]).mean(axis=1)]
        tstd = u.std(axis=1)
        cols += [(flat[:, -1] - rest) / noise, (cell_mean.max(axis=1) - rest) / noise,
                 tstd.mean(axis=1) / noise, tstd.max(axis=1) / noise]
        return np.column_stack(cols)


REF_SETS = {"touch-rhythm": RefTouchRhythm, "cell-rhythm": RefCellRhythm, "contact-motion": RefContactMotion}


class RefTouchWindows(TouchWindows):
    """touch-windows as it was computed before it was made faster: each window cut out and given to
    each inner set (here their reference computations) on its own, one window at a time."""

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        starts, length = self.window_starts(stack.shape[1])
        inner = [REF_SETS[name](frame_rate=self._fs(), value_range=self._range()) for name in self.sets]
        per_window = []
        for s in starts:
            part = stack[:, s:s + length]
            per_window.append(np.hstack([fs._transform_batch(part) for fs in inner]))
        W = np.stack(per_window)  # (windows, N, D)
        return np.hstack([W.mean(axis=0), W.std(axis=0)])
