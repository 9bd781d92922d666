"""``bmh``: binary motion history (Gaus et al. 2015, section 3.2.2)."""

from __future__ import annotations

from numbers import Real

from typing import Any

import numpy as np

from sklearn.utils._param_validation import StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureSet, cell_names
from ..core.compiled import kernels
from .gaus_common import GAUS_PAPER, resolve_units

# Section 3.2.2: high pressure is value >= maximum - offset.
_TABLE: dict[str, dict[str, Any]] = {"haart": {"offset": 5.0}, "cost": {"offset": 100.0}}


@FEATURES.register("bmh", description="binary map of the cells ever touched with high pressure")
class BinaryMotionHistory(FeatureSet):
    """Binary motion history (BMH): the high-pressure shape of a gesture.

    Gaus et al. 2015, section 3.2.2: one value per cell, 1 if "throughout
    the gesture instance, the corresponding sensor cell was touched at least
    once with high pressure (CoST: pressure >= (maximum - 100); HAART:
    pressure >= (maximum - 5))", 0 otherwise. 64 values for an 8 x 8 grid
    (H x W in general), row-major ``bmh_r{i}_c{j}``.

    Interpretations:

    - "maximum" is the capture's maximum over all cells and frames
      (``level="instance"``, default): the paper's shape is one matrix per
      instance. ``level="frame"`` uses each frame's own maximum instead
      (a cell is set if it was ever within ``offset`` of its frame's peak).
    - The offsets 5 and 100 are raw sensor units, as in Table 3.
    - With the instance maximum at least one cell is always 1; a constant
      capture (no touch, all zero, all saturated) sets every cell to 1.
      Finite and binary for every input.

    - The preset: named (as published), or the one of the sensor's
      recording setting (HAART's or CoST's). Any other grid sensor
      (:mod:`touchbench.features.gaus_common`): HAART's offset scaled to
      its value range, ``5 * (hi - lo) / 1023``, the same fraction of full
      scale (0.49 %): 1.246 on a 0..255 sensor, so a cell counts at
      ``max - 1`` but not ``max - 2``. A channel sensor is refused; without
      a sensor a preset or ``offset`` must be given. The output is one
      value per cell of any grid (nothing else depends on the grid).
    """

    paper = f"{GAUS_PAPER}.2"
    cost = "cheap"
    fold_dependent = False
    compiled_loops = "features.gaus_kernels"

    _parameter_constraints = {"preset": [StrOptions(set(_TABLE)), None], "offset": [Real, None],
                              "level": [StrOptions({"instance", "frame"})]}
    _parameter_docs = {"preset": "the table's settings (None: the sensor's).",
                       "offset": "overrides the preset, never scaled.",
                       "level": "``instance`` or ``frame`` (above).",
                       "sensor": "picks the preset or scales HAART's."}

    def __init__(self, preset: str | None = None, offset: float | None = None, level: str = "instance", sensor: SensorSpec | None = None):
        self.preset = preset
        self.offset = offset
        self.level = level
        self.sensor = sensor

    def _check_params(self) -> None:
        resolve_units("bmh", self.preset, _TABLE, "offset", self.offset, self.sensor, "offset")

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        return [f"bmh_{c}" for c in cell_names(grid)]

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        off = float(resolve_units("bmh", self.preset, _TABLE, "offset", self.offset, self.sensor, "offset"))
        n, t = stack.shape[:2]
        kern = kernels("features.gaus_kernels")
        if kern is not None and stack.dtype != np.float16:  # numba has no float16: numpy's path for it
            frames = stack.reshape(n, t, -1)
            out = np.empty((n, frames.shape[2]))
            kern.bmh(frames.view(np.uint8) if frames.dtype.kind == "b" else frames, off, self.level == "frame", out)
            return out
        if self.level == "instance":
            # a cell reaches the threshold in some frame iff its largest value does; the maxima are
            # taken in the captures' dtype and then made float64 (rounding keeps the order)
            peak = stack.reshape(n, t, -1).max(axis=1).astype(np.float64)
            return (peak >= peak.max(axis=1, keepdims=True) - off).astype(np.float64)
        x = stack.reshape(n, t, -1).astype(np.float64)
        return (x >= x.max(axis=2, keepdims=True) - off).any(axis=1).astype(np.float64)
