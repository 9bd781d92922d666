"""Helpers shared by the classifier modules: building an estimator from a
registry entry's defaults, the standardisation MATLAB and Weka apply, a
random forest whose ``max_features`` can follow Weka's rule, and the
``LabelEncoded`` base for estimators whose backend wants integer labels.

Nothing here is tied to one paper; the paper modules (``gaus.py``,
``flagg.py``, ``zhou.py``, ``jung.py``, ``xgb.py``, ``cnn.py``) import it.
"""

from __future__ import annotations

import importlib.util
import inspect
import math
from typing import Any, Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, TransformerMixin
from sklearn.ensemble import RandomForestClassifier
from sklearn.tree import DecisionTreeClassifier
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import StrOptions
from sklearn.utils.metaestimators import available_if
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.errors import TouchbenchError

#: Largest seed handed to a sub-estimator (numpy's legacy RandomState bound).
MAX_SEED = 2**31 - 1


def build(cls: type, defaults: dict[str, Any], random_state: Any, params: dict[str, Any], *, name: str):
    """``cls(**{**defaults, **params, random_state})``, refusing unknown names.

    ``random_state`` is passed only when ``cls`` takes one (LDA, KNN and
    Gaussian naive Bayes are deterministic and ignore it).
    """
    valid = set(cls().get_params(deep=False))
    unknown = sorted(set(params) - valid)
    if "random_state" in params:
        raise TouchbenchError(f"classifier {name!r}: pass random_state as its own argument, not in params")
    if unknown:
        raise TouchbenchError(
            f"classifier {name!r}: unknown parameter(s) {', '.join(unknown)}; "
            f"known: {', '.join(sorted(valid - {'random_state'}))}"
        )
    kwargs = {**defaults, **params}
    if "random_state" in valid:
        kwargs["random_state"] = random_state
    return cls(**kwargs)


def seed_int(random_state: Any) -> int:
    """An integer seed for a sub-estimator: ``random_state`` itself when it is an
    integer, else one draw from it (None, a RandomState) below ``MAX_SEED``."""
    if isinstance(random_state, (int, np.integer)):
        return int(random_state)
    return int(check_random_state(random_state).randint(MAX_SEED))


def frames_in_row(n_columns: int, grid: tuple[int, int], who: str = "") -> int:
    """Frames in a flattened capture of ``n_columns`` values on ``grid`` (H, W);
    a ``ValueError`` (prefixed with ``who``) when they do not fill whole frames."""
    h, w = (int(g) for g in grid)
    if n_columns % (h * w):
        raise ValueError(f"{who + ': ' if who else ''}{n_columns} features is not a whole number of {h}x{w} frames")
    return n_columns // (h * w)


def is_captures(X: Any) -> bool:
    """Whether ``X`` is a sequence of ``(T, H, W)`` captures (a list, or an ``(n, T, H, W)``
    array) rather than a 2-D matrix of flattened frames."""
    if isinstance(X, np.ndarray):
        return X.ndim == 4
    return isinstance(X, (list, tuple)) and len(X) > 0 and np.ndim(X[0]) == 3


def captures_to_rows(captures: Sequence[np.ndarray], grid: tuple[int, int], length: int, who: str = "") -> np.ndarray:
    """``(n, length * H * W)`` float64 rows of frames (frame-major, row-major, as ``raw-window``
    lays them out): each capture's first ``length`` frames, a shorter one padded by repeating
    its last frame (a held pose, not an invented release). The captures must be on ``grid``."""
    h, w = (int(g) for g in grid)
    out = np.empty((len(captures), int(length), h, w), dtype=np.float64)
    for i, c in enumerate(captures):
        c = np.asarray(c)
        if c.ndim != 3 or c.shape[1:] != (h, w):
            raise ValueError(f"{who + ': ' if who else ''}capture {i} has shape {c.shape}, not (T, {h}, {w}) "
                             "frames of the sensor's grid")
        if len(c) == 0:
            raise ValueError(f"{who + ': ' if who else ''}capture {i} has no frames")
        idx = np.minimum(np.arange(int(length)), len(c) - 1)
        out[i] = c[idx]
    return out.reshape(len(captures), -1)


class SensorError(TouchbenchError, ValueError):
    """A raw-frame classifier without the sensor it needs, or with a grid that is not the sensor's."""


def sensor_frames(who: str, sensor: Any, grid: Any, frame_rate: Any = None, *,
                  need_rate: bool = False) -> tuple[tuple[int, int], float | None]:
    """The ``(grid, frame rate)`` a raw-frame classifier works with: the sensor's.

    A flattened row of frames does not say its grid, so the classifier must
    be told: by ``sensor`` (the run engine passes the dataset's), or, from
    Python without a sensor, by ``grid`` (and ``frame_rate`` when
    ``need_rate``). A ``grid`` or ``frame_rate`` given with a sensor must be
    the sensor's. Raises :class:`SensorError` naming ``who`` and the reason;
    the rate is None when not ``need_rate``.
    """
    if grid is not None:
        try:
            g = tuple(int(v) for v in grid)
        except (TypeError, ValueError):
            g = ()
        if len(g) != 2 or min(g) < 1:
            raise SensorError(f"{who}: grid must be (H, W) with positive sizes, got {grid!r}")
        grid = g
    if frame_rate is not None and not (isinstance(frame_rate, (int, float)) and math.isfinite(frame_rate) and frame_rate > 0):
        raise SensorError(f"{who}: frame_rate must be a positive number, got {frame_rate!r}")
    if sensor is not None:
        sg = tuple(int(v) for v in sensor.grid)
        if grid is not None and grid != sg:
            raise SensorError(f"{who}: grid {grid} is not the grid of sensor {sensor.describe()}; "
                              "leave grid unset, the sensor gives it")
        rate = float(sensor.frame_rate)
        if need_rate and frame_rate is not None and float(frame_rate) != rate:
            raise SensorError(f"{who}: frame_rate {frame_rate:g} is not the rate of sensor {sensor.describe()}; "
                              "leave frame_rate unset, the sensor gives it")
        return sg, (rate if need_rate else None)
    if grid is None or (need_rate and frame_rate is None):
        what = "grid and frame rate" if need_rate else "grid"
        alt = "grid=(H, W) and frame_rate=..." if need_rate else "grid=(H, W)"
        raise SensorError(f"{who}: needs the sensor's {what} (a row of raw frames does not say them): "
                          f"pass sensor=SensorSpec(...) (or {alt})")
    return grid, (float(frame_rate) if need_rate else None)


def importable(module: str) -> bool:
    """Whether the optional package ``module`` can be imported, without importing it."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # a broken or blocked install
        return False


def torch_available() -> bool:
    """Whether PyTorch can be imported, without importing it."""
    return importable("torch")


def check_sample_weight(sample_weight, n: int) -> np.ndarray:
    """Sample weights as a float64 vector of length ``n`` (ones when None):
    finite, non-negative, not all zero."""
    if sample_weight is None:
        return np.ones(n)
    w = np.asarray(sample_weight, dtype=np.float64)
    if w.ndim == 0:
        w = np.full(n, float(w))
    if w.shape != (n,):
        raise ValueError(f"sample_weight has shape {w.shape}, expected ({n},)")
    if not np.isfinite(w).all() or (w < 0).any():
        raise ValueError("Sample weights must be finite and non-negative.")
    if not (w > 0).any():
        raise ValueError("Sample weights must contain at least one non-zero number.")
    return w


# ---------------------------------------------------------------------------
# standardisation


class SampleStandardScaler(TransformerMixin, BaseEstimator):
    """Centre each column on its mean and divide by its *sample* standard
    deviation (``ddof=1``).

    This is what MATLAB's ``'Standardize', true`` (``fitcsvm``, ``fitcknn``,
    the Classification Learner presets) and Weka's ``Logistic`` do, whereas
    scikit-learn's ``StandardScaler`` divides by the population deviation
    (``ddof=0``). A column with zero (or undefined, n = 1) deviation is only
    centred, as MATLAB does.
    """

    def fit(self, X, y=None, sample_weight=None):
        """``sample_weight`` are frequency weights (a weight of 2 is a repeated
        row; the denominator is ``sum(w) - 1``, as in Weka)."""
        X = validate_data(self, X, dtype=np.float64)
        w = check_sample_weight(sample_weight, X.shape[0])
        sw = w.sum()
        self.mean_ = (w @ X) / sw
        if sw > 1:
            scale = np.sqrt((w @ (X - self.mean_) ** 2) / (sw - 1.0))
        else:
            scale = np.zeros(X.shape[1])
        scale[~np.isfinite(scale) | (scale == 0)] = 1.0
        self.scale_ = scale
        return self

    def transform(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return (X - self.mean_) / self.scale_


# ---------------------------------------------------------------------------
# Weka's random forest


def weka_max_features(max_features: Any, n_features: int) -> Any:
    """Resolve Weka's ``-K`` rule: ``"weka"`` (Weka's ``-K 0``) is
    ``int(log2(M)) + 1`` attributes per split (``RandomForest.java``:
    ``(int) Utils.log2(numAttributes - 1) + 1``); an integer is capped at
    ``M`` as Weka does; anything else is scikit-learn's own value."""
    if isinstance(max_features, str) and max_features == "weka":
        return int(math.log2(n_features)) + 1 if n_features > 0 else 1
    if isinstance(max_features, (int, np.integer)) and not isinstance(max_features, bool):
        return int(min(max_features, max(n_features, 1)))
    return max_features


class WekaRandomForestClassifier(RandomForestClassifier):
    """scikit-learn's random forest, with ``max_features="weka"`` for Weka's
    default ``int(log2(M)) + 1`` and an integer ``max_features`` capped at the
    number of features (Weka caps it; scikit-learn would raise).

    Weighted fits (boosting) draw each bag with probability proportional to
    the instance weights, as Weka's ``Bagging`` does (scikit-learn 1.9, the
    development version; releases before the weighted bootstrap multiplied
    bootstrap counts by ``sample_weight`` instead). Remaining differences
    from Weka's ``RandomForest``: the random streams and the tie-breaking
    between equally good splits, so individual trees differ for one seed.
    """

    #: scikit-learn's domains, ``max_features`` taking ``"weka"`` too (without it the default would
    #: break the parent's domain, and a protocol's ``max_features`` would not be checked at all)
    _parameter_constraints = {
        **RandomForestClassifier._parameter_constraints,
        "max_features": [c if not isinstance(c, StrOptions) else StrOptions({*c.options, "weka"})
                         for c in RandomForestClassifier._parameter_constraints["max_features"]],
    }

    def _make_estimator(self, append=True, random_state=None):
        """A tree as scikit-learn's ensembles make it (a tree of the forest's ``estimator_params``,
        its ``random_state`` the one integer drawn from ``random_state``), built directly instead of
        by ``clone`` and ``set_params``, which read the constructor's signature at every tree
        (about a twentieth of a 100-tree forest's fit): the same trees."""
        if type(self.estimator_) is not DecisionTreeClassifier:
            return super()._make_estimator(append=append, random_state=random_state)
        tree = DecisionTreeClassifier(**{p: getattr(self, p) for p in self.estimator_params})
        if random_state is not None:
            tree.random_state = check_random_state(random_state).randint(np.iinfo(np.int32).max)
        if append:
            self.estimators_.append(tree)
        return tree

    def fit(self, X, y, sample_weight=None):
        requested = self.max_features
        try:
            n_features = np.shape(X)[1] if len(np.shape(X)) == 2 else 0
        except Exception:  # let the parent's validation report it
            n_features = 0
        self.max_features = weka_max_features(requested, n_features)
        try:
            return super().fit(X, y, sample_weight=sample_weight)
        finally:
            self.max_features = requested


# ---------------------------------------------------------------------------
# estimators that wrap another (a pipeline) but keep flat parameters


class DelegatingClassifier(ClassifierMixin, BaseEstimator):
    """Base for wrappers with flat, paper-named parameters.

    Subclasses implement :meth:`_make_estimator` (called in ``fit``) and get
    ``predict``, ``predict_proba`` (only when the inner estimator has it) and
    ``decision_function`` delegated to the fitted ``estimator_``. Labels pass
    through unchanged (the inner estimators accept string labels).
    """

    def _make_estimator(self, n_features: int, n_classes: int):  # pragma: no cover
        raise NotImplementedError

    def fit(self, X, y, sample_weight=None):
        X, y = validate_data(self, X, y, dtype=np.float64)

        check_classification_targets(y)
        self.classes_ = np.unique(y)
        est = self._make_estimator(X.shape[1], len(self.classes_))
        if sample_weight is not None:
            w = check_sample_weight(sample_weight, X.shape[0])
            est.fit(X, y, **_weight_params(est, w))
        else:
            est.fit(X, y)
        self.estimator_ = est
        return self

    def _X(self, X):
        check_is_fitted(self)
        return validate_data(self, X, dtype=np.float64, reset=False)

    def predict(self, X):
        X = self._X(X)
        return self.estimator_.predict(X)

    def _proba_available(self) -> bool:
        """Whether an unfitted instance will have ``predict_proba`` (override)."""
        return True

    @available_if(lambda self: _inner_has(self, "predict_proba"))
    def predict_proba(self, X):
        X = self._X(X)
        return self.estimator_.predict_proba(X)

    @available_if(lambda self: _inner_has(self, "decision_function"))
    def decision_function(self, X):
        X = self._X(X)
        return self.estimator_.decision_function(X)


def _inner_has(self: DelegatingClassifier, method: str) -> bool:
    if hasattr(self, "estimator_"):
        return hasattr(self.estimator_, method)
    if method == "predict_proba":
        return self._proba_available()
    return getattr(self, "_has_decision_function", False)


def _weight_params(est, w: np.ndarray) -> dict[str, np.ndarray]:
    """``sample_weight`` for an estimator, or for every step of a pipeline
    whose ``fit`` takes it (so a scaler sees the same weights as the model)."""

    steps = getattr(est, "steps", None)
    if not steps:
        return {"sample_weight": w}
    out = {}
    for name, step in steps:
        if step != "passthrough" and step is not None and "sample_weight" in inspect.signature(step.fit).parameters:
            out[f"{name}__sample_weight"] = w
    return out
