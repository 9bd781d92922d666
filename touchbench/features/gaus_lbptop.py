"""``lbptop``: local binary patterns on three orthogonal planes (Gaus et al.
2015, section 3.2.5, after Zhao and Pietikainen 2007)."""

from __future__ import annotations

from numbers import Integral

from functools import lru_cache

import numpy as np

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet
from ..core.compiled import kernels
from .gaus_common import GAUS_PAPER

PLANES = ("xy", "xt", "yt")


def circle_offsets(n_points: int, r_a: int, r_b: int) -> list[tuple[int, int]]:
    """Integer (a, b) offsets of ``n_points`` neighbours on an ellipse of radii
    (r_a, r_b), counter-clockwise from (0, +r_b): ``a = -round(r_a sin)``,
    ``b = round(r_b cos)`` (no bilinear interpolation: for 8 points and
    radius 1 this is the 3 x 3 neighbourhood)."""
    ang = 2 * np.pi * np.arange(n_points) / n_points
    a = -np.rint(r_a * np.sin(ang)).astype(int)
    b = np.rint(r_b * np.cos(ang)).astype(int)
    return list(zip(a.tolist(), b.tolist()))


@lru_cache(maxsize=None)
def uniform_mapping(n_points: int) -> tuple[np.ndarray, int]:
    """Ojala's "u2" mapping: code -> bin. Codes with at most two circular 0/1
    transitions get their own bin in increasing code order; every other
    code shares the last bin. ``n_points * (n_points - 1) + 3`` bins (59 for 8)."""
    codes = np.arange(2**n_points)
    bits = (codes[:, None] >> np.arange(n_points)) & 1
    transitions = (bits != np.roll(bits, 1, axis=1)).sum(axis=1)
    uniform = transitions <= 2
    n_bins = int(uniform.sum()) + 1
    table = np.full(2**n_points, n_bins - 1, dtype=np.int64)
    table[uniform] = np.arange(n_bins - 1)
    return table, n_bins


@FEATURES.register("lbptop", description="LBP-TOP histograms (XY, XT, YT planes) of the pressure video")
class LBPTOP(FeatureSet):
    """Local binary patterns on three orthogonal planes (LBP-TOP).

    Gaus et al. 2015, section 3.2.5 gives no parameters; we use Zhao and
    Pietikainen's (2007) LBP-TOP_{8,8,8,1,1,1} with uniform ("u2")
    patterns: for every voxel (t, y, x) at least one radius away from every
    border, an 8-bit code per plane compares the 8 neighbours on the
    circle of radius 1 in that plane (XY: the frame; XT: x and time; YT: y
    and time) with the centre, bit p = neighbour_p >= centre. Each plane's
    codes are histogrammed into 59 u2 bins and normalised to sum 1; the
    three histograms are concatenated: 3 x 59 = 177 values (for any grid
    of at least 3 x 3 and capture of at least 3 frames),
    ``lbptop_{plane}_b{k}`` (b58 is the non-uniform bin).

    Interpretations (the paper is silent on all of them):

    - Radii 1 in x, y and t (one frame at 54 Hz), 8 neighbours per plane,
      neighbours at rounded integer positions (Zhao's code without
      bilinear interpolation; on an 8 x 8 grid there is no room for
      larger radii).
    - The same interior voxels feed all three planes (Zhao 2007), so on an
      8 x 8 grid the 6 x 6 inner cells of frames 2..T-1 are centres.
    - ``>=`` (a neighbour equal to the centre sets its bit), the usual LBP
      convention: a constant capture has every code 255, all mass in that
      uniform bin.
    - Histograms are normalised (fractions of the centres) so that
      captures of different lengths compare; a capture with no interior
      voxel (fewer than 2 r_t + 1 frames, or a grid thinner than
      2 r + 1, e.g. a 1 x C channel sensor) has no codes: its histograms
      are all 0 rather than 0/0.
    """

    paper = f"{GAUS_PAPER}.5 (Zhao & Pietikainen 2007)"
    cost = "moderate"
    fold_dependent = False
    compiled_loops = "features.gaus_kernels"

    _parameter_constraints = {"radius": ["array-like"], "n_points": [Interval(Integral, 4, 16, closed="both")],
                              "mapping": [StrOptions({"u2", "none"})]}
    _parameter_docs = {"radius": "the radii (r_x, r_y, r_t), three positive integers.",
                       "n_points": "P, the neighbours per plane.",
                       "mapping": "``u2``: the uniform patterns' bins; ``none``: all 2**P codes.",
                       "sensor": "unused."}

    def __init__(self, radius: tuple[int, int, int] = (1, 1, 1), n_points: int = 8, mapping: str = "u2", sensor: SensorSpec | None = None):
        self.radius = radius
        self.n_points = n_points
        self.mapping = mapping
        self.sensor = sensor

    def _check_params(self) -> None:
        if len(tuple(self.radius)) != 3 or any(isinstance(r, bool) or int(r) != r or r < 1 for r in self.radius):
            raise FeatureInputError(f"lbptop: radius must be three positive integers (r_x, r_y, r_t), got {self.radius!r}")

    def _table(self) -> tuple[np.ndarray, int]:
        p = int(self.n_points)
        if self.mapping == "u2":
            return uniform_mapping(p)
        return np.arange(2**p), 2**p

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        _, nb = self._table()
        return [f"lbptop_{pl}_b{k:0{len(str(nb - 1))}d}" for pl in PLANES for k in range(nb)]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        rx, ry, rt = (int(r) for r in self.radius)
        p = int(self.n_points)
        table, nb = self._table()
        n, t, h, w = stack.shape
        out = np.zeros((n, 3 * nb))
        ct, ch, cw = t - 2 * rt, h - 2 * ry, w - 2 * rx
        if ct < 1 or ch < 1 or cw < 1:
            return out
        n_centres = ct * ch * cw
        v = stack if stack.dtype.kind in "biu" else stack.astype(np.float64)
        # Flat layout: voxel (t, y, x) is t*H*W + y*W + x, so a neighbour is a
        # fixed offset and every comparison runs over one contiguous range: the
        # whole frames rt..T-rt-1 but their first and last ``margin`` voxels
        # (border cells), so that no offset leaves the array. Codes of voxels
        # that are not interior (a neighbour wraps around a border) are computed
        # and then left out by slicing the frames' inner cells.
        hw = h * w
        margin = ry * w + rx
        flat = v.reshape(n, -1)
        lo, hi = rt * hw + margin, (t - rt) * hw - margin
        centre = flat[:, lo:hi]
        planes = {
            "xy": [(0, a, b) for a, b in circle_offsets(p, ry, rx)],
            "xt": [(a, 0, b) for a, b in circle_offsets(p, rt, rx)],
            "yt": [(a, b, 0) for a, b in circle_offsets(p, rt, ry)],
        }
        kern = kernels("features.gaus_kernels")
        if kern is not None:
            offs = np.array([[dt * hw + dy * w + dx for dt, dy, dx in planes[pl]] for pl in PLANES], dtype=np.int64)
            counts = np.zeros((n, len(PLANES), 2**p), dtype=np.int64)
            code = np.empty(hi - lo, dtype=np.uint8 if p <= 8 else np.uint16)
            kern.lbptop(flat.view(np.uint8) if flat.dtype.kind == "b" else flat, offs, lo, hi, _inner(ct, h, w, rx, ry),
                        counts, code)
            bins = (table + (np.arange(n * len(PLANES)) * nb)[:, None]).ravel()
            return np.bincount(bins, weights=counts.ravel(), minlength=n * 3 * nb).reshape(n, 3 * nb) / n_centres
        # one row of bits per neighbour, combined into codes by one weighted sum (neighbour k: 2**k)
        bits = np.empty((p,) + centre.shape, dtype=np.uint8)
        weights = (2 ** np.arange(p)).astype(np.uint8 if p <= 8 else np.uint16)
        offsets = (np.arange(n) * 2**p)[:, None, None, None]
        code = np.zeros((n, ct * hw), dtype=weights.dtype)
        for i, pl in enumerate(PLANES):
            for k, (dt, dy, dx) in enumerate(planes[pl]):
                off = dt * hw + dy * w + dx
                np.greater_equal(flat[:, lo + off:hi + off], centre, out=bits[k].view(bool))
            np.einsum("pnm,p->nm", bits, weights, out=code[:, margin:ct * hw - margin])
            inner = code.reshape(n, ct, h, w)[:, :, ry:h - ry, rx:w - rx]
            # each capture's codes counted, then the counts summed into the mapping's bins
            counts = np.bincount(np.add(inner, offsets, dtype=np.intp).ravel(), minlength=n * 2**p)
            bins = (table + (np.arange(n) * nb)[:, None]).ravel()
            out[:, i * nb:(i + 1) * nb] = np.bincount(bins, weights=counts, minlength=n * nb).reshape(n, nb) / n_centres
        return out


@lru_cache(maxsize=64)
def _inner(ct: int, h: int, w: int, rx: int, ry: int) -> np.ndarray:
    """The interior voxels' places among the compared ones (frames ``rt..T - rt - 1`` laid end to end
    from their first cell ``margin = ry * W + rx`` on), read-only: the centres whose codes count."""
    t, y, x = np.meshgrid(np.arange(ct), np.arange(ry, h - ry), np.arange(rx, w - rx), indexing="ij")
    out = (t * h * w + y * w + x - (ry * w + rx)).ravel().astype(np.int64)
    out.flags.writeable = False
    return out
