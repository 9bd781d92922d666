"""``smmhh``: spatial multi-scale motion history histogram (Gaus et al.
2015, section 3.2.4, equation 1)."""

from __future__ import annotations

from numbers import Integral, Real

from typing import Any, Sequence

import numpy as np

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, cell_names
from ..core.compiled import kernels
from .gaus_common import GAUS_PAPER, resolve_units
from .numerics import count_true

# Motion threshold (raw sensor units): the paper says only "appropriate
# thresholds". HAART: 3 is the 99th percentile of |frame(t+s) - frame(t)|
# of a cell in the no-touch captures of the real recordings (s = 1..6), so
# sensor noise rarely counts as motion. CoST: no data here; 10 is a guess.
_TABLE: dict[str, dict[str, Any]] = {"haart": {"threshold": 3.0}, "cost": {"threshold": 10.0}}


def pool2(frames: np.ndarray) -> np.ndarray:
    """2 x 2 average pooling of ``(..., H, W)`` frames -> ``(..., ceil(H/2), ceil(W/2))``.

    An odd row or column is pooled with the cells that exist (a 1 x 2 or
    2 x 1 or 1 x 1 window), so every output cell is the mean of real cells.
    """
    h, w = frames.shape[-2:]
    ph, pw = h % 2, w % 2
    if ph or pw:
        pad = [(0, 0)] * (frames.ndim - 2) + [(0, ph), (0, pw)]
        frames = np.pad(frames, pad)
        cnt = np.pad(np.ones((h, w)), [(0, ph), (0, pw)])
        cnt = cnt[0::2, 0::2] + cnt[1::2, 0::2] + cnt[0::2, 1::2] + cnt[1::2, 1::2]
    else:
        cnt = 4.0
    # four strided slices: faster than a reduction over two length-2 axes
    s = frames[..., 0::2, 0::2] + frames[..., 1::2, 0::2] + frames[..., 0::2, 1::2] + frames[..., 1::2, 1::2]
    return s / cnt


def scales_to_one_cell(grid: tuple[int, int]) -> int:
    """Levels of the pyramid that ends at 1 x 1 (each halving with ceil): 4 for 8 x 8, 6 for 19 x 24."""
    h, w = grid
    levels = 1
    while (h, w) != (1, 1):
        h, w = (h + 1) // 2, (w + 1) // 2
        levels += 1
    return levels


def pyramid_shapes(grid: tuple[int, int], n_scales: int) -> list[tuple[int, int]]:
    h, w = grid
    out = []
    for _ in range(n_scales):
        out.append((h, w))
        h, w = (h + 1) // 2, (w + 1) // 2
    return out


def run_length_histogram(padded: np.ndarray, length: int, max_len: int) -> np.ndarray:
    """Histogram of the lengths of the runs of 1s along axis 1 of ``padded`` ``(R, length + max_len + 1, P)``
    booleans: the sequences of ``length`` samples in rows ``1..length``, the other rows 0 (so a run
    touching either end counts, the sequence read as bordered by 0s). Returns ``(R, max_len, P)``.

    Bin m-1 counts runs of exactly m ones, m < ``max_len``; the last bin counts runs of ``max_len``
    or more. With ``a_m(t)`` = "a run starts at t and lasts at least m samples" (a start, ANDed with
    the next m - 1 samples), the runs of at least m are the sum of ``a_m`` over t, and those of
    exactly m the difference of two such sums: ``max_len`` ANDs of whole arrays, no run is listed.
    """
    a = np.greater(padded[:, 1:length + 1], padded[:, :length])  # a run starts: 1 after 0
    at_least = [count_true(a)]
    for k in range(1, max_len):
        a &= padded[:, 1 + k:1 + k + length]
        at_least.append(count_true(a))
    g = np.stack(at_least, axis=1).astype(np.float64)  # (R, max_len, P): runs of at least m
    g[:, :-1] -= g[:, 1:]
    return g


@FEATURES.register("smmhh", description="multi-scale motion history histograms on 8x8..1x1 pooled videos")
class SpatialMultiScaleMHH(FeatureSet):
    """Spatial multi-scale motion history histogram (SMMHH).

    Gaus et al. 2015, section 3.2.4 and equation 1, after the motion history
    histogram (MHH) of Meng et al. The capture is a video; average pooling
    (2 x 2) is applied three times (8x8, 4x4, 2x2, 1x1). On each video, for
    each frame skip ``s`` in 2..6 ("comparing frame n with n + 2:6"), each
    pixel's binary motion sequence is ``|v(t+s) - v(t)| > threshold``, and
    MHH counts, per pixel, the runs of 1 to M = 5 consecutive motion frames.
    Output: sum over scales of S x M x P_i = 25 x (64 + 16 + 4 + 1) = 2125
    values for an 8 x 8 grid (equation 1), ordered scale, skip, run length,
    pixel: ``smmhh_k{scale}_s{skip}_m{length}_r{i}_c{j}``.

    Interpretations:

    - MHH pattern P_m = "0, m ones, 0" (Meng et al.): a run of exactly m
      motion frames. Runs longer than M are counted in the last bin (m = M
      means "M or more"), so sustained motion is not lost; a run that
      touches the start or end of the sequence counts (the sequence is read
      as bordered by no-motion).
    - "skipping a fixed range of 1 to 5 frames" and "n + 2:6": skips
      ``s`` = 2, 3, 4, 5, 6 (S = 5). The paper's "appropriate thresholds"
      are not given: ``threshold`` defaults per preset (HAART 3 raw units,
      just above the sensor noise of no-touch captures; CoST 10, a guess),
      the same on every scale unless a sequence of one value per scale is
      given; motion is strictly greater than the threshold.
    - "resized and concatenated": flattened and concatenated; counts are
      raw (not divided by the number of frames).
    - Other grids: each pooling halves with ceil (odd edges pool the cells
      that exist). The paper pools three times, taking 8 x 8 down to a
      single cell (the whole surface's motion); ``n_scales=None`` (default)
      keeps that rule on any grid, pooling until 1 x 1: 4 levels on 8 x 8,
      6 on 19 x 24 (19x24, 10x12, 5x6, 3x3, 2x2, 1x1: 620 pixels, 15500
      values). An integer ``n_scales`` fixes the number of levels. Output
      length depends on the grid only.
    - Skips and run lengths are frames, never rescaled by the frame rate:
      the paper used the same 2..6 at 54 Hz (HAART) and 135 Hz (CoST).
    - A capture shorter than s + 1 frames has no frame pair at skip s: its
      counts are 0. A constant capture has no motion: all 0.

    - The preset: named (as published), or the one of the sensor's
      recording setting (HAART's or CoST's). Any other grid sensor
      (:mod:`touchbench.features.gaus_common`): HAART's threshold scaled
      to its value range, ``3 * (hi - lo) / 1023``, the same fraction of
      full scale (0.29 %): 0.748 on a 0..255 sensor, so a change of one
      unit is motion. This assumes the sensor's noise is the same fraction
      of its range as HAART's; give ``threshold`` when it is not. A channel
      sensor is refused; without a sensor a preset or ``threshold`` must be
      given.

    Parameters: ``preset`` ("haart", "cost" or None: the sensor's),
    ``threshold`` (scalar or one per scale, never scaled), ``skips``
    (default (2, 3, 4, 5, 6)), ``max_len`` (M, 5), ``n_scales`` (None:
    down to 1 x 1), ``sensor`` (picks the preset or scales HAART's).
    """

    paper = f"{GAUS_PAPER}.4, eq. 1"
    cost = "moderate"
    fold_dependent = False
    compiled_loops = "features.gaus_kernels"

    _parameter_constraints = {"preset": [StrOptions(set(_TABLE)), None], "threshold": [Real, "array-like", None],
                              "skips": ["array-like"], "max_len": [Interval(Integral, 1, None, closed="left")],
                              "n_scales": [Interval(Integral, 1, None, closed="left"), None]}

    def __init__(
        self,
        preset: str | None = None,
        threshold: float | Sequence[float] | None = None,
        skips: Sequence[int] = (2, 3, 4, 5, 6),
        max_len: int = 5,
        n_scales: int | None = None,
        sensor: SensorSpec | None = None,
    ):
        self.preset = preset
        self.threshold = threshold
        self.skips = skips
        self.max_len = max_len
        self.n_scales = n_scales
        self.sensor = sensor

    def _levels(self, grid: tuple[int, int]) -> int:
        """``n_scales`` if given, else the levels that take ``grid`` down to 1 x 1."""
        return int(self.n_scales) if self.n_scales is not None else scales_to_one_cell(tuple(grid))

    def _thresholds(self, levels: int | None = None) -> list[float]:
        thr = resolve_units("smmhh", self.preset, _TABLE, "threshold", self.threshold, self.sensor, "threshold")
        if np.ndim(thr) == 0:
            return [float(thr)] * int(levels or 1)
        thr = [float(v) for v in thr]
        if levels is not None and len(thr) != levels:
            raise FeatureInputError(f"smmhh: threshold has {len(thr)} values for {levels} scales")
        return thr

    def _check_params(self) -> None:
        self._thresholds(int(self.n_scales) if self.n_scales is not None else None)
        if not len(self.skips) or any(isinstance(s, bool) or int(s) != s or s < 1 for s in self.skips):
            raise FeatureInputError(f"smmhh: skips must be positive frame offsets, got {self.skips!r}")

    def _check_grid(self, grid: tuple[int, int]) -> None:
        self._thresholds(self._levels(grid))

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        names = []
        for k, shape in enumerate(pyramid_shapes(grid, self._levels(grid))):
            cells = cell_names(shape)
            for s in self.skips:
                for m in range(1, int(self.max_len) + 1):
                    names += [f"smmhh_k{k}_s{int(s)}_m{m}_{c}" for c in cells]
        return names

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        levels = self._levels(stack.shape[2:])
        skips = [int(s) for s in self.skips]
        M = int(self.max_len)
        n, t = stack.shape[:2]
        shapes = pyramid_shapes(stack.shape[2:], levels)
        edges = np.cumsum([0] + [h * w for h, w in shapes])
        L = max(t - min(skips), 0)
        if L < 1:
            return np.zeros((n, len(skips) * M * int(edges[-1])))
        thresholds = self._thresholds(levels)
        kern = kernels("features.gaus_kernels")
        if kern is not None:
            lens = np.arange(1, M + 1, dtype=np.uint8 if M < 255 else np.uint32)  # the loop's counters' dtype
            out, args = np.empty((n, len(skips) * M * int(edges[-1]))), (np.array(skips, dtype=np.int64), lens, edges)
            if exact_pyramid(stack, shapes, thresholds):  # the pyramid built in the loop, capture by capture
                ints = np.ascontiguousarray(stack.view(np.uint8) if stack.dtype.kind == "b" else stack)
                kern.smmhh(ints, np.array(shapes, dtype=np.int64), sum_thresholds(shapes, thresholds), *args, out)
            else:
                video, thr = pyramid_video(stack, shapes, thresholds)
                kern.smmhh_video(video, thr, *args, out)
            return out
        video, thr = pyramid_video(stack, shapes, thresholds)
        motion = np.zeros((n, len(skips), L + M + 1, int(edges[-1])), dtype=bool)
        for si, s in enumerate(skips):
            if t > s:
                d = np.subtract(video[:, s:], video[:, :-s])
                np.greater(np.abs(d, out=d), thr, out=motion[:, si, 1:t - s + 1])
        hist = run_length_histogram(motion.reshape(n * len(skips), L + M + 1, -1), L, M).reshape(n, len(skips), M, -1)
        # scale, skip, run length, pixel
        return np.concatenate([hist[..., a:b].reshape(n, -1) for a, b in zip(edges[:-1], edges[1:])], axis=1)


def exact_pyramid(stack: np.ndarray, shapes: list[tuple[int, int]], thresholds: list[float]) -> bool:
    """Whether the pyramid of ``stack`` is taken in int32 sums (:func:`pyramid_video`): integer
    readings of up to 16 bits on a grid every pooling halves exactly (8 x 8: 8, 4, 2)."""
    even = all(h % 2 == 0 and w % 2 == 0 for h, w in shapes[:-1])
    return (stack.dtype.kind in "biu" and stack.dtype.itemsize <= 2 and shapes[0][0] * shapes[0][1] < 2**14 and even
            and not np.isnan(thresholds).any())


def sum_thresholds(shapes: list[tuple[int, int]], thresholds: list[float]) -> np.ndarray:
    """Each pixel's threshold on the int32 sums of an exact pyramid (:func:`pyramid_video`)."""
    scaled = np.asarray(thresholds, dtype=np.float64) * 4.0 ** np.arange(len(shapes))
    return np.repeat(np.clip(np.floor(scaled), -1, 2**31 - 1).astype(np.int32), [h * w for h, w in shapes])


def pyramid_video(stack: np.ndarray, shapes: list[tuple[int, int]], thresholds: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Every scale's pixels side by side, time-major ``(N, T, pixels of all scales)``, and each
    pixel's motion threshold: motion at skip ``s`` is ``|video(t + s) - video(t)| > threshold``.

    The scales are :func:`pool2`'s averages, in float64. Integer readings (up to 16 bits) on a grid
    that every pooling halves exactly (8 x 8: 8, 4, 2) give the same motion in int32: a level-k
    pixel is then the sum of its ``c = 4**k`` cells over ``c`` (exactly, in float64), so its change
    exceeds ``thr`` iff the sum's change exceeds ``thr * c``, for an integer iff it exceeds
    ``floor(thr * c)``.
    """
    n, t = stack.shape[:2]
    sizes = [h * w for h, w in shapes]
    edges = np.cumsum([0] + sizes)
    exact = exact_pyramid(stack, shapes, thresholds)
    video = np.empty((n, t, int(edges[-1])), dtype=np.int32 if exact else np.float64)
    v = stack.astype(video.dtype)
    for k in range(len(shapes)):
        if k:
            v = v[..., 0::2, 0::2] + v[..., 1::2, 0::2] + v[..., 0::2, 1::2] + v[..., 1::2, 1::2] if exact else pool2(v)
        video[:, :, edges[k]:edges[k + 1]] = v.reshape(n, t, -1)
    if not exact:
        return video, np.repeat(thresholds, sizes)
    return video, sum_thresholds(shapes, thresholds)
