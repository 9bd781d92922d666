"""``raw-window``: a fixed-size window of raw frames, the CNN's input
(Al-mashhadani et al. 2021, section 3)."""

from __future__ import annotations

import numpy as np

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet

HAART_FRAMES = 432


@FEATURES.register("raw-window", description="F raw frames from an offset, flattened (CNN input)")
class RawWindow(FeatureSet):
    """The first ``frames`` frames of a capture (from ``offset``), flattened.

    Al-mashhadani et al. 2021, section 3: the CNN takes raw 8 x 8 x F
    frames, no preprocessing; F = 432 / L is chosen by grid search (Fig.
    5: L = 30, F = 14, "the first subsample is picked"). Default F = 432,
    all frames of a HAART capture, so the classifier can choose its own
    sub-window. Output ``(n, F * H * W)`` float64 in frame-major,
    row-major order: column ``f{t}_r{i}_c{j}`` is frame ``offset + t``,
    row i, column j, so ``X.reshape(n, F, H, W)`` recovers the frames.

    Interpretations and limits:

    - Values are the raw sensor values as float64 (no scaling: the paper
      feeds raw data; scaling belongs to the classifier).
    - A capture with fewer than ``offset + frames`` frames is padded by
      repeating its last available frame (a held pose rather than an
      invented "no touch" of zeros); a capture with ``offset`` beyond its
      end repeats its last frame throughout. A constant capture stays
      constant. The window length never depends on the capture.

    Parameters: ``frames`` (F >= 1, 432), ``offset`` (>= 0, 0), ``sensor``
    (unused).
    """

    paper = "Al-mashhadani et al. 2021, section 3 (raw-frame CNN)"
    cost = "cheap"
    fold_dependent = False

    def __init__(self, frames: int = HAART_FRAMES, offset: int = 0, sensor: SensorSpec | None = None):
        self.frames = frames
        self.offset = offset
        self.sensor = sensor

    def _check_params(self) -> None:
        if int(self.frames) < 1 or int(self.offset) < 0 or int(self.frames) != self.frames or int(self.offset) != self.offset:
            raise FeatureInputError(f"raw-window: frames must be an integer >= 1 and offset an integer >= 0, got {self.frames!r}, {self.offset!r}")

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        h, w = grid
        return [f"f{t}_r{i}_c{j}" for t in range(int(self.frames)) for i in range(h) for j in range(w)]

    def n_features(self, grid: tuple[int, int]) -> int:
        return int(self.frames) * int(grid[0]) * int(grid[1])

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t = stack.shape[:2]
        f, off = int(self.frames), int(self.offset)
        idx = np.minimum(np.arange(off, off + f), t - 1)  # repeat the last frame past the end
        return stack[:, idx].reshape(n, -1).astype(np.float64)
