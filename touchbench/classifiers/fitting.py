"""The one fit path from a feature matrix and labels to a fitted estimator, and its predictions.

The run engine's tasks, ``touchbench train`` (through
:func:`touchbench.methods.fitting.fit_estimator`) and the nested search over
candidate methods (:mod:`touchbench.classifiers.search`) all fit here, so
they treat labels, subjects and degenerate folds the same way:

- labels: the estimator is fitted on integer codes ``0..C-1`` of the
  classes present in the training rows, sorted (:func:`label_codes`),
  which every estimator accepts (XGBoost needs contiguous codes);
  predictions are decoded back to the labels;
- subjects: an estimator whose ``fit`` takes ``groups`` receives them (the
  training rows' subjects, for subject-grouped inner cross-validation);
- one class: a training set with a single class gets no estimator; every
  prediction is that class (the caller notes it).

Threads are the caller's business (:func:`touchbench.core.threads.single_thread`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_memory

from ..core.errors import TouchbenchError
from ..core.introspect import accepts, sensor_problem
from ..features.base import FeatureStack, feature_set_refusal, learns_from_data, make_feature_set
from .base import make_classifier

__all__ = ["FittedEstimator", "FittedMethod", "capture_labels", "feature_specs", "fit_features", "fit_on_codes", "fit_pipeline",
           "label_codes", "labels_are_argmax", "pipeline_refusal", "proba_over"]


def label_codes(y: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(classes, codes)``: the sorted distinct values of ``y`` and each row's index into them."""
    classes, codes = np.unique(np.asarray(y), return_inverse=True)
    return classes, codes.astype(np.int64)


@dataclass
class FittedEstimator:
    """A fitted estimator with the labels its codes stand for (``estimator`` None: one class)."""

    classes: np.ndarray
    estimator: Any | None

    def predict(self, X: np.ndarray) -> np.ndarray:
        if self.estimator is None:
            return np.repeat(self.classes[:1], len(X))
        codes = np.asarray(self.estimator.predict(X)).astype(np.int64)
        return self.classes[codes]

    def predict_proba(self, X: np.ndarray) -> dict[str, np.ndarray] | None:
        """Probability of each training class (by label), or None when the estimator gives none."""
        if self.estimator is None:
            return {str(self.classes[0]): np.ones(len(X), dtype=np.float64)}
        if not hasattr(self.estimator, "predict_proba"):
            return None
        try:
            P = self.estimator.predict_proba(X)
        except Exception:  # probabilities are optional (e.g. an SVM without them)
            return None
        return self._by_label(P)

    def _by_label(self, P: Any) -> dict[str, np.ndarray]:
        P = np.asarray(P, dtype=np.float64)
        est_classes = getattr(self.estimator, "classes_", np.arange(P.shape[1]))
        return {str(self.classes[int(c)]): P[:, j] for j, c in enumerate(est_classes)}

    def predict_in_one_pass(self, X: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray] | None]:
        """The labels, and the probabilities when the same pass gives them: an estimator whose
        labels are the argmax of its probabilities (:func:`labels_are_argmax`) is asked once;
        any other is asked for its labels alone (probabilities None: ask :meth:`predict_proba`)."""
        est = self.estimator
        if est is None or not labels_are_argmax(est):
            return self.predict(X), None
        P = est.predict_proba(X)
        codes = np.asarray(est.classes_.take(np.argmax(P, axis=1), axis=0)).astype(np.int64)
        return self.classes[codes], self._by_label(P)


def labels_are_argmax(est: Any) -> bool:
    """Whether ``est.predict`` is ``classes_`` at the argmax of ``est.predict_proba``, computed the
    same way: scikit-learn's forests (their own ``predict``, one output) and an estimator that
    declares it (class attribute ``labels_are_argmax_proba``)."""
    from sklearn.ensemble._forest import ForestClassifier  # scikit-learn's private base of its forests

    if getattr(type(est), "labels_are_argmax_proba", False):
        return True
    return type(est).predict is ForestClassifier.predict and getattr(est, "n_outputs_", 1) == 1


def fit_on_codes(name: str, params: dict[str, Any], seed: int | None, X: Any, y: Any, groups: Any = None,
                 test_set: tuple[Any, Any] | None = None, **build: Any) -> FittedEstimator:
    """Build the registered estimator ``name`` (``random_state=seed``, ``params``, and ``build``
    keywords such as the sensor) and fit it on ``X`` and the codes of ``y`` (:func:`label_codes`);
    ``groups`` go to an estimator whose ``fit`` takes them. ``test_set``, ``(X_test, y_test)``: the
    leak of the audit's stopped-on-test variant, the test rows and their labels' codes (-1 for a
    label the training rows lack) given to the ``fit`` of an estimator that takes them (another is
    refused)."""
    classes, codes = label_codes(y)
    if len(classes) < 2:
        return FittedEstimator(classes, None)
    est = make_classifier(name, random_state=seed, **build, **params)
    fit_kw: dict[str, Any] = {"groups": np.asarray(groups)} if groups is not None and accepts(est.fit, "groups") else {}
    if accepts(est.fit, "class_names"):  # an estimator that names a class in its parameters (two-stage's idle)
        fit_kw["class_names"] = classes
    if test_set is not None:
        if not accepts(est.fit, "test_set"):
            raise TouchbenchError(f"{name!r} cannot stop early on the test data: its fit takes no test_set")
        y_test = np.asarray(test_set[1])
        known = np.isin(y_test, classes)
        fit_kw["test_set"] = (test_set[0], np.where(known, np.searchsorted(classes, y_test), -1))
    est.fit(X, codes, **fit_kw)
    return FittedEstimator(classes, est)


@dataclass
class FittedMethod:
    """A fitted method: its feature sets fitted on the training captures, its estimator on their
    columns (:class:`FittedEstimator`). What a task fits, a model file holds
    (:class:`touchbench.deploy.model.TrainedModel`), a :class:`touchbench.methods.FeaturePipeline`
    wraps and ``nested-select`` refits. ``feature_seconds`` and ``fit_seconds`` are what fitting
    took (NaN when the parts were fitted elsewhere)."""

    sets: list[Any]
    fitted: FittedEstimator
    feature_seconds: float = float("nan")
    fit_seconds: float = float("nan")
    _fast: Any = field(default=None, init=False, repr=False, compare=False)
    _stack: Any = field(default=None, init=False, repr=False, compare=False)

    @property
    def classes(self) -> np.ndarray:
        return self.fitted.classes

    @property
    def estimator(self) -> Any | None:
        return self.fitted.estimator

    def transform(self, captures: Any) -> Any:
        """The feature matrix of ``captures`` (the captures themselves without feature sets): one
        :class:`FeatureStack` of the fitted sets, kept, so the sets' parameters are checked once."""
        if not self.sets:
            return list(captures)
        if getattr(self, "_stack", None) is None:
            self._stack = FeatureStack(self.sets)
        return self._stack.transform(captures)

    def predict(self, captures: Any) -> np.ndarray:
        return self.fitted.predict(self.transform(captures))

    def predict_proba(self, captures: Any) -> dict[str, np.ndarray] | None:
        return self.fitted.predict_proba(self.transform(captures))

    def proba_rows(self, X: Any, fast: bool = True) -> np.ndarray:
        """``(n, C)`` probabilities of the rows ``X`` (features, or captures without feature sets),
        columns in the order of :attr:`classes`: what a live recogniser decides from.

        A classifier without ``predict_proba`` gives 1 for its predicted class. ``fast`` uses the
        flat-array forest walk for forests (same numbers as scikit-learn, :mod:`.fastforest`).
        """
        n, C = len(X), len(self.classes)
        est = self.estimator
        if est is None:
            return np.ones((n, 1))
        P = np.zeros((n, C), dtype=np.float64)
        if hasattr(est, "predict_proba"):
            compiled = self._compiled() if fast else None
            raw = compiled.predict_proba(X) if compiled else np.asarray(est.predict_proba(X), dtype=np.float64)
            codes = np.asarray(getattr(est, "classes_", np.arange(raw.shape[1]))).astype(np.int64)
            P[:, codes] = raw
        else:
            P[np.arange(n), np.asarray(est.predict(X)).astype(np.int64)] = 1.0
        return P

    def __getstate__(self) -> dict[str, Any]:
        """Everything but the compiled forest and the kept feature stack, built again when asked."""
        state = dict(self.__dict__)
        state.pop("_fast", None)
        state.pop("_stack", None)
        return state

    def _compiled(self) -> Any:
        """The estimator's flat-array forest (:mod:`.fastforest`), built once; None for another estimator."""
        if getattr(self, "_fast", None) is None:
            from .fastforest import compile_forest  # a private scikit-learn API: imported where used
            self._fast = compile_forest(self.estimator) or False
        return self._fast or None

    def window_proba(self, captures: Any, fast: bool = True) -> np.ndarray:
        """:meth:`proba_rows` of ``captures``' features."""
        return self.proba_rows(self.transform(captures), fast=fast)


def _fitted_set(name: str, params: dict[str, Any], sensor: Any, captures: Any, y: Any) -> tuple[Any, np.ndarray]:
    """A feature set fitted on ``captures`` and its output for them (what ``memory`` caches)."""
    fs = make_feature_set(name, dict(params), sensor)
    return fs, np.asarray(fs.fit(captures, y).transform(captures), dtype=np.float64)


def fit_pipeline(feature_sets: Any, estimator: str, params: dict[str, Any], seed: int | None, captures: Any, y: Any,
                 groups: Any = None, sensor: Any = None, memory: Any = None) -> FittedMethod:
    """Fit the feature sets ``[(name, params)...]`` (built with ``sensor``) on ``captures``, then the
    registered ``estimator`` on their columns through :func:`fit_on_codes`.

    ``memory`` (a folder or a :class:`joblib.Memory`, as scikit-learn's ``Pipeline(memory=...)``)
    caches what a feature set that learns nothing (``fold_dependent = False``) computes from its
    captures: fitting again on the same captures reads its matrix back instead of computing it.
    """
    t0 = time.perf_counter()
    sets, X = fit_features(feature_sets, captures, y, sensor, memory)
    t1 = time.perf_counter()
    fitted = fit_on_codes(estimator, params, seed, X, y, groups, sensor=sensor)
    return FittedMethod(sets, fitted, t1 - t0, time.perf_counter() - t1)


def fit_features(feature_sets: Any, captures: Any, y: Any, sensor: Any = None, memory: Any = None,
                 ) -> tuple[list[Any], Any]:
    """The feature sets ``[(name, params)...]`` fitted on ``captures`` and their stacked matrix (the
    captures themselves without feature sets); ``memory`` as :func:`fit_pipeline`'s."""
    cached = check_memory(os.fspath(memory) if isinstance(memory, os.PathLike) else memory).cache(_fitted_set)
    sets, blocks = [], []
    for name, set_params in feature_sets:
        if learns_from_data(name):
            fs, X_s = _fitted_set(name, set_params, sensor, captures, y)
        else:  # nothing learnt from the labels: cached by the captures alone
            fs, X_s = cached(name, set_params, sensor, captures, None)
        sets.append(fs)
        blocks.append(X_s)
    return sets, (np.hstack(blocks) if blocks else list(captures))


def capture_labels(y: Any, captures: list, name: str) -> np.ndarray:
    """``y`` as an array of classification targets, one per capture (a classifier that takes the
    captures, ``name``, refuses another count)."""
    y = np.asarray(y)
    check_classification_targets(y)
    if len(y) != len(captures):
        raise TouchbenchError(f"{name}: {len(y)} labels for {len(captures)} captures")
    return y


def feature_specs(entries: Any) -> list[tuple[str, dict[str, Any]]]:
    """Feature sets as ``[(name, params)...]`` from names, ``{name, params}`` mappings or
    ``[name, params]`` pairs (how a protocol or a Python user writes a pipeline's ``features``)."""
    sets = []
    for f in entries or []:
        if isinstance(f, str):
            sets.append((f, {}))
        elif isinstance(f, dict):
            sets.append((str(f["name"]), dict(f.get("params") or {})))
        else:
            name, params = f
            sets.append((str(name), dict(params or {})))
    return sets


def pipeline_refusal(feature_sets: Any, estimator: str, params: dict[str, Any], sensor: Any,
                     min_frames: int | None = None) -> str | None:
    """Why the pipeline ``feature_sets`` (``[(name, params)...]``) -> ``estimator`` (with ``params``)
    cannot serve ``sensor`` with captures from ``min_frames`` frames: its first feature set that
    refuses, else its estimator's reason; None when every part serves."""
    for name, set_params in feature_sets:
        problem = feature_set_refusal(name, set_params, sensor, min_frames)
        if problem:
            return problem
    return sensor_problem(make_classifier(estimator, random_state=0, sensor=sensor, **params), sensor, min_frames)


def proba_over(fitted: FittedEstimator, X: Any, classes: np.ndarray) -> np.ndarray:
    """``fitted``'s probabilities for the rows ``X`` as float64 columns of ``classes`` (sorted, a superset
    of its training classes): 0 for a class it never saw, one-hot of its prediction when its estimator
    gives no probabilities."""
    out = np.zeros((len(X), len(classes)), dtype=np.float64)
    by_label = fitted.predict_proba(X)
    if by_label is None:
        out[np.arange(len(X)), np.searchsorted(classes, fitted.predict(X))] = 1.0
        return out
    column = {str(c): j for j, c in enumerate(classes)}
    for label, p in by_label.items():
        out[:, column[label]] = p
    return out
