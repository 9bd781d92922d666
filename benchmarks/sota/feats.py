"""Candidate cheap features, vectorised over a batch (N, T, H, W) float64."""
from __future__ import annotations
import numpy as np

FS = 54.0

def _stats(s, prefix):
    """s: (N, T) series -> dict of (N,) features."""
    out = {}
    mu = s.mean(1); sd = s.std(1)
    out[f"{prefix}_mean"] = mu
    out[f"{prefix}_std"] = sd
    q = np.percentile(s, [5, 25, 50, 75, 95], axis=1)
    for k, p in zip([5, 25, 50, 75, 95], q):
        out[f"{prefix}_p{k}"] = p
    out[f"{prefix}_max"] = s.max(1)
    z = (s - mu[:, None]) / np.maximum(sd[:, None], 1e-9)
    out[f"{prefix}_skew"] = (z ** 3).mean(1)
    out[f"{prefix}_kurt"] = (z ** 4).mean(1)
    d = np.diff(s, axis=1)
    out[f"{prefix}_mad1"] = np.abs(d).mean(1)
    out[f"{prefix}_dstd"] = d.std(1)
    out[f"{prefix}_cv"] = sd / (np.abs(mu) + 1e-9)
    out[f"{prefix}_madn"] = np.abs(d).mean(1) / (sd + 1e-9)
    # mean-crossing rate
    sgn = np.sign(s - mu[:, None])
    out[f"{prefix}_mcr"] = (np.diff(sgn, axis=1) != 0).mean(1)
    # spectrum of detrended series
    sdm = s - mu[:, None]
    F = np.abs(np.fft.rfft(sdm * np.hanning(s.shape[1])[None], axis=1)) ** 2
    f = np.fft.rfftfreq(s.shape[1], 1 / FS)
    tot = F[:, 1:].sum(1) + 1e-12
    bands = [(0, 1), (1, 2), (2, 3), (3, 4.5), (4.5, 6), (6, 8), (8, 11), (11, 15), (15, 27.1)]
    for lo, hi in bands:
        m = (f > lo) & (f <= hi)
        out[f"{prefix}_band{lo}-{hi}"] = F[:, m].sum(1) / tot
    out[f"{prefix}_fpeak"] = f[1:][np.argmax(F[:, 1:], axis=1)]
    out[f"{prefix}_fcent"] = (F[:, 1:] * f[None, 1:]).sum(1) / tot
    P = F[:, 1:] / tot[:, None]
    out[f"{prefix}_fent"] = -(P * np.log(P + 1e-12)).sum(1)
    out[f"{prefix}_logpow"] = np.log1p(tot)
    # autocorrelation at a few lags (normalised)
    ac0 = (sdm ** 2).sum(1) + 1e-12
    for lag in [2, 4, 6, 9, 13, 18, 27]:
        out[f"{prefix}_ac{lag}"] = (sdm[:, lag:] * sdm[:, :-lag]).sum(1) / ac0
    return out


def touch_dynamics(X, thr_frac=0.2):
    """X (N, T, H, W) float -> (N, F) features, names."""
    N, T, H, W = X.shape
    C = X.reshape(N, T, H * W)
    base = np.percentile(C, 5, axis=1)  # per-cell baseline (N, 64)
    S = np.clip(C - base[:, None, :], 0, None)
    feats = {}
    P = C.sum(2); Ps = S.sum(2)
    M = C.max(2)
    peak = S.max(axis=(1, 2))
    thr = np.maximum(thr_frac * peak, 3.0)
    A = (S > thr[:, None, None]).sum(2).astype(float)
    yy, xx = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    yy = yy.ravel().astype(float); xx = xx.ravel().astype(float)
    w = S + 1e-9
    ws = w.sum(2)
    cy = (w * yy).sum(2) / ws; cx = (w * xx).sum(2) / ws
    sy = np.sqrt(np.maximum((w * yy ** 2).sum(2) / ws - cy ** 2, 0))
    sx = np.sqrt(np.maximum((w * xx ** 2).sum(2) / ws - cx ** 2, 0))
    vy = np.gradient(cy, axis=1); vx = np.gradient(cx, axis=1)
    speed = np.hypot(vx, vy) * (Ps > thr[:, None])
    series = {"P": P, "logP": np.log1p(Ps), "M": M, "A": A, "cy": cy, "cx": cx, "sy": sy, "sx": sx,
              "speed": speed, "dP": np.abs(np.diff(P, axis=1, prepend=P[:, :1]))}
    # normalised total pressure (scale invariant)
    series["Pn"] = Ps / (Ps.mean(1, keepdims=True) + 1e-9)
    for k, s in series.items():
        feats.update(_stats(s, k))
    # per-capture scalars
    feats["base_mean"] = base.mean(1); feats["base_max"] = base.max(1)
    feats["peak"] = peak; feats["logpeak"] = np.log1p(peak)
    feats["active_frac"] = (Ps > 0.2 * Ps.max(1, keepdims=True)).mean(1)
    # path length of centroid, net displacement
    feats["path"] = np.hypot(np.diff(cx, axis=1), np.diff(cy, axis=1)).sum(1)
    feats["disp"] = np.hypot(cx[:, -1] - cx[:, 0], cy[:, -1] - cy[:, 0])
    # per-cell temporal statistics, spatially pooled by rank (position invariant)
    cm = np.sort(S.mean(1), axis=1); cs = np.sort(S.std(1), axis=1)
    cd = np.sort(np.abs(np.diff(S, axis=1)).mean(1), axis=1)
    for name, v in [("cellmean", cm), ("cellstd", cs), ("celldiff", cd)]:
        for q in [0, 16, 32, 48, 56, 60, 63]:
            feats[f"{name}_r{q}"] = v[:, q]
        feats[f"{name}_sum"] = v.sum(1)
    # spatial gradient energy (mean over time) relative to pressure
    G = S.reshape(N, T, H, W)
    gx = np.abs(np.diff(G, axis=3)).sum((2, 3)); gy = np.abs(np.diff(G, axis=2)).sum((2, 3))
    feats["grad_rel"] = ((gx + gy).mean(1)) / (Ps.mean(1) + 1e-9)
    # temporal cell-level diff relative to total
    feats["tdiff_rel"] = np.abs(np.diff(S, axis=1)).sum((1, 2)) / (Ps.sum(1) + 1e-9)
    names = list(feats)
    return np.column_stack([feats[k] for k in names]), names


def cell_spectral(X):
    """Per-cell spectra pooled over cells weighted by each cell's activity."""
    N, T, H, W = X.shape
    C = X.reshape(N, T, H * W)
    base = np.percentile(C, 5, axis=1)
    S = np.clip(C - base[:, None, :], 0, None)
    D = S - S.mean(1, keepdims=True)
    F = np.abs(np.fft.rfft(D * np.hanning(T)[None, :, None], axis=1)) ** 2  # (N, f, 64)
    f = np.fft.rfftfreq(T, 1 / FS)
    pw = F[:, 1:].sum(1) + 1e-12  # (N, 64) power per cell
    wcell = pw / pw.sum(1, keepdims=True)  # cell weights
    feats = {}
    bands = [(0, 1), (1, 2), (2, 3), (3, 4.5), (4.5, 6), (6, 8), (8, 11), (11, 15), (15, 27.1)]
    Pn = F / pw[:, None, :]
    for lo, hi in bands:
        m = (f > lo) & (f <= hi)
        feats[f"cell_band{lo}-{hi}"] = (Pn[:, m].sum(1) * wcell).sum(1)
    fc = (F[:, 1:] * f[None, 1:, None]).sum(1) / pw
    feats["cell_fcent_w"] = (fc * wcell).sum(1)
    fp = f[1:][np.argmax(F[:, 1:], axis=1)]
    feats["cell_fpeak_w"] = (fp * wcell).sum(1)
    feats["cell_fpeak_top"] = fp[np.arange(N), np.argmax(pw, 1)]
    # sum of cell powers vs power of the sum: coherence across cells (moving contact -> low)
    Ptot = np.abs(np.fft.rfft(D.sum(2) * np.hanning(T)[None], axis=1)) ** 2
    feats["coherence"] = Ptot[:, 1:].sum(1) / pw.sum(1)
    feats["cell_pow_entropy"] = -(wcell * np.log(wcell + 1e-12)).sum(1)
    # mean-crossing rate per cell, weighted
    sg = np.sign(D)
    mcr = (np.diff(sg, axis=1) != 0).mean(1)
    feats["cell_mcr_w"] = (mcr * wcell).sum(1)
    # spatial correlation between neighbouring cells' time series
    G = D.reshape(N, T, H, W)
    sd = np.sqrt((G ** 2).sum(1)) + 1e-9
    ch = (G[:, :, :, 1:] * G[:, :, :, :-1]).sum(1) / (sd[:, :, 1:] * sd[:, :, :-1])
    cv = (G[:, :, 1:, :] * G[:, :, :-1, :]).sum(1) / (sd[:, 1:, :] * sd[:, :-1, :])
    wh = (sd[:, :, 1:] * sd[:, :, :-1]); wv = (sd[:, 1:, :] * sd[:, :-1, :])
    feats["ncorr_h"] = (ch * wh).sum((1, 2)) / wh.sum((1, 2))
    feats["ncorr_v"] = (cv * wv).sum((1, 2)) / wv.sum((1, 2))
    # contact blobs: cells above half the frame max, count 4-connected components approx by edges
    fm = S.max(2, keepdims=True)
    B = (S > np.maximum(0.5 * fm, 3.0)).reshape(N, T, H, W)
    nodes = B.sum((2, 3)); edges = (B[:, :, :, 1:] & B[:, :, :, :-1]).sum((2, 3)) + (B[:, :, 1:, :] & B[:, :, :-1, :]).sum((2, 3))
    act = nodes > 0
    comp = np.where(act, nodes - edges, 0)  # Euler characteristic approx of component count
    feats["blobs_mean"] = comp.sum(1) / np.maximum(act.sum(1), 1)
    feats["blobs_max"] = comp.max(1)
    feats["nodes_mean"] = nodes.sum(1) / np.maximum(act.sum(1), 1)
    names = list(feats)
    return np.column_stack([feats[k] for k in names]), names


def thresholded_series(X, rel=(0.1, 0.3, 0.5)):
    """Noise-robust contact descriptors: weights above a relative threshold of the capture peak."""
    N, T, H, W = X.shape
    C = X.reshape(N, T, H * W)
    base = np.percentile(C, 5, axis=1)
    S = np.clip(C - base[:, None, :], 0, None)
    peak = np.percentile(S.max(2), 95, axis=1)  # robust capture peak
    yy, xx = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    yy = yy.ravel().astype(float); xx = xx.ravel().astype(float)
    feats = {}
    for r in rel:
        thr = np.maximum(r * peak, 4.0)[:, None, None]
        Wt = np.clip(S - thr, 0, None)
        ws = Wt.sum(2); act = ws > 0
        cy = np.where(act, (Wt * yy).sum(2) / np.maximum(ws, 1e-9), np.nan)
        cx = np.where(act, (Wt * xx).sum(2) / np.maximum(ws, 1e-9), np.nan)
        # fill gaps by carrying the mean position (so velocities are zero when not touching)
        my = np.nanmean(np.where(act.any(1, keepdims=True), cy, 3.5), 1, keepdims=True)
        mx = np.nanmean(np.where(act.any(1, keepdims=True), cx, 3.5), 1, keepdims=True)
        cy = np.where(act, cy, my); cx = np.where(act, cx, mx)
        A = (Wt > 0).sum(2).astype(float)
        vy = np.diff(cy, axis=1); vx = np.diff(cx, axis=1)
        both = act[:, 1:] & act[:, :-1]
        sp = np.hypot(vx, vy) * both
        nb = np.maximum(both.sum(1), 1)
        tag = f"t{int(r * 100)}"
        feats[f"{tag}_actfrac"] = act.mean(1)
        feats[f"{tag}_onsets"] = (np.diff(act.astype(int), axis=1) == 1).sum(1)
        feats[f"{tag}_A_mean"] = A.sum(1) / np.maximum(act.sum(1), 1)
        feats[f"{tag}_A_max"] = A.max(1)
        feats[f"{tag}_sp_mean"] = sp.sum(1) / nb
        feats[f"{tag}_sp_p90"] = np.percentile(np.where(both, sp, 0), 90, axis=1)
        feats[f"{tag}_range_y"] = np.percentile(cy, 95, 1) - np.percentile(cy, 5, 1)
        feats[f"{tag}_range_x"] = np.percentile(cx, 95, 1) - np.percentile(cx, 5, 1)
        feats[f"{tag}_path"] = sp.sum(1)
        # dominant axis of motion and back-and-forth reversals
        vmaj = np.where(feats[f"{tag}_range_y"][:, None] >= feats[f"{tag}_range_x"][:, None], vy, vx) * both
        sg = np.sign(vmaj); nz = sg != 0
        feats[f"{tag}_reversal"] = ((sg[:, 1:] * sg[:, :-1]) < 0).sum(1) / np.maximum(nz.sum(1), 1)
        # spectrum of the major-axis position
        pos = np.where(feats[f"{tag}_range_y"][:, None] >= feats[f"{tag}_range_x"][:, None], cy, cx)
        pd_ = pos - pos.mean(1, keepdims=True)
        Fp = np.abs(np.fft.rfft(pd_ * np.hanning(T)[None], axis=1)) ** 2
        f = np.fft.rfftfreq(T, 1 / FS); tot = Fp[:, 1:].sum(1) + 1e-12
        feats[f"{tag}_pos_fpeak"] = f[1:][np.argmax(Fp[:, 1:], 1)]
        feats[f"{tag}_pos_fcent"] = (Fp[:, 1:] * f[None, 1:]).sum(1) / tot
        for lo, hi in [(0, 1.5), (1.5, 3), (3, 6), (6, 27.1)]:
            m = (f > lo) & (f <= hi); feats[f"{tag}_pos_band{lo}-{hi}"] = Fp[:, m].sum(1) / tot
        # activity (on/off) spectrum
        a = act.astype(float) - act.mean(1, keepdims=True)
        Fa = np.abs(np.fft.rfft(a, axis=1)) ** 2; ta = Fa[:, 1:].sum(1) + 1e-12
        feats[f"{tag}_act_fpeak"] = f[1:][np.argmax(Fa[:, 1:], 1)]
        feats[f"{tag}_act_fcent"] = (Fa[:, 1:] * f[None, 1:]).sum(1) / ta
    feats["peak_robust"] = np.log1p(peak)
    names = list(feats)
    return np.column_stack([feats[k] for k in names]), names
