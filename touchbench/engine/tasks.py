"""One task: (repetition, fold, method) -> scores and predictions.

A task is independent of every other: it reads the dataset (shared,
read-only), the fold's indices and the feature cache, fits the combination's
fold-dependent feature sets and the classifier on the training fold only,
predicts the test fold and measures its timings. It returns one scores row
and one predictions table; it never raises for an error of the feature set
or classifier: that error becomes a ``failed`` row (the run goes on).

Determinism: the classifier's ``random_state`` is the task's ``seed``
(derived from the protocol seed and the task's identity), and every task
runs with BLAS / OpenMP / torch limited to one thread, so the predictions do
not depend on ``--jobs`` or on which worker ran the task.

A task evaluates one method: its feature sets (fold-independent ones from
the feature cache, fold-dependent ones fitted on the training fold) and its
estimator, fitted through :func:`touchbench.methods.fitting.fit_estimator`
(label codes, subjects as ``groups``, one-class folds), the same path
``touchbench train`` takes.
"""

from __future__ import annotations

import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd

from ..classifiers.adapt import adapt_each_session
from ..core.threads import available_cpus, single_thread
from ..datasets.model import TouchDataset
from ..features.base import make_feature_set
from ..methods import FittedMethod, Method
from ..methods.fitting import FittedEstimator, fit_estimator
from ..protocols.schemes import Fold, fold_notes
from ..results.manifest import load_average
from ..results.store import PREDICTED, PROBA_PREFIX, TRUE
from ..scoring.metrics import metrics
from ..streams.replay import LiveSpec
from .backends import run_setup
from .cache import FeatureCache, crop_captures
from .live import live_outcome

__all__ = ["RunContext", "SetSpec", "Task", "execute_task"]

#: the one-capture latency: the fold's first LATENCY_CAPTURES test captures, labelled one at a time in
#: turn after a warm-up, at least LATENCY_MIN_CALLS times and until LATENCY_BUDGET_S seconds were timed,
#: at most LATENCY_MAX_CALLS times: a fast method gets many calls, a slow one costs the run little
LATENCY_CAPTURES = 5
LATENCY_MIN_CALLS = 5
LATENCY_MAX_CALLS = 25
LATENCY_BUDGET_S = 0.05


@dataclass(frozen=True)
class SetSpec:
    """One feature set of a task's combination, with its cache keys."""

    name: str
    params: dict[str, Any]
    fold_dependent: bool
    key_full: str | None = None  # cache key of the uncut captures
    key_crop: str | None = None  # cache key of the cut captures (early scheme)


@dataclass(frozen=True)
class Task:
    """(evaluation, fold, method): the unit the engine runs and stores."""

    task_id: str
    repetition: int
    fold: Fold
    method: Method
    sets: tuple[SetSpec, ...]  # the method's feature sets with their cache keys
    seed: int
    crop_frames: int | None = None  # the fold's crop (``Fold.crop_frames``) at the sensor's frame rate
    measure_latency: bool = True  # the one task per method (and crop) of a run that measures latency
    base_row: dict[str, Any] = field(default_factory=dict)


class RunContext:
    """What every task shares: the dataset, its labels and the feature cache.

    Pickled for parallel workers without the dataset itself: a worker loads
    it once from ``dataset_path`` (a Parquet copy in the cache) and keeps it
    for the following tasks.
    """

    _loaded: dict[str, TouchDataset] = {}

    def __init__(self, dataset: TouchDataset, target: str, cache_root: Path, dataset_path: Path | None = None,
                 setup: Callable[[], None] | None = None):
        self.dataset_hash = dataset.content_hash
        self.dataset_path = dataset_path
        self.target = target
        self.cache_root = Path(cache_root)
        self.setup = setup
        self._dataset: TouchDataset | None = dataset
        self._labels: np.ndarray | None = None
        RunContext._loaded = {self.dataset_hash: dataset}  # keep one dataset per process

    def ensure_setup(self) -> None:
        """Run ``setup`` (e.g. registering plug-in components) once per process."""
        run_setup(self.setup)

    def __getstate__(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["_dataset"] = None
        d["_labels"] = None
        return d

    @property
    def dataset(self) -> TouchDataset:
        if self._dataset is None:
            ds = RunContext._loaded.get(self.dataset_hash)
            if ds is None:
                assert self.dataset_path is not None, "a worker needs the dataset's Parquet copy"
                ds = TouchDataset.from_parquet(self.dataset_path, verify=True)
                if ds.content_hash != self.dataset_hash:
                    raise RuntimeError(f"{self.dataset_path} holds another dataset than the run's")
                RunContext._loaded = {self.dataset_hash: ds}  # one dataset per worker
            self._dataset = ds
        return self._dataset

    @property
    def cache(self) -> FeatureCache:
        return FeatureCache(self.cache_root)

    def labels(self) -> np.ndarray:
        """The target of every capture, as text (computed once per context and process)."""
        if self._labels is None:
            self._labels = np.array([str(v) for v in self.dataset.meta[self.target].tolist()], dtype=object)
        return self._labels


# ----------------------------------------------------------------- metrics
# ----------------------------------------------------------------- features
def _fold_features(task: Task, ctx: RunContext, y_train: np.ndarray):
    """Training and test matrices of the task's combination, the fitted sets and timings.

    A method without feature sets (an estimator that takes captures) gets the
    fold's captures as recorded, in their native dtype (cut for the early scheme).
    """
    ds = ctx.dataset
    fold = task.fold
    crop_train = fold.crops_training()
    n = task.crop_frames
    if not task.sets:
        return (crop_captures([ds.captures[i] for i in fold.train], n if crop_train else None),
                crop_captures([ds.captures[i] for i in fold.test], n), [], 0.0, 0.0)
    train_caps = test_caps = None
    X_tr, X_te, fitted = [], [], []
    per_capture = 0.0
    fit_seconds = 0.0
    cache = ctx.cache
    for s in task.sets:
        if not s.fold_dependent:
            k_tr = s.key_crop if crop_train else s.key_full
            k_te = s.key_crop if n is not None else s.key_full
            got_tr = cache.load(k_tr)
            got_te = got_tr if k_te == k_tr else cache.load(k_te)
            if got_tr is None or got_te is None:
                raise RuntimeError(f"feature cache entry for {s.name!r} is missing (was the cache cleared during the run?)")
            X_tr.append(np.asarray(got_tr[0][fold.train], dtype=np.float64))
            X_te.append(np.asarray(got_te[0][fold.test], dtype=np.float64))
            per_capture += float(got_te[1].get("seconds_per_capture", np.nan))
            fitted.append(None)  # built lazily for the latency measurement
        else:
            if train_caps is None:
                train_caps = crop_captures([ds.captures[i] for i in fold.train], n if crop_train else None)
                test_caps = crop_captures([ds.captures[i] for i in fold.test], n)
            fs = make_feature_set(s.name, s.params, ds.sensor)
            t0 = time.perf_counter()
            fs.fit(train_caps, y_train)
            fit_seconds += time.perf_counter() - t0
            X_tr.append(np.asarray(fs.transform(train_caps), dtype=np.float64))
            t0 = time.perf_counter()
            X_te.append(np.asarray(fs.transform(test_caps), dtype=np.float64))
            per_capture += (time.perf_counter() - t0) / max(1, len(test_caps))
            fitted.append(fs)
    return np.hstack(X_tr), np.hstack(X_te), fitted, per_capture, fit_seconds


def _latency_sets(task: Task, ctx: RunContext, fitted: list, y_train: np.ndarray) -> list:
    """Fitted feature sets for one-capture latency (fold-independent ones fitted on a few captures)."""
    ds = ctx.dataset
    out = []
    for s, fs in zip(task.sets, fitted):
        if fs is None:
            fs = make_feature_set(s.name, s.params, ds.sensor)
            few = [ds.captures[i] for i in task.fold.train[:2]]
            fs.fit(few, y_train[:2])
        out.append(fs)
    return out


def _measure_latency(method: FittedMethod, captures: list[np.ndarray]) -> tuple[float, float]:
    """Median milliseconds for ``method`` to label one capture (features + predict), wall-clock and
    CPU time of the labelling thread (which other processes' load changes far less): ``captures``
    in turn, one at a time, after one warm-up call; at least ``LATENCY_MIN_CALLS`` calls and until
    ``LATENCY_BUDGET_S`` wall-clock seconds were timed, at most ``LATENCY_MAX_CALLS``."""
    method.predict([captures[0]])
    wall: list[float] = []
    cpu: list[float] = []
    while len(wall) < LATENCY_MAX_CALLS and (len(wall) < LATENCY_MIN_CALLS or sum(wall) < LATENCY_BUDGET_S):
        capture = captures[len(wall) % len(captures)]
        t0, c0 = time.perf_counter(), time.thread_time_ns()
        method.predict([capture])
        cpu.append((time.thread_time_ns() - c0) / 1e9)
        wall.append(time.perf_counter() - t0)
    return 1000.0 * float(np.median(wall)), 1000.0 * float(np.median(cpu))


def _with_subject_id(ds: TouchDataset, fold: Fold, X_tr: np.ndarray, X_te: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The leaky variant's matrices: each row's subject, one-hot over the dataset's subjects, appended."""
    subjects = ds.meta["subject"].astype(str).to_numpy()
    onehot = (subjects[:, None] == np.unique(subjects)[None, :]).astype(np.float64)
    return np.hstack([X_tr, onehot[fold.train]]), np.hstack([X_te, onehot[fold.test]])


def _predictions(task: Task, ds: TouchDataset, y_test: np.ndarray, y_pred: np.ndarray,
                 proba: dict[str, np.ndarray] | None) -> pd.DataFrame:
    """The task's predictions table: one row per test capture, ``proba_<class>`` columns last (classes
    sorted), built in one go."""
    fold = task.fold
    meta = ds.meta.iloc[fold.test]
    columns: dict[str, Any] = {
        "task_id": task.task_id,
        "repetition": task.repetition,
        "fold": fold.name,
        "fold_group": fold.group,
        "early_frames": np.float64(task.crop_frames) if task.crop_frames is not None else np.nan,
        "features": task.method.features_label,
        "classifier": task.method.label,
        "capture_id": meta["capture_id"].astype(str).to_numpy(),
        "subject": meta["subject"].astype(str).to_numpy(),
        "gesture": meta["gesture"].astype(str).to_numpy(),
        TRUE: y_test.astype(str),
        PREDICTED: y_pred.astype(str),
        "correct": (y_test.astype(str) == y_pred.astype(str)),
    }
    for label in sorted(proba or {}):
        columns[f"{PROBA_PREFIX}{label}"] = proba[label]
    return pd.DataFrame(columns)


def _adapted_predictions(fitted: FittedEstimator, X_te: np.ndarray,
                         sessions: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray] | None]:
    """An adapted method's labels and probabilities of the test rows (None when its estimator gives
    none): the estimator is adapted to each session's rows (``sessions``: each test row's subject),
    unlabelled, before they are predicted (:func:`touchbench.classifiers.adapt.adapt_each_session`)."""
    y_pred = np.empty(len(X_te), dtype=object)
    proba: dict[str, np.ndarray] = {}
    for rows in adapt_each_session(fitted.estimator, X_te, sessions):
        part, p = fitted.predict_in_one_pass(X_te[rows])
        y_pred[rows] = part
        for label, v in (p if p is not None else fitted.predict_proba(X_te[rows]) or {}).items():
            proba.setdefault(label, np.full(len(X_te), np.nan))[rows] = v
    return y_pred, proba or None


def _capture_outcome(task: Task, ctx: RunContext, row: dict[str, Any], notes: list[str]):
    """Fit the task's method on the fold's training captures and label its test captures: ``(labels,
    probabilities or None)``; the measurements go into ``row``, what the method chose into ``notes``."""
    ds = ctx.dataset
    y = ctx.labels()
    fold = task.fold
    y_train, y_test = y[fold.train], y[fold.test]
    X_tr, X_te, fitted, per_capture, feat_fit = _fold_features(task, ctx, y_train)
    if task.method.subject_id_feature:
        X_tr, X_te = _with_subject_id(ds, fold, X_tr, X_te)
    row["feature_seconds_per_capture"] = per_capture
    row["feature_fit_seconds"] = feat_fit
    groups = ds.meta["subject"].to_numpy()[fold.train]
    t0 = time.perf_counter()
    spec = task.method.spec
    test_set = (X_te, y_test) if task.method.stopped_on_test else None  # the audit's leak: stopped on test
    fitted_est = fit_estimator(spec.estimator, spec.estimator_params, task.seed, X_tr, y_train, groups,
                               test_set=test_set, sensor=ds.sensor)
    row["fit_seconds"] = time.perf_counter() - t0 if fitted_est.estimator is not None else 0.0
    row["n_classes_train"] = int(len(fitted_est.classes))
    est = fitted_est.estimator
    t0 = time.perf_counter()
    if task.method.adaptation and est is not None:  # adapted to each test subject's captures, unlabelled
        y_pred, proba = _adapted_predictions(fitted_est, X_te, ds.meta["subject"].to_numpy()[fold.test])
    else:
        y_pred, proba = fitted_est.predict_in_one_pass(X_te)  # probabilities too where the same pass gives them
    row["predict_seconds"] = time.perf_counter() - t0
    if getattr(est, "selection_note_", None):  # a method that searched inside the training fold says what it chose
        notes.append(est.selection_note_)
    if proba is None and est is not None and not task.method.adaptation:
        proba = fitted_est.predict_proba(X_te)
    row.update(metrics(y_test, y_pred))
    if task.measure_latency:  # once per method and run: features + predict of one capture
        lat_sets = _latency_sets(task, ctx, fitted, y_train)
        caps = [ds.captures[int(i)][: task.crop_frames] if task.crop_frames is not None else ds.captures[int(i)]
                for i in fold.test[:LATENCY_CAPTURES]]
        row["latency_ms"], row["latency_cpu_ms"] = _measure_latency(FittedMethod(lat_sets, fitted_est), caps)
    return y_pred, proba


# ----------------------------------------------------------------- the task
def execute_task(task: Task, ctx: RunContext) -> tuple[dict[str, Any], pd.DataFrame | None]:
    """Run one task; a feature or classifier error becomes a ``failed`` row."""

    ctx.ensure_setup()
    row = dict(task.base_row)  # the planned row, every measurement still empty
    ds = ctx.dataset
    y = ctx.labels()
    fold = task.fold
    y_train, y_test = y[fold.train], y[fold.test]
    notes = list(fold.notes) + fold_notes(fold, y)
    preds = None
    try:
        with single_thread(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if fold.extra(LiveSpec) is not None:  # a stream fold: trained once, every test stream replayed
                values, y_pred, row["live"] = live_outcome(task, ds, y)
                row.update(values)
                row.update(metrics(y_test, y_pred))
                proba = None
            else:
                y_pred, proba = _capture_outcome(task, ctx, row, notes)
        preds = _predictions(task, ds, y_test, y_pred, proba)
    except Exception as e:  # the task fails, the run goes on
        tb = traceback.format_exc(limit=-3)
        row["status"] = "failed"
        row["error"] = f"{type(e).__name__}: {e}\n{tb}"
        preds = None
    row["notes"] = "; ".join(dict.fromkeys(notes))
    row["load_avg"], row["usable_cpus"] = load_average(), available_cpus()  # how busy the machine was
    row["finished_at"] = pd.Timestamp.now(tz="UTC").isoformat()
    return row, preds

