"""The feature-set base class and registry.

A feature set is a scikit-learn transformer whose ``X`` is a sequence of
captures, each a ``(T, H, W)`` array (see :mod:`touchbench.datasets.model`).
``transform`` returns a 2-D float64 array with stable column names
(``get_feature_names_out``). ``fit`` learns only data-dependent parameters
(histogram edges, for example) and only from the training fold; a set whose
``fit`` learns nothing declares ``fold_dependent = False`` so the run engine
may compute its features once per capture and cache them.
"""

from __future__ import annotations

import importlib
from typing import ClassVar, Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from ..registry import Registry

# Modules that register feature sets; imported on first use of the registry.
_MODULES: list[str] = []


def _load() -> None:
    for m in _MODULES:
        importlib.import_module(m)


FEATURES: Registry = Registry("feature set", loader=_load)


def check_captures(captures: Sequence[np.ndarray], *, name: str = "features") -> list[np.ndarray]:
    """Validate a batch of captures: 3-D, same grid, at least one frame, finite.

    NaN or infinite input is refused with the index of the offending capture.
    Accepts a single ``(N, T, H, W)`` array as well as a list.
    """
    if isinstance(captures, np.ndarray) and captures.ndim == 4:
        captures = list(captures)
    out = []
    grid = None
    for i, c in enumerate(captures):
        a = np.asarray(c)
        if a.ndim != 3:
            raise ValueError(f"{name}: capture {i} must be a (frames, H, W) array, got shape {a.shape}")
        if a.shape[0] < 1:
            raise ValueError(f"{name}: capture {i} has no frames")
        if grid is None:
            grid = a.shape[1:]
        elif a.shape[1:] != grid:
            raise ValueError(f"{name}: capture {i} has grid {a.shape[1:]}, capture 0 has {grid}")
        if a.dtype.kind == "f" and not np.isfinite(a).all():
            raise ValueError(f"{name}: capture {i} contains NaN or infinite values")
        if a.dtype.kind not in "biuf":
            raise ValueError(f"{name}: capture {i} has non-numeric dtype {a.dtype}")
        out.append(a)
    return out


class FeatureSet(TransformerMixin, BaseEstimator):
    """Base class: subclasses implement ``_transform_one`` or ``transform``.

    Class attributes (read by the registry listing and the run engine):
    ``paper`` (citation with section), ``cost`` (``cheap`` / ``moderate`` /
    ``expensive``), ``fold_dependent`` (``fit`` learns from data).
    """

    paper: ClassVar[str] = ""
    cost: ClassVar[str] = "cheap"
    fold_dependent: ClassVar[bool] = False

    def fit(self, captures, y=None):
        caps = check_captures(captures, name=type(self).__name__)
        self.grid_ = caps[0].shape[1:] if caps else None
        self._fit(caps, y)
        self.n_features_out_ = len(self.feature_names(self.grid_)) if self.grid_ is not None else 0
        return self

    def _fit(self, captures: list[np.ndarray], y=None) -> None:
        """Learn data-dependent parameters; nothing by default."""

    def transform(self, captures) -> np.ndarray:
        caps = check_captures(captures, name=type(self).__name__)
        if not caps:
            grid = getattr(self, "grid_", None)
            return np.zeros((0, len(self.feature_names(grid)) if grid else 0))
        rows = [self._transform_one(c) for c in caps]
        return np.vstack(rows).astype(np.float64, copy=False)

    def _transform_one(self, capture: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        """Column names for a grid of shape ``grid``; length = output size."""
        raise NotImplementedError

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        return np.asarray(self.feature_names(self.grid_), dtype=object)

    def n_features(self, grid: tuple[int, int]) -> int:
        return len(self.feature_names(grid))
