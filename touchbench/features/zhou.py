"""``zhou-basic`` and ``zhou-wavelet``: statistics and wavelet features of the
frame descriptors D1..D6 (Zhou et al. 2017, section 4.1).

Shared pipeline (section 4.1):

1. every frame is up-sampled by ``upsample`` (2: 20x20 -> 40x40 in the
   paper) with bicubic interpolation;
2. six descriptors per frame: D1 mean, D2 maximum, D3 standard deviation of
   the pixels, D4 distance from the centre of gravity to the frame centre,
   D5 distance from the maximum point to the frame centre, D6 number of
   pixels above mean + standard deviation;
3. the 10 % cut-off: threshold = min(D1) + 10 % (max(D1) - min(D1));
   samples before the first and after the last t with D1(t) > threshold
   are removed (from every descriptor);
4. per descriptor: basic statistics (4.1.1) or wavelet features (4.1.2).

Interpretations common to both sets:

- Bicubic = MATLAB ``imresize`` bicubic (Keys cubic, a = -0.5, pixel
  centres mapped by u = (i + 0.5) / f - 0.5, symmetric reflection at the
  borders), applied separably. A constant frame is kept exactly constant
  (floating-point rounding of the weights would otherwise give it a 1e-16
  spread and an arbitrary D6).
- D3 is the ddof=1 standard deviation over the pixels (MATLAB ``std``), 0
  for a single pixel. D6 counts pixels strictly above mean + D3.
- D4: the centre of gravity weighs each pixel by its value above the
  sensor's low end (``sensor.value_range[0]``, 0 by default), negative
  bicubic overshoot clipped to 0. An empty frame (no weight) has no centre
  of gravity: we define it as the frame centre, so D4 = 0 (as
  :func:`touchbench.features.numerics.weighted_centroid`).
- D5: when several pixels share the maximum (a flat peak, a constant
  frame), the "maximum point" is their mean position, independent of scan
  order; a constant frame has D5 = 0.
- Distances are in pixels of the up-sampled frame, from the frame centre
  ((H'-1)/2, (W'-1)/2).
- Cut-off: if D1 is constant no sample exceeds the threshold and nothing is
  removed. The cut-off always uses D1, whatever ``descriptors`` selects.
- ``descriptors`` (Table 6 ablation) selects and orders the descriptors
  the features are computed on, e.g. ``("D1", "D4")``.
- Other sensors: no constant of these sets depends on a grid size or a
  value range (section 4.1: the up-sampling is a factor, D6's threshold is
  the frame's own mean + standard deviation, the cut-off 10 % of the
  capture's own D1 range, D4's zero the sensor's low end), so they serve
  any grid unchanged; distances are in pixels of the up-sampled grid
  (38 x 48 for a 19 x 24 sensor) and the wavelet levels count samples, not
  seconds, as in the paper.
"""

from __future__ import annotations

from numbers import Integral, Real

import warnings
from functools import lru_cache
from typing import Sequence

import numpy as np
import pywt

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet, SharedPrep
from .numerics import as_f64, moments

ZHOU_PAPER = "Zhou et al. 2017 (Sensors 17:2585), section 4.1"
DESCRIPTORS = ("D1", "D2", "D3", "D4", "D5", "D6")
BASIC_STATS = ("mean", "std", "range", "kurt", "skew")
MEAN_READINGS = {"average": "mean", "sum": "sum"}  # reading of section 4.1.1's first statistic -> its name


def _keys_cubic(x: np.ndarray) -> np.ndarray:
    ax = np.abs(x)
    ax2, ax3 = ax * ax, ax * ax * ax
    return np.where(ax <= 1, 1.5 * ax3 - 2.5 * ax2 + 1, np.where(ax <= 2, -0.5 * ax3 + 2.5 * ax2 - 4 * ax + 2, 0.0))


@lru_cache(maxsize=64)
def bicubic_taps(n_in: int, factor: float) -> tuple[np.ndarray, np.ndarray]:
    """MATLAB ``imresize(..., 'bicubic')`` along one axis of length ``n_in``:
    (4, n_out) source indices and weights, n_out = ceil(n_in * factor);
    output i = sum_k weight[k, i] * input[index[k, i]]."""
    n_out = int(np.ceil(n_in * factor))
    u = (np.arange(n_out) + 0.5) / factor - 0.5
    j = np.floor(u).astype(int)[None, :] + np.arange(-1, 3)[:, None]
    wgt = _keys_cubic(u[None, :] - j)
    j = np.where(j < 0, -j - 1, j)  # symmetric reflection at the borders
    j = np.where(j >= n_in, 2 * n_in - j - 1, j)
    j = np.clip(j, 0, n_in - 1)  # a 1-cell axis reflects past itself
    return j, wgt / wgt.sum(axis=0, keepdims=True)


def bicubic_matrix(n_in: int, factor: float) -> np.ndarray:
    """The same resampling as a dense (n_out, n_in) matrix: out = A @ in."""
    j, wgt = bicubic_taps(n_in, factor)
    a = np.zeros((j.shape[1], n_in))
    np.add.at(a, (np.broadcast_to(np.arange(j.shape[1]), j.shape), j), wgt)
    return a


def upsample_frames(frames: np.ndarray, factor: float) -> np.ndarray:
    """Bicubic up-sampling of ``(N, T, H, W)`` float64 frames; constant frames stay exactly constant.

    ``A_h @ frame @ A_w.T`` as stacked matrix products over all frames at
    once (numpy's batched matmul: one small product per frame, computed the
    same way whatever the batch, and no BLAS threading overhead).
    """
    if factor == 1:
        return frames
    n, t, h, w = frames.shape
    ah, aw = bicubic_matrix(h, float(factor)), bicubic_matrix(w, float(factor))
    up = ah @ (frames @ aw.T)
    flat = frames.reshape(n, t, h * w)
    lo = flat.min(axis=-1)
    const = lo == flat.max(axis=-1)
    if const.any():
        up[const] = lo[const][:, None, None]
    return up


def frame_descriptors(stack: np.ndarray, factor: float, floor: float) -> np.ndarray:
    """D1..D6 of every frame: ``(N, T, H, W)`` -> ``(N, T, 6)`` float64, vectorised over frames and pixels."""
    up = upsample_frames(as_f64(stack), factor)
    n, t, h, w = up.shape
    p = h * w
    frames = up.reshape(n * t, h, w)
    flat = frames.reshape(n * t, p)
    rows = np.arange(h, dtype=np.float64)
    cols = np.arange(w, dtype=np.float64)
    cy, cx = (h - 1) / 2.0, (w - 1) / 2.0
    d1 = flat.sum(axis=-1) / p
    d2 = flat.max(axis=-1)
    const = d2 == flat.min(axis=-1)
    dev = flat - d1[:, None]
    var = np.einsum("ij,ij->i", dev, dev) / (p - 1) if p > 1 else np.zeros(len(flat))
    d3 = np.sqrt(np.where(const, 0.0, var))
    # D4: centre of gravity of the pressure above the sensor's floor
    wts = np.maximum(frames - floor, 0.0)
    tot = wts.sum(axis=(-2, -1))
    empty = (tot <= 0) | const  # a uniform frame's centre of gravity is the centre, exactly
    safe = np.where(empty, 1.0, tot)
    gr = np.where(empty, cy, (wts.sum(axis=-1) * rows).sum(axis=-1) / safe)
    gc = np.where(empty, cx, (wts.sum(axis=-2) * cols).sum(axis=-1) / safe)
    d4 = np.hypot(gr - cy, gc - cx)
    # D5: mean position of the pixels at the maximum
    at_max = frames == d2[:, None, None]
    n_max = np.count_nonzero(at_max.reshape(n * t, p), axis=-1)
    mr = (np.count_nonzero(at_max, axis=-1) * rows).sum(axis=-1) / n_max
    mc = (np.count_nonzero(at_max, axis=-2) * cols).sum(axis=-1) / n_max
    d5 = np.hypot(mr - cy, mc - cx)
    d6 = np.count_nonzero(flat > (d1 + d3)[:, None], axis=-1).astype(np.float64)
    return np.stack([d1, d2, d3, d4, d5, d6], axis=-1).reshape(n, t, 6)


def cutoff_slice(d1: np.ndarray, fraction: float = 0.1) -> slice:
    """The samples kept by the cut-off on one capture's D1 series (section 4.1)."""
    lo, hi = d1.min(), d1.max()
    above = np.flatnonzero(d1 > lo + (hi - lo) * fraction)
    if above.size == 0:
        return slice(0, len(d1))
    return slice(int(above[0]), int(above[-1]) + 1)


def _parse_descriptors(owner: str, descriptors: Sequence) -> list[int]:
    out = []
    for d in descriptors:
        s = str(d).upper()
        s = s if s.startswith("D") else f"D{s}"
        if s not in DESCRIPTORS:
            raise FeatureInputError(f"{owner}: unknown descriptor {d!r} (known: {', '.join(DESCRIPTORS)})")
        out.append(DESCRIPTORS.index(s))
    if not out or len(set(out)) != len(out):
        raise FeatureInputError(f"{owner}: descriptors must be a non-empty list without repeats, got {descriptors!r}")
    return out


class _ZhouBase(FeatureSet):
    paper = ZHOU_PAPER
    cost = "moderate"
    fold_dependent = False
    _name = "zhou"
    #: upsample: the bicubic factor, at most 16 (a frame of 16 x 16 cells becomes 256 x 256 pixels)
    _parameter_constraints = {"upsample": [Interval(Real, 1, 16, closed="both")], "descriptors": ["array-like"],
                              "trim": ["boolean"]}

    def _common_check(self) -> None:
        _parse_descriptors(self._name, self.descriptors)

    def _floor(self) -> float:
        return float(self.sensor.value_range[0]) if self.sensor is not None else 0.0

    def _per_descriptor(self, series: np.ndarray) -> np.ndarray:
        """Features of one capture's trimmed descriptor series ``(k, L)`` -> ``(k * n_per,)``."""
        raise NotImplementedError

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        return self._from_descriptors(frame_descriptors(stack, float(self.upsample), self._floor()))

    def _batch_rows(self, stack: np.ndarray, shared: SharedPrep) -> np.ndarray:
        """:meth:`_transform_batch`, the stack's :func:`frame_descriptors` computed once for the Zhou
        sets of a :class:`FeatureStack` with the same up-sampling and floor (every descriptor, whatever
        ``descriptors`` selects; the rows never write into them)."""
        key = ("zhou-descriptors", float(self.upsample), self._floor())
        return self._from_descriptors(shared.get(key, lambda: frame_descriptors(stack, key[1], key[2])))

    def _from_descriptors(self, desc: np.ndarray) -> np.ndarray:
        """The rows of captures whose frame descriptors are ``desc`` ``(N, T, 6)``."""
        idx = _parse_descriptors(self._name, self.descriptors)
        rows = []
        for d in desc:  # one capture at a time: the cut-off gives each its own length
            keep = cutoff_slice(d[:, 0]) if self.trim else slice(None)
            rows.append(self._per_descriptor(np.ascontiguousarray(d[keep][:, idx].T)))
        return np.vstack(rows)


@FEATURES.register("zhou-basic", description="5 statistics of each frame-descriptor series D1..D6")
class ZhouBasic(_ZhouBase):
    """Basic features of the frame descriptors (Zhou et al. 2017, section 4.1.1).

    Pipeline and common interpretations: module docstring. Per descriptor
    series: mean, standard deviation (ddof = 1, as the paper's formula),
    absolute range max - min, kurtosis and skewness, in the paper's order:
    5 x 6 = 30 values for all descriptors (any grid),
    ``zhou_basic_{D}_{stat}``.

    Interpretations:

    - The paper names the first statistic "the average value in the window"
      but prints its formula without the 1/T, as the sum of the series.
      ``mean="average"`` (the default) follows the words; ``mean="sum"``
      the formula as printed (the feature is then named ``..._sum``), a
      reading measured in ``docs/research/scene-calibration.md``. Only the
      basic features take it: section 4.1.2's wavelet "mean" gives no
      formula of its own.
    - Kurtosis and skewness divide the biased 4th / 3rd central moment
      (1/T) by the ddof = 1 standard deviation to the 4th / 3rd power,
      literally as written (MATLAB's functions use the biased standard
      deviation; the difference is a factor ((T-1)/T)^2 resp. ^1.5).
    - A constant descriptor series (notouch, constant pressure, one frame)
      has std 0, range 0, skewness 0 and kurtosis 3 (see
      :mod:`touchbench.features.numerics`).

    Parameters: ``upsample`` (bicubic factor, 2), ``descriptors``
    (subset of D1..D6), ``trim`` (the 10 % cut-off, True), ``mean``
    ("average" or "sum", above), ``sensor`` (its low end is the zero of the
    D4 weights).
    """

    _name = "zhou-basic"
    paper = f"{ZHOU_PAPER}.1"

    _parameter_constraints = {**_ZhouBase._parameter_constraints, "mean": [StrOptions(set(MEAN_READINGS))]}

    def __init__(self, upsample: float = 2, descriptors: Sequence = DESCRIPTORS, trim: bool = True,
                 mean: str = "average", sensor: SensorSpec | None = None):
        self.upsample = upsample
        self.descriptors = descriptors
        self.trim = trim
        self.mean = mean
        self.sensor = sensor

    def _check_params(self) -> None:
        self._common_check()

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        idx = _parse_descriptors(self._name, self.descriptors)
        stats = (MEAN_READINGS[self.mean],) + BASIC_STATS[1:]
        return [f"zhou_basic_{DESCRIPTORS[i]}_{s}" for i in idx for s in stats]

    def _per_descriptor(self, series: np.ndarray) -> np.ndarray:
        m = moments(series, ddof_scale=1)
        first = m[MEAN_READINGS[self.mean]]
        return np.stack([first, np.sqrt(m["var"]), m["range"], m["kurt"], m["skew"]], axis=1).ravel()


@FEATURES.register("zhou-wavelet", description="db8 wavelet subband statistics of each frame-descriptor series")
class ZhouWavelet(_ZhouBase):
    """Wavelet features of the frame descriptors (Zhou et al. 2017, section 4.1.2).

    Pipeline and common interpretations: module docstring. Per descriptor
    series D of length T: pad with floor(T/2) copies of its first value
    before and of its last value after; multiply by the symmetric Hamming
    window 0.54 - 0.46 cos(2 pi t / (N - 1)) over the padded length N;
    db8 discrete wavelet transform with J levels (``levels``, 10 by default,
    the paper's final choice; Table 4 tries 4, 6, 8, 10). Features: the
    mean of a_J, d_J, d_(J-1), d_(J-2), then for each of d_1..d_(J-3):
    mean, max - min, standard deviation, kurtosis, skewness. 4 + 5 (J - 3)
    per descriptor: 14 for J = 5 and 39 for J = 10 as the paper states;
    6 x 39 = 234 values for J = 10 (any grid). Names
    ``zhou_wavelet_{D}_{subband}_{stat}``.

    Interpretations:

    - The paper's text is inconsistent: "the last three subbands (... d3,
      d4, d5, a5)" lists four subbands and "n in {aJ, dJ, d(J-1), d(J-2),
      d(J-3)}" five, for "the first four wavelet features"; and "lower
      levels j in [1, J-4]" would give 4 + 5 (J - 4) = 9 features for J = 5,
      not the stated 14. The only reading that gives both 14 (J = 5) and
      39 (J = 10) is: four means (a_J, d_J, d_(J-1), d_(J-2)) and five
      statistics on each of d_1..d_(J-3). We follow the counts.
    - d_1 is the finest (highest-frequency) subband, as in the paper's
      Table 2. Transform: the paper uses LTFAT's ``fwt``, whose default
      periodic boundary ('per') first zero-pads the signal at its end to
      the next multiple of 2^J ("zero padding to the next legal length and
      periodic boundary extension", LTFAT's ``fwt`` help) and then halves
      it exactly at each level, as Table 2 does (800, 400, ... for 1600
      samples). We do the same: the windowed signal is zero-padded to a
      multiple of 2^J, then PyWavelets ``wavedec(mode="periodization")``,
      the same periodic orthogonal transform on such a length (whether
      the two align their filters on the same samples was not checked
      against LTFAT, which is MATLAB/Octave code). So for
      J = 8 and 10 most captures carry many zeros, and their subband
      statistics depend on the capture's length.
    - Padding size T/2 for odd T: floor(T/2).
    - A level deeper than the signal allows (e.g. a 10-frame capture with
      J = 10) is no special case: the zero padding to 2^J gives every
      subband its coefficients. PyWavelets' warning about boundary effects
      is silenced.
    - Standard deviation, kurtosis and skewness as in ``zhou-basic``.

    Parameters: ``levels`` (J >= 3), ``wavelet`` ("db8"), ``upsample``,
    ``descriptors``, ``trim``, ``sensor``.
    """

    _name = "zhou-wavelet"
    paper = f"{ZHOU_PAPER}.2, Tables 2, 4, 6"

    _parameter_constraints = {**_ZhouBase._parameter_constraints, "levels": [Interval(Integral, 3, None, closed="left")],
                              "wavelet": [str]}

    def __init__(
        self,
        levels: int = 10,
        wavelet: str = "db8",
        upsample: float = 2,
        descriptors: Sequence = DESCRIPTORS,
        trim: bool = True,
        sensor: SensorSpec | None = None,
    ):
        self.levels = levels
        self.wavelet = wavelet
        self.upsample = upsample
        self.descriptors = descriptors
        self.trim = trim
        self.sensor = sensor

    def _check_params(self) -> None:
        self._common_check()
        try:
            pywt.Wavelet(self.wavelet)
        except ValueError:
            raise FeatureInputError(f"zhou-wavelet: unknown wavelet {self.wavelet!r}") from None

    def _subband_names(self) -> list[str]:
        J = int(self.levels)
        names = [f"a{J}_mean", f"d{J}_mean", f"d{J - 1}_mean", f"d{J - 2}_mean"]
        for j in range(1, J - 2):
            names += [f"d{j}_{s}" for s in BASIC_STATS]
        return names

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        idx = _parse_descriptors(self._name, self.descriptors)
        return [f"zhou_wavelet_{DESCRIPTORS[i]}_{s}" for i in idx for s in self._subband_names()]

    def _per_descriptor(self, series: np.ndarray) -> np.ndarray:
        J = int(self.levels)
        t = series.shape[1]
        pad = t // 2
        padded = np.pad(series, [(0, 0), (pad, pad)], mode="edge")
        windowed = padded * np.hamming(padded.shape[1])
        block = 2**J  # LTFAT's 'per': zero padding at the end to the next multiple of 2^J
        windowed = np.pad(windowed, [(0, 0), (0, -windowed.shape[1] % block)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            coeffs = pywt.wavedec(windowed, self.wavelet, mode="periodization", level=J, axis=-1)
        # coeffs = [a_J, d_J, d_(J-1), ..., d_1]
        cols = [c.mean(axis=-1) for c in coeffs[:4]]
        for j in range(1, J - 2):
            m = moments(coeffs[J + 1 - j], ddof_scale=1)
            cols += [m["mean"], m["range"], np.sqrt(m["var"]), m["kurt"], m["skew"]]
        return np.stack(cols, axis=1).ravel()
