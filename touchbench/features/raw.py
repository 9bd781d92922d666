"""``raw-window``: a fixed-size window of raw frames, the CNN's input
(Al-mashhadani et al. 2021, section 3)."""

from __future__ import annotations

from numbers import Integral

import numpy as np

from sklearn.utils._param_validation import Interval, StrOptions

from ..datasets.model import SensorSpec
from .base import FEATURES, FeatureInputError, FeatureSet

SHORTER_RULES = ("refuse", "pad")
MAX_WINDOW_VALUES = 1 << 24  # values per capture (128 MiB of float64): 262,144 frames of 8 x 8


@FEATURES.register("raw-window", description="F raw frames from an offset, flattened (CNN and raw-frame classifier input)")
class RawWindow(FeatureSet):
    """``frames`` frames of a capture (from ``offset``), flattened.

    Al-mashhadani et al. 2021, section 3: the CNN takes raw 8 x 8 x F
    frames of HAART, no preprocessing; F = 432 / L is chosen by grid search
    (Fig. 5: L = 30, F = 14, "the first subsample is picked"). The HAART
    protocols state ``frames: 432`` (all frames of a HAART capture), so the
    classifier can choose its own sub-window. Output ``(n, F * H * W)``
    float64 in frame-major, row-major order: column ``f{t}_r{i}_c{j}`` is
    frame ``offset + t``, row i, column j, so ``X.reshape(n, F, H, W)``
    recovers the frames.

    Interpretations and limits:

    - The window length ``frames`` has no default: it must be stated. A
      classifier needs every capture as a row of the same length, and no
      length fits every sensor (HAART's 432 frames are 8 s at 54 Hz; on a
      12 Hz grid of 5-s captures they would be 85 % padding). It is not
      taken from the data either: the shortest training capture would
      differ between folds (and tasks), and a set whose output width
      depends on the fold could not be cached per capture.
    - ``shorter`` is the stated rule for a capture with fewer than
      ``offset + frames`` frames: ``"refuse"`` (default: nothing is
      invented; the run is refused before any task when the dataset holds
      such a capture) or ``"pad"``: repeat its last available frame (a
      held pose rather than an invented "no touch" of zeros; a capture
      with ``offset`` beyond its end repeats its last frame throughout; a
      constant capture stays constant). A longer capture keeps its frames
      ``offset .. offset + frames - 1``. The window length never depends on
      the capture.
    - Values are the raw sensor values as float64 (no scaling: the paper
      feeds raw data; scaling belongs to the classifier).

    Examples
    --------
    Two frames of a 1 x 2 grid, flattened frame by frame:

    >>> import numpy as np
    >>> raw = RawWindow(frames=2)
    >>> raw.fit_transform([np.array([[[1, 2]], [[3, 4]]])])
    array([[1., 2., 3., 4.]])
    >>> list(raw.get_feature_names_out())
    ['f0_r0_c0', 'f0_r0_c1', 'f1_r0_c0', 'f1_r0_c1']
    """

    paper = "Al-mashhadani et al. 2021, section 3 (raw-frame CNN)"
    cost = "cheap"
    fold_dependent = False

    _parameter_constraints = {"frames": [Interval(Integral, 1, None, closed="left"), None],
                              "offset": [Interval(Integral, 0, None, closed="left")],
                              "shorter": [StrOptions(set(SHORTER_RULES))]}
    _parameter_docs = {"frames": "F, the window's length in frames (required: None is refused when it runs).",
                       "offset": "the first frame kept.",
                       "shorter": "a capture shorter than the window: ``refuse`` it, or ``pad`` it with its last frame.",
                       "sensor": "unused: the grid comes with the captures."}

    def __init__(self, frames: int | None = None, offset: int = 0, shorter: str = "refuse", sensor: SensorSpec | None = None):
        self.frames = frames
        self.offset = offset
        self.shorter = shorter
        self.sensor = sensor

    def _check_params(self) -> None:
        if self.frames is None:
            raise FeatureInputError("raw-window: state the window length: frames=N (every capture becomes N frames; "
                                    "shorter ones are refused or padded as 'shorter' says)")

    def _window_problem(self, grid: tuple[int, int]) -> str | None:
        """A window of more than ``MAX_WINDOW_VALUES`` values per capture is refused: padded, it would
        be allocated whatever the captures' length."""
        values = int(self.frames) * int(grid[0]) * int(grid[1])
        if values > MAX_WINDOW_VALUES:
            return (f"raw-window: frames={int(self.frames)} on a {grid[0]} x {grid[1]} grid is {values:,} values per "
                    f"capture, above the {MAX_WINDOW_VALUES:,} a window may hold; lower frames")
        return None

    def _check_grid(self, grid: tuple[int, int]) -> None:
        problem = self._window_problem(grid)
        if problem:
            raise FeatureInputError(problem)

    def check_sensor(self, sensor: SensorSpec, min_frames: int | None = None) -> str | None:
        problem = super().check_sensor(sensor, min_frames) or self._window_problem(sensor.grid)
        need = None if problem else int(self.offset) + int(self.frames)
        if problem is None and self.shorter == "refuse" and min_frames is not None and min_frames < need:
            problem = (f"raw-window: the shortest capture has {min_frames} frames, the window needs {need} "
                       f"(offset {int(self.offset)} + frames {int(self.frames)}); lower frames or set shorter: pad")
        return problem

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        h, w = grid
        return [f"f{t}_r{i}_c{j}" for t in range(int(self.frames)) for i in range(h) for j in range(w)]

    def n_features(self, grid: tuple[int, int]) -> int:
        return int(self.frames) * int(grid[0]) * int(grid[1])

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        n, t = stack.shape[:2]
        f, off = int(self.frames), int(self.offset)
        if t < off + f and self.shorter == "refuse":
            raise FeatureInputError(f"raw-window: a capture has {t} frames, the window needs {off + f} "
                                    "(offset + frames); lower frames or set shorter='pad'")
        idx = np.minimum(np.arange(off, off + f), t - 1)  # repeat the last frame past the end
        return stack[:, idx].reshape(n, -1).astype(np.float64)
