"""Adaptation to a new session from its unlabelled rows: each session re-centred by its own statistics.

The idea is Euclidean alignment (He & Wu, "Transfer learning for
brain-computer interfaces: a Euclidean space data alignment approach",
IEEE Trans. Biomed. Eng. 67(2), 2020; online 2019): the trials of each
session are transformed by that session's own reference statistics,
computed from its trials without their labels, so that every session --
the training ones and a new one -- is brought to a common reference before
the classifier sees it.

``session-centred`` wraps a registered classifier on a feature matrix:

- ``fit(X, y, groups)``: ``groups`` name each training row's session (the
  run engine passes the training subjects); each session's rows are centred
  on that session's mean (and, with ``scale``, divided by its per-feature
  standard deviation), and the inner classifier (``estimator`` with
  ``params``, built by :func:`touchbench.classifiers.make_classifier` with
  the sensor and seed given here) is fitted on the result through the one
  fit path (:func:`touchbench.classifiers.fitting.fit_on_codes`: label codes,
  the sessions as ``groups`` to an inner classifier that takes them, a
  training set of one class kept without a classifier). Without ``groups``
  every training row is one session.
- ``adapt(X)``: stores the statistics of one new session from its rows,
  unlabelled; ``predict`` / ``predict_proba`` transform with them and are
  refused (:class:`NotAdaptedError`) until ``adapt`` was called. A new
  session replaces the previous one's statistics.

Interpretations (the paper aligns multichannel trials by the inverse square
root of the session's mean covariance matrix; here a row is a feature
vector, not a trial of channels):

- the session's reference is its per-feature mean (first moment) and, with
  ``scale``, its per-feature population standard deviation (``ddof=0``):
  the diagonal of the whitening, since a full covariance of hundreds of
  features over the few captures of one session is not invertible;
- a standard deviation below ``sd_floor`` is taken as ``sd_floor`` (a
  constant feature, a session of one row): the centred value, zero, stays
  zero instead of becoming undefined; a session of one row is therefore
  centred to zeros; ``sd_floor`` must be a positive finite number (declared:
  a protocol's validation refuses 0, a negative or a non-finite floor, and
  ``fit`` does too);
- statistics in float64, in the order of the rows (bit-identical for the
  same rows).

The registry entry carries ``unlabelled_test=True``: an evaluation of this
classifier adapts to the test session's captures (never their labels), a
figure of another kind than a plain one (:func:`uses_unlabelled_test`).
"""

from __future__ import annotations

from numbers import Real
from typing import Any, Iterator

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils._param_validation import Interval
from sklearn.utils.metaestimators import available_if
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.errors import TouchbenchError
from ..core.introspect import sensor_problem
from ._util import build
from .base import CLASSIFIERS, check_declared, check_nested_params, make_classifier
from .fitting import fit_on_codes

__all__ = ["NotAdaptedError", "SessionCentred", "adapt_each_session", "session_statistics", "uses_unlabelled_test"]

SOURCE = ("He & Wu, IEEE TBME 67(2) 2020, Euclidean alignment, per feature on a feature matrix: "
          "each session centred (and scaled) by its own unlabelled rows")
#: the smallest standard deviation a feature is divided by (``scale``)
SD_FLOOR = 1e-6


class NotAdaptedError(TouchbenchError):
    """A session-adapted classifier asked to predict before it was adapted to a session."""


def uses_unlabelled_test(estimator: str) -> bool:
    """Whether the registered classifier ``estimator`` adapts to the test session's unlabelled
    captures (registry tag ``unlabelled_test=True``)."""
    return estimator in CLASSIFIERS and bool(CLASSIFIERS.entry(estimator).tags.get("unlabelled_test"))


def session_statistics(X: np.ndarray, scale: bool, sd_floor: float) -> tuple[np.ndarray, np.ndarray]:
    """``(mean, sd)`` per column of the rows ``X`` of one session (float64): the mean, and the
    population standard deviation floored at ``sd_floor`` with ``scale`` (ones without)."""
    X = np.asarray(X, dtype=np.float64)
    mean = X.mean(axis=0)
    sd = np.maximum(X.std(axis=0), float(sd_floor)) if scale else np.ones(X.shape[1], dtype=np.float64)
    return mean, sd


def adapt_each_session(estimator: Any, X: np.ndarray, sessions: Any) -> Iterator[np.ndarray]:
    """For each session of ``sessions`` (one label per row of ``X``; sorted by name), adapt
    ``estimator`` to that session's rows and yield their positions: the caller predicts them
    before the next session's statistics replace these."""
    sessions = np.asarray([str(s) for s in np.asarray(sessions, dtype=object).tolist()], dtype=object)
    for s in np.unique(sessions):
        rows = np.flatnonzero(sessions == s)
        estimator.adapt(X[rows])
        yield rows


def check_params(params: dict[str, Any]) -> None:
    """The inner classifier's own checks of its ``params`` (its declared domains, then its own
    ``check_params``)."""
    check_nested_params(params.get("estimator"), dict(params.get("params") or {}), ("params",))


class SessionCentred(ClassifierMixin, BaseEstimator):
    """A registered classifier on rows centred (and scaled) by their own session's statistics
    (module docstring).

    Parameters
    ----------
    estimator : the inner classifier, a registered name taking a feature matrix.
    params : its parameters (None: its defaults).
    scale : also divide by the session's per-feature standard deviation.
    sd_floor : the smallest standard deviation divided by.
    sensor : the data's SensorSpec, given to an inner classifier that takes one.
    random_state : the inner classifier's seed.
    """

    #: ``sd_floor`` a positive finite number (a floor of 0 divides a constant feature by 0); the
    #: inner classifier's parameters are its own (``check_params``)
    _parameter_constraints = {"estimator": [str], "params": [dict, None], "scale": ["boolean"],
                              "sd_floor": [Interval(Real, 0, None, closed="neither")],
                              "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, estimator="touch-extra-trees", params=None, scale=False, sd_floor=SD_FLOOR, sensor=None,
                 random_state=None):
        self.estimator = estimator
        self.params = params
        self.scale = scale
        self.sd_floor = sd_floor
        self.sensor = sensor
        self.random_state = random_state

    def _check_inner(self) -> None:
        """Refuse an inner classifier that does not take a feature matrix (or adapts itself)."""
        if uses_unlabelled_test(self.estimator) or CLASSIFIERS.entry(self.estimator).tags.get("input") == "captures":
            raise TouchbenchError(f"session-centred: the inner classifier {self.estimator!r} must take a feature "
                                  "matrix (not the captures, not another session-adapted classifier)")

    def _inner(self, sensor: Any = None) -> Any:
        """The inner classifier, unfitted."""
        self._check_inner()
        return make_classifier(self.estimator, random_state=0, sensor=sensor, **dict(self.params or {}))

    def check_sensor(self, sensor: Any, min_frames: int | None = None) -> str | None:
        """Why the inner classifier cannot serve ``sensor``, or None."""
        return sensor_problem(self._inner(sensor), sensor, min_frames)

    def _centred(self, X: np.ndarray, groups: Any) -> np.ndarray:
        """The training rows, each session's centred (and scaled) by that session's statistics."""
        sessions = np.zeros(len(X), dtype=np.int64) if groups is None else np.asarray(groups)
        if len(sessions) != len(X):
            raise ValueError(f"groups has {len(sessions)} entries for {len(X)} training rows")
        out = np.empty_like(X)
        for s in np.unique(sessions):
            rows = np.flatnonzero(sessions == s)
            mean, sd = session_statistics(X[rows], self.scale, self.sd_floor)
            out[rows] = (X[rows] - mean) / sd
        return out

    def fit(self, X, y, groups=None):
        """Centre (scale) each training session by its own statistics, then fit the inner classifier."""
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        check_declared(self)
        check_params(self.get_params(deep=False))
        self._check_inner()
        self.fitted_ = fit_on_codes(self.estimator, dict(self.params or {}), self.random_state,
                                    self._centred(X, groups), y, groups, sensor=self.sensor)
        self.classes_ = self.fitted_.classes
        for name in ("adapted_mean_", "adapted_sd_"):
            self.__dict__.pop(name, None)  # a refit forgets the session it was adapted to
        return self

    def adapt(self, X) -> "SessionCentred":
        """Store the statistics of one new session from its rows ``X`` (no labels)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        self.adapted_mean_, self.adapted_sd_ = session_statistics(X, self.scale, self.sd_floor)
        return self

    def _adapted(self, X) -> np.ndarray:
        check_is_fitted(self)
        if not hasattr(self, "adapted_mean_"):
            raise NotAdaptedError("session-centred: call adapt(X) with the new session's unlabelled rows before "
                                  "predicting: every session is centred by its own statistics")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return (X - self.adapted_mean_) / self.adapted_sd_

    def predict(self, X):
        Z = self._adapted(X)
        return self.fitted_.predict(Z)

    def _proba_available(self) -> bool:
        if hasattr(self, "fitted_"):
            return self.fitted_.estimator is None or hasattr(self.fitted_.estimator, "predict_proba")
        return hasattr(self._inner(self.sensor), "predict_proba")

    @available_if(_proba_available)
    def predict_proba(self, X):
        """Probabilities over ``classes_`` (in that order)."""
        Z = self._adapted(X)
        P = self.fitted_.predict_proba(Z)
        return np.column_stack([P[str(c)] for c in self.classes_]).astype(np.float64)


DEFAULTS = {"estimator": "touch-extra-trees", "params": None, "scale": False, "sd_floor": SD_FLOOR}


@CLASSIFIERS.register(
    "session-centred",
    description="a registered classifier on rows centred (optionally scaled) by their own session's statistics; "
                "adapts to a new session from its unlabelled rows",
    source=SOURCE, defaults=DEFAULTS, extra=None, unlabelled_test=True, check_params=check_params,
    cheap_params=dict(params={"n_estimators": 5}),
)
def session_centred(random_state=None, sensor=None, **params):
    return build(SessionCentred, DEFAULTS, random_state, {**params, "sensor": sensor}, name="session-centred")
