"""Reference implementations for tests/test_features_gaus_values.py: the five Gaus et al. (2015)
feature sets (sd, msd, bmh, lbptop, smmhh) as they were computed before they were made faster,
kept here unchanged (with the shared numerics they used) so the fast code is checked against them.
A sibling of tests/features_reference.py, which holds the other sets' references.

Each reference class subclasses the fast one and replaces only ``_transform_batch``, so both see the
same parameters, input checks and sensor. Not collected by pytest (no ``test_`` prefix).
"""

from __future__ import annotations

import numpy as np

from touchbench.features.gaus_bmh import _TABLE as BMH_TABLE
from touchbench.features.gaus_bmh import BinaryMotionHistory
from touchbench.features.gaus_common import resolve_units
from touchbench.features.gaus_lbptop import LBPTOP, PLANES, circle_offsets
from touchbench.features.gaus_msd import MotionStatisticalDistribution
from touchbench.features.gaus_sd import StatisticalDistribution
from touchbench.features.gaus_smmhh import SpatialMultiScaleMHH, pyramid_shapes

SKEW_CONSTANT = 0.0
KURT_CONSTANT = 3.0


# ------------------------------------------------------------------ shared numerics (as they were)
def sort_last(x: np.ndarray) -> np.ndarray:
    small_int = x.dtype.kind in "biu" and x.dtype.itemsize <= 2
    return np.sort(x, axis=-1, kind="stable" if small_int else None)


def moments(x: np.ndarray, *, presorted: bool = False, overwrite: bool = False) -> dict[str, np.ndarray]:
    n = x.shape[-1]
    total = x.sum(axis=-1)
    mean = total / n
    if presorted:
        lo, hi = x[..., 0].copy(), x[..., -1].copy()
    else:
        lo, hi = x.min(axis=-1), x.max(axis=-1)
    rng = hi - lo
    const = rng == 0
    scale = np.where(const, 1.0, rng)
    z = np.subtract(x, lo[..., None], out=x if overwrite else None)
    z /= scale[..., None]
    z -= (z.sum(axis=-1) / n)[..., None]
    z2 = z * z
    m2 = z2.sum(axis=-1) / n
    m3 = np.einsum("...i,...i->...", z2, z) / n
    m4 = np.einsum("...i,...i->...", z2, z2) / n
    var = np.where(const, 0.0, m2 * scale * scale * (n / (n - 1) if n > 1 else 0.0))
    s2 = np.where(const, 1.0, m2)
    skew = np.where(const, SKEW_CONSTANT, m3 / s2**1.5)
    kurt = np.where(const, KURT_CONSTANT, m4 / (s2 * s2))
    return {"sum": total, "mean": mean, "var": var, "skew": skew, "kurt": kurt, "min": lo, "max": hi}


def hazen_quantiles(sorted_x: np.ndarray, probs: tuple[float, ...]) -> list[np.ndarray]:
    n = sorted_x.shape[-1]
    out = []
    for p in probs:
        pos = min(max(n * p - 0.5, 0.0), n - 1.0)
        i = int(np.floor(pos))
        j = min(i + 1, n - 1)
        f = pos - i
        a = sorted_x[..., i]
        out.append(a + f * (sorted_x[..., j] - a) if f else a.astype(np.float64, copy=True))
    return out


def total_variation(x: np.ndarray) -> np.ndarray:
    if x.shape[-1] < 2:
        return np.zeros(x.shape[:-1])
    if x.dtype.kind in "biu" and x.dtype.itemsize <= 2:
        return np.abs(np.diff(x.astype(np.int32), axis=-1)).sum(axis=-1, dtype=np.int64).astype(np.float64)
    return np.abs(np.diff(np.asarray(x, dtype=np.float64), axis=-1)).sum(axis=-1)


# ------------------------------------------------------------------------------------------ sd
def histogram_rows(values: np.ndarray, edges: np.ndarray, clip: bool) -> np.ndarray:
    nb = len(edges) - 1
    idx = np.searchsorted(edges, values, side="right") - 1
    idx = np.where(values == edges[-1], nb - 1, idx)
    inside = (idx >= 0) & (idx < nb)
    idx = np.clip(idx, 0, nb - 1)
    n = values.shape[0]
    flat = (np.arange(n)[:, None] * nb + idx)
    weights = np.ones(values.shape) if clip else inside.astype(np.float64)
    return np.bincount(flat.ravel(), weights=weights.ravel(), minlength=n * nb).reshape(n, nb)


def median_rows(flat: np.ndarray) -> np.ndarray:
    m = flat.shape[1]
    srt = sort_last(flat)
    return (srt[:, (m - 1) // 2].astype(np.float64) + srt[:, m // 2].astype(np.float64)) / 2.0


class RefStatisticalDistribution(StatisticalDistribution):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        off, fixed, edges = self._resolved()
        n, t = stack.shape[:2]
        x = stack.reshape(n, t, -1)
        if x.dtype.kind == "f":
            x = x.astype(np.float64)
        flat = x.reshape(n, -1)
        fmin = x.min(axis=2, keepdims=True)
        fmax = x.max(axis=2, keepdims=True)
        imin = fmin.min(axis=1, keepdims=True)
        imax = fmax.max(axis=1, keepdims=True)
        imed = median_rows(flat)[:, None, None]

        def count(cond: np.ndarray) -> np.ndarray:
            return np.count_nonzero(cond, axis=2).astype(np.float64)

        counts = {
            "notouch_frame": count(x == fmin),
            "notouch_instance": count(x == imin),
            "touched_median": count(x >= imed),
            "high_frame": count(x >= fmax - off) if off else count(x == fmax),
            "high_instance": count(x >= imax - off) if off else count(x == imax),
        }
        if fixed is not None:
            counts[f"touched_ge{fixed:g}"] = count(x >= fixed)
        parts = []
        for p, key in self._conditions():
            h = histogram_rows(counts[p], edges[key], self.clip)
            parts.append(h / t if self.normalize else h)
        return np.hstack(parts)


# ----------------------------------------------------------------------------------------- msd
class RefMotionStatisticalDistribution(MotionStatisticalDistribution):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t = stack.shape[:2]
        series = np.ascontiguousarray(stack.reshape(n, t, -1).transpose(0, 2, 1))
        srt = np.asarray(sort_last(series), dtype=np.float64)
        q1, med, q3 = hazen_quantiles(srt, (0.25, 0.5, 0.75))
        m = moments(srt, presorted=True, overwrite=True)
        area = m["sum"]
        tv = total_variation(series)
        cols = [m["min"], m["max"], m["mean"], q1, med, q3, area, tv, q3 - q1, m["var"], m["skew"], m["kurt"]]
        return np.concatenate(cols, axis=1)


# ----------------------------------------------------------------------------------------- bmh
class RefBinaryMotionHistory(BinaryMotionHistory):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        off = float(resolve_units("bmh", self.preset, BMH_TABLE, "offset", self.offset, self.sensor, "offset"))
        n, t = stack.shape[:2]
        x = stack.reshape(n, t, -1).astype(np.float64)
        if self.level == "instance":
            top = x.max(axis=(1, 2))[:, None, None]
        else:
            top = x.max(axis=2, keepdims=True)
        return (x >= top - off).any(axis=1).astype(np.float64)


# -------------------------------------------------------------------------------------- lbptop
class RefLBPTOP(LBPTOP):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        rx, ry, rt = (int(r) for r in self.radius)
        p = int(self.n_points)
        table, nb = self._table()
        n, t, h, w = stack.shape
        out = np.zeros((n, 3 * nb))
        ct, ch, cw = t - 2 * rt, h - 2 * ry, w - 2 * rx
        if ct < 1 or ch < 1 or cw < 1:
            return out
        v = stack if stack.dtype.kind in "biu" else stack.astype(np.float64)
        flat = v.reshape(n, -1)
        hw = h * w
        lo = rt * hw + ry * w + rx
        hi = (t - rt - 1) * hw + (h - ry - 1) * w + (w - rx - 1) + 1
        pos = np.arange(lo, hi)
        tt, yy, xx = pos // hw, (pos // w) % h, pos % w
        interior = (tt >= rt) & (tt < t - rt) & (yy >= ry) & (yy < h - ry) & (xx >= rx) & (xx < w - rx)
        centre = flat[:, lo:hi]
        planes = {
            "xy": [(0, a, b) for a, b in circle_offsets(p, ry, rx)],
            "xt": [(a, 0, b) for a, b in circle_offsets(p, rt, rx)],
            "yt": [(a, b, 0) for a, b in circle_offsets(p, rt, ry)],
        }
        onehot = np.zeros((2**p, nb))
        onehot[np.arange(2**p), table] = 1.0
        n_centres = ct * ch * cw
        code_dtype = np.uint8 if p <= 8 else np.uint16
        offsets = (np.arange(n) * 2**p)[:, None]
        for i, pl in enumerate(PLANES):
            code = np.zeros(centre.shape, dtype=code_dtype)
            for bit, (dt, dy, dx) in enumerate(planes[pl]):
                off = dt * hw + dy * w + dx
                ge = flat[:, lo + off:hi + off] >= centre
                code += ge.view(np.uint8) * code_dtype(1 << bit)
            codes = code[:, interior].astype(np.int64) + offsets
            hist = np.bincount(codes.ravel(), minlength=n * 2**p).reshape(n, 2**p)
            out[:, i * nb:(i + 1) * nb] = (hist @ onehot) / n_centres
        return out


# --------------------------------------------------------------------------------------- smmhh
def pool2(frames: np.ndarray) -> np.ndarray:
    h, w = frames.shape[-2:]
    ph, pw = h % 2, w % 2
    if ph or pw:
        pad = [(0, 0)] * (frames.ndim - 2) + [(0, ph), (0, pw)]
        frames = np.pad(frames, pad)
        cnt = np.pad(np.ones((h, w)), [(0, ph), (0, pw)])
        cnt = cnt[0::2, 0::2] + cnt[1::2, 0::2] + cnt[0::2, 1::2] + cnt[1::2, 1::2]
    else:
        cnt = 4.0
    s = frames[..., 0::2, 0::2] + frames[..., 1::2, 0::2] + frames[..., 0::2, 1::2] + frames[..., 1::2, 1::2]
    return s / cnt


def run_length_histogram(binary: np.ndarray, max_len: int) -> np.ndarray:
    lead, L = binary.shape[:-1], binary.shape[-1]
    r = int(np.prod(lead))
    padded = np.zeros(lead + (L + 2,), dtype=np.int8)
    padded[..., 1:-1] = binary
    d = np.diff(padded.reshape(r, L + 2), axis=1).ravel()
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1)
    lengths = ends - starts
    rows = starts // (L + 1)
    bins = np.minimum(lengths, max_len) - 1
    hist = np.bincount(rows * max_len + bins, minlength=r * max_len).astype(np.float64)
    return hist.reshape(lead + (max_len,))


class RefSpatialMultiScaleMHH(SpatialMultiScaleMHH):
    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        levels = self._levels(stack.shape[2:])
        thr = self._thresholds(levels)
        skips = [int(s) for s in self.skips]
        M = int(self.max_len)
        n, t = stack.shape[:2]
        shapes = pyramid_shapes(stack.shape[2:], levels)
        sizes = [h * w for h, w in shapes]
        ptot = sum(sizes)
        L = max(t - min(skips), 0)
        motion = np.zeros((n, len(skips), max(L, 1), ptot), dtype=bool)
        v = np.asarray(stack, dtype=np.float64)
        off = 0
        for k, size in enumerate(sizes):
            if k:
                v = pool2(v)
            flat = v.reshape(n, t, size)
            for si, s in enumerate(skips):
                if t > s:
                    np.greater(np.abs(flat[:, s:] - flat[:, :-s]), thr[k], out=motion[:, si, : t - s, off:off + size])
            off += size
        hist = run_length_histogram(motion.transpose(0, 1, 3, 2), M)
        parts = []
        off = 0
        for size in sizes:
            parts.append(hist[:, :, off:off + size, :].transpose(0, 1, 3, 2).reshape(n, -1))
            off += size
        return np.concatenate(parts, axis=1)
