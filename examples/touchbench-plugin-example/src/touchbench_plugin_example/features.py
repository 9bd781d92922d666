"""The feature set ``example-pressure-stats``: statistics of the per-frame mean pressure."""

from __future__ import annotations

import numpy as np

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FEATURES, FeatureSet

STATISTICS = ("mean", "sd", "min", "max")


@FEATURES.register("example-pressure-stats",
                   description="example plugin: mean, sd, min and max of the per-frame mean pressure")
class PressureStats(FeatureSet):
    """Four numbers per capture from its per-frame mean pressure.

    For each frame the mean over all cells is taken: ``m[t] = mean(capture[t])``.
    The features are the mean, the standard deviation (population, ``ddof=0``),
    the minimum and the maximum of ``m`` over the frames.

    Interpretations: with a ``sensor`` whose higher values mean more pressure,
    values are rescaled to 0..1 by the sensor's value range, so sensors of
    different resolution give comparable numbers; without a sensor (or with
    ``normalise=False``) the raw values are used. The set learns nothing from
    the training fold.
    """

    paper = "example plugin (no paper)"
    cost = "cheap"
    fold_dependent = False

    def __init__(self, normalise: bool = True, sensor: SensorSpec | None = None):
        self.normalise = normalise
        self.sensor = sensor

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        frames = stack.astype(np.float64).mean(axis=(2, 3))  # (N, T): the per-frame mean pressure
        if self.normalise and self.sensor is not None:
            lo, hi = (float(v) for v in self.sensor.value_range)
            frames = (frames - lo) / (hi - lo) if hi > lo else frames - lo
            if not self.sensor.higher_is_more_pressure:
                frames = 1.0 - frames
        return np.column_stack([frames.mean(axis=1), frames.std(axis=1), frames.min(axis=1), frames.max(axis=1)])

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        return [f"frame_mean_pressure_{s}" for s in STATISTICS]
