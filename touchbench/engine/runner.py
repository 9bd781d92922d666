"""The run engine: protocol -> plan of tasks -> parallel execution -> reports.

``plan_run`` does every check that needs the data before any work: it loads
the dataset, applies the protocol's filters (unknown columns or values are
refused with the protocol line), checks the target, builds the folds of every
repetition (a scheme that cannot be evaluated is refused with the scheme's
message) and turns (repetition x fold x feature combination x classifier)
into :class:`touchbench.engine.tasks.Task` objects with stable ids.

``run_plan`` then

1. skips finished tasks (their scores fragment exists; ``force`` recomputes,
   ``retry_failed`` reruns failed ones),
2. computes the fold-independent features of the pending tasks once, into
   the on-disk feature cache (``engine.cache``),
3. runs the pending tasks, in parallel with joblib when ``jobs > 1``, each
   result written as soon as it arrives (one atomic fragment per task),
4. merges the fragments into ``scores`` / ``predictions`` / ``confusion``
   and writes ``manifest.json``.

A rerun of a finished run loads the dataset, rebuilds the plan, sees that
every task is finished and the reports are current, and does nothing else.

Identity and seeds: a task id is a hash of everything that determines its
result: the dataset's content hash (recomputed from the data when it is
loaded), target, scheme and its parameters, repetition, fold name and
indices, the feature sets and the classifier with their parameters and
their identities (:mod:`touchbench.engine.identity`: the source of their
modules and of the helper modules these import, touchbench's or the user's,
and the versions of the third-party packages they import), and the protocol
seed. Editing a component's code, or a helper it imports, recomputes exactly
the tasks that use it. The run id is a hash of the protocol, the dataset and
the task ids. The classifier's ``random_state`` is
``derive_seed(seed, "task", repetition, fold, features, classifier)``.
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Sequence

import numpy as np
import pandas as pd
from joblib import delayed
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from ..classifiers import make_classifier
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.introspect import sensor_problem
from ..core.paths import cache_dir
from ..core.suggest import did_you_mean
from ..datasets.model import DatasetChangedWarning, SensorSpec, TouchDataset
from ..features import FEATURES
from ..features.base import feature_set_refusal
from ..methods import METHODS, MethodSpec, expand_candidates, method_spec, resolve_entry
from ..protocols.schema import Protocol, expand_grid, load_protocol, resolve_dataset_ref
from ..protocols.seeding import derive_seed
from ..protocols.schemes import SplitError
from ..results.ledger import LEDGER_NAME, check_final, record_look, test_set_hash
from ..results.manifest import LEFT_OUT, now_iso, update_manifest
from ..results.store import PREDICTED, SCHEMA_VERSION, TRUE, ResultStore, check_schema, read_results_table
from ..results.summary import check_expected, summarize
from .backends import check_jobs, is_local_backend, local_jobs, parallel
from .cache import FeatureCache, crop_captures
from .evaluation_data import apply_filters, evaluation_dataset, load_spec
from .identity import MAX_MODULES, Identity, classifier_identity, feature_set_identity
from .tasks import RunContext, SetSpec, Task, execute_task, make_feature_set

__all__ = ["Plan", "RunResult", "check_sensor_fit", "sensor_refusals", "default_ledger", "default_results_dir", "method_labels", "plan_run", "plan_test_set",
           "results_dirs", "run_plan", "run_protocol"]


def default_results_dir(protocol: Protocol) -> Path:
    """``results/<protocol name>/`` under the current directory (``results/<protocol name>/<evaluation>/``
    for one evaluation of a protocol with several)."""
    root = Path("results") / protocol.name
    return root / protocol.evaluation if protocol.evaluation else root


@dataclass
class Plan:
    protocol: Protocol
    dataset: TouchDataset
    dataset_ref: str
    source_hash: str
    tasks: list[Task]
    notes: list[str]
    run_id: str
    cache_root: Path
    n_folds: int = 0
    #: the identity of every component the tasks use, by label ("feature set msd {...}")
    identities: dict[str, Identity] = field(default_factory=dict)

    @property
    def package_versions(self) -> dict[str, str | None]:
        """Every package version that entered a task id (the union over the components)."""
        out: dict[str, str | None] = {}
        for ident in self.identities.values():
            out.update(ident.packages)
        return dict(sorted(out.items()))

    @property
    def leakages(self) -> list[str]:
        """The distinct reasons the plan's tasks leak (empty when every task is honest)."""
        return sorted({t.base_row.get("leakage", "") for t in self.tasks} - {""})

    @property
    def task_ids(self) -> list[str]:
        return [t.task_id for t in self.tasks]

    @property
    def ids_hash(self) -> str:
        return hashlib.sha256("\n".join(self.task_ids).encode()).hexdigest()[:16]


@dataclass
class RunResult:
    out: Path
    run_id: str
    n_tasks: int
    n_ran: int
    n_skipped: int
    n_failed: int
    noop: bool
    seconds: float
    scores: pd.DataFrame
    summary: pd.DataFrame
    expected: list[dict[str, Any]]
    notes: list[str] = field(default_factory=list)
    #: ``fail_fast`` stopped the run at its first failed task (the other pending tasks did not run)
    stopped_early: bool = False


# ----------------------------------------------------------------- planning
def _label(kind: str, name: str, params: dict[str, Any]) -> str:
    return f"{kind} {name}" + (f" {canonical_json(params)}" if params else "")


def _spec_index(protocol: Protocol, name: str) -> int:
    """The index in ``classifiers:`` of the first entry named ``name`` (for error locations)."""
    return next((i for i, s in enumerate(protocol.classifiers) if s.name == name), 0)


def _whole_captures_note(clf: Any, sets: Any, ds: TouchDataset) -> str | None:
    """Beside a named method, ``[raw-window]`` stands for the captures as recorded: a note when
    its parameters would have cut or padded them (they are not applied)."""
    frames = dict(sets[0][1]).get("frames")
    lo, hi = int(ds.n_frames.min()), int(ds.n_frames.max())
    if frames is not None and (lo != int(frames) or hi != int(frames)):
        return (f"method {clf.name!r} takes the captures as recorded ({lo}..{hi} frames); the frames={frames} "
                f"of raw-window beside it is not applied")
    return None


def sensor_refusals(protocol: Protocol, sensor: SensorSpec, min_frames: int) -> list[tuple[tuple, str]]:
    """Every component of the protocol that cannot serve ``sensor``: ``(field, message)`` pairs.

    Every feature set and classifier (with each of its parameter settings)
    is built with the sensor and asked (:func:`touchbench.core.introspect.sensor_problem`);
    ``min_frames`` is the shortest capture a task will see. One pair per
    entry (feature combination, classifier or method), its first reason.
    """
    out: list[tuple[tuple, str]] = []
    for i, combo in enumerate(protocol.features):
        problem = _sets_refusal(combo, ("features", i), sensor, min_frames)
        if problem:
            out.append(problem)
    refused_methods = set()
    for j, m in enumerate(protocol.methods):
        problem = _sets_refusal(m.features or [], ("methods", j, "features"), sensor, min_frames)
        if problem:
            out.append(problem)
            refused_methods.add(j)
    specs = [(("classifiers", i), s.name, s.params) for i, s in enumerate(protocol.classifiers)]
    specs += [(("methods", i), m.name or m.estimator, m.params) for i, m in enumerate(protocol.methods)
              if i not in refused_methods]
    for loc, name, params in specs:
        problem = _classifier_refusal(name, params, sensor, min_frames)
        if problem:
            out.append((loc, problem))
    return out


def _sets_refusal(refs: Sequence[Any], field: tuple, sensor: SensorSpec, min_frames: int) -> tuple[tuple, str] | None:
    """The first feature set of ``refs`` (any of its parameter settings) that cannot serve ``sensor``:
    its protocol field (``field`` + its index) and the message, or None."""
    for k, ref in enumerate(refs):
        for p in expand_grid(ref.params):
            problem = sensor_problem(make_feature_set(ref.name, p, sensor), sensor, min_frames)
            if problem:
                return (*field, k), f"feature set {ref.name!r} cannot serve sensor {sensor.describe()}: {problem}"
    return None


def _classifier_refusal(name: str, params: dict, sensor: SensorSpec, min_frames: int) -> str | None:
    """Why the classifier or named method ``name`` (any of its parameter settings) cannot serve ``sensor``."""
    for p in expand_grid(params):
        spec_name = name
        if name in METHODS:  # a named method: its own feature sets, then its estimator
            m = method_spec(name, **p)
            for set_name, set_params in m.feature_sets:
                problem = feature_set_refusal(set_name, set_params, sensor, min_frames)
                if problem:
                    return f"method {name!r} cannot serve sensor {sensor.describe()}: {problem}"
            spec_name, p = m.estimator, m.estimator_params
        try:
            p = expand_candidates(spec_name, p)
            est = make_classifier(spec_name, random_state=0, sensor=sensor, **p)
        except Exception as e:
            return f"classifier {name!r} rejects {p}: {type(e).__name__}: {e}"
        problem = sensor_problem(est, sensor, min_frames)
        if problem:
            return f"classifier {name!r} cannot serve sensor {sensor.describe()}: {problem}"
    return None


def check_sensor_fit(protocol: Protocol, sensor: SensorSpec, min_frames: int) -> None:
    """Refuse the protocol when one of its components cannot serve ``sensor`` (:func:`sensor_refusals`):
    the first such component, with one message naming it, the sensor and its reason."""
    refusals = sensor_refusals(protocol, sensor, min_frames)
    if refusals:
        raise protocol.error_at(*refusals[0])


def without_refused(protocol: Protocol, refusals: list[tuple[tuple, str]]) -> Protocol:
    """``protocol`` without the entries ``refusals`` name (a feature combination, classifier or method)."""
    drop: dict[str, set[int]] = {"features": set(), "classifiers": set(), "methods": set()}
    for loc, _ in refusals:
        drop[loc[0]].add(int(loc[1]))
    update = {k: [x for i, x in enumerate(getattr(protocol, k)) if i not in drop[k]] for k in drop}
    return protocol.model_copy(update=update)


def plan_run(protocol: Protocol, cache_root: str | Path | None = None, dataset: TouchDataset | None = None) -> Plan:
    """Every check that needs the data, then the list of tasks (no work done)."""

    cache_root = Path(cache_root) if cache_root is not None else cache_dir() / "features"
    notes: list[str] = []
    full = dataset if dataset is not None else load_spec(protocol, protocol.dataset, ("dataset",), notes)
    ds = evaluation_dataset(protocol, apply_filters(protocol, full), notes)
    target = protocol.target
    if target not in ds.meta.columns:
        cols = sorted(c for c in ds.meta.columns if c != "capture_id")
        raise protocol.error_at(("target",), f"the dataset has no {target!r} column{did_you_mean(target, cols)} "
                                             f"(its metadata columns: {', '.join(cols)})")
    if ds.meta[target].isna().any():
        raise protocol.error_at(("target",), f"{int(ds.meta[target].isna().sum())} captures have no {target!r} value")
    classes = sorted({str(v) for v in ds.meta[target]})
    if len(classes) < 2:
        raise protocol.error_at(("target",), f"after the filters the target {target!r} has a single value {classes}: nothing to classify")

    # feature sets must build with their parameters and this dataset's sensor
    for i, combo in enumerate(protocol.features):
        for j, ref in enumerate(combo):
            for p in expand_grid(ref.params):
                try:
                    make_feature_set(ref.name, p, ds.sensor)
                except Exception as e:
                    raise protocol.error_at(("features", i, j), f"feature set {ref.name!r} rejects {p}: {type(e).__name__}: {e}") from None

    entries = protocol.entries()
    # each (combination, classifier) entry is a method: the combination's sets -> the classifier,
    # or a named method's own sets -> its estimator (the combination is then [raw-window])
    methods: dict[int, MethodSpec] = {}
    for ei, (c, clf) in enumerate(entries):
        try:
            methods[ei] = resolve_entry(c.sets, clf.name, clf.params)
        except TouchbenchError as e:
            raise protocol.error_at(("classifiers", _spec_index(protocol, clf.name)), str(e)) from None
        note = _whole_captures_note(clf, c.sets, ds) if clf.name in METHODS else None
        if note:
            notes.append(note)
    identities: dict[str, Identity] = {}
    set_info: dict[tuple, tuple[bool, str]] = {}
    clf_info: dict[tuple, str] = {}
    for m in methods.values():
        for name, params in m.feature_sets:
            k = (name, canonical_json(params))
            if k not in set_info:
                ident = identities[_label("feature set", name, params)] = feature_set_identity(name, params)
                set_info[k] = (bool(getattr(FEATURES.get(name), "fold_dependent", True)), ident.digest)
        k = (m.estimator, canonical_json(m.estimator_params))
        if k not in clf_info:
            ident = identities[_label("classifier", m.estimator, m.estimator_params)] = classifier_identity(
                m.estimator, m.estimator_params)
            clf_info[k] = ident.digest
    for label, ident in identities.items():
        if ident.incomplete:
            notes.append(f"the {label} imports more than {MAX_MODULES} modules of its own: "
                         "edits beyond the first ones found are not noticed (use --force after editing them)")

    scheme_leak = protocol.splitter(0).leakage()
    for ei, (c, clf) in enumerate(entries):
        if clf.subject_id_feature and not methods[ei].feature_sets:
            raise protocol.error_at(("methods",), f"{clf.label!r}: subject_id_feature needs a feature matrix; "
                                                  f"{methods[ei].estimator!r} takes the captures themselves")
    tasks: list[Task] = []
    timed: set[tuple] = set()  # methods (and crops) whose latency task is chosen: the first in plan order
    n_folds = 0
    scheme_json = canonical_json({"name": protocol.scheme.name, **protocol.scheme.params})
    for r in range(protocol.repetitions):
        splitter = protocol.splitter(r)
        try:
            folds = splitter.folds(ds.meta)
        except SplitError as e:
            raise protocol.error_at(("scheme",), str(e)) from None
        prefix = f"repetition {r}: " if protocol.repetitions > 1 else ""
        notes += [prefix + n for n in splitter.notes_]
        n_folds += len(folds)
        for fold in folds:
            crop_frames = fold.crop.n_frames(ds.sensor.frame_rate) if fold.crop is not None else None
            idx_hash = hashlib.sha256(fold.train.tobytes() + b"|" + fold.test.tobytes()).hexdigest()[:16]
            for ei, (combo, clf) in enumerate(entries):
                method = methods[ei]
                sets = []
                for name, params in method.feature_sets:
                    dep, ver = set_info[(name, canonical_json(params))]
                    sets.append(SetSpec(
                        name=name, params=params, fold_dependent=dep,
                        key_full=None if dep else FeatureCache.key(ds.content_hash, name, params, ver, None),
                        key_crop=None if dep or crop_frames is None else FeatureCache.key(ds.content_hash, name, params, ver, crop_frames),
                    ))
                estimator = [method.estimator, method.estimator_params,
                             clf_info[(method.estimator, canonical_json(method.estimator_params))]]
                identity = {
                    "dataset": ds.content_hash, "target": target, "scheme": scheme_json, "repetition": r,
                    "fold": fold.name, "indices": idx_hash, "crop": [crop_frames, bool(fold.crop and fold.crop.train)],
                    "features": [[n, p, set_info[(n, canonical_json(p))][1]] for n, p in method.feature_sets],
                    "classifier": [clf.name, method.estimator_params, *estimator[2:]] if clf.name == method.estimator
                    else [clf.name, clf.params, estimator],
                    "seed": protocol.seed,
                }
                if clf.subject_id_feature:  # only then: the ids of every other task stay as they were
                    identity["subject_id_feature"] = True
                task_id = hashlib.sha256(canonical_json(identity).encode()).hexdigest()[:20]
                seed = derive_seed(protocol.seed, "task", r, fold.name, combo.label, clf.label)
                base = {
                    "task_id": task_id, "protocol": protocol.name, "dataset": protocol.dataset.name,
                    "dataset_hash": ds.content_hash, "target": target, "scheme": protocol.scheme.name,
                    "repetition": r, "fold": fold.name, "fold_group": fold.group,
                    "early_frames": np.float64(crop_frames) if crop_frames is not None else np.nan,
                    "features": combo.label, "feature_sets": "+".join(method.feature_names),
                    "feature_params": canonical_json([[n, p] for n, p in method.feature_sets]),
                    "classifier": clf.label, "classifier_name": clf.name,
                    "classifier_params": canonical_json(clf.params), "seed": seed,
                    "n_train": int(len(fold.train)), "n_test": int(len(fold.test)),
                    "leakage": "; ".join(x for x in [scheme_leak, *clf.leakage] if x),
                    "selection": clf.tuned_on_test,
                }
                tasks.append(Task(
                    task_id=task_id, repetition=r, fold=fold, features_label=combo.label, sets=tuple(sets),
                    classifier_label=clf.label, classifier_name=clf.name, classifier_params=clf.params,
                    seed=seed, crop_frames=crop_frames, base_row=base,
                    estimator_name=method.estimator, estimator_params=method.estimator_params,
                    measure_latency=(combo.label, clf.label, crop_frames) not in timed and not clf.subject_id_feature,
                    subject_id_feature=clf.subject_id_feature,
                ))
                timed.add((combo.label, clf.label, crop_frames))
    crops = [t.crop_frames for t in tasks if t.crop_frames is not None]
    min_frames = int(min([int(ds.n_frames.min()), *crops]))
    refusals = sensor_refusals(protocol, ds.sensor, min_frames)
    if refusals:
        # one of several evaluations: what cannot serve this evaluation's sensor is left out of it, said;
        # a protocol of one evaluation (or one left with nothing) is refused
        reduced = without_refused(protocol, refusals) if protocol.evaluation else None
        if reduced is None or not reduced.entries():
            raise protocol.error_at(*refusals[0])
        plan = plan_run(reduced, cache_root=cache_root, dataset=full)
        plan.notes[:0] = [f"{LEFT_OUT}{protocol.evaluation!r}: {msg}" for _, msg in refusals]
        return plan
    ids = [t.task_id for t in tasks]
    if len(set(ids)) != len(ids):
        raise protocol.error_at(("features",), "two entries of the protocol describe the same task (duplicate combination or classifier)")
    # The run is the set of its tasks: a change of protocol, data, component source or
    # package version that changes any task gives another run id.
    run_id = hashlib.sha256(canonical_json(
        {"protocol": protocol.content_hash, "dataset": ds.content_hash,
         "tasks": hashlib.sha256("\n".join(ids).encode()).hexdigest()}).encode()).hexdigest()[:12]
    return Plan(protocol=protocol, dataset=ds, dataset_ref=resolve_dataset_ref(protocol), source_hash=full.content_hash,
                tasks=tasks, notes=list(dict.fromkeys(notes)), run_id=run_id, cache_root=cache_root, n_folds=n_folds,
                identities=identities)


# ----------------------------------------------------------------- progress
class _Progress:
    """A rich progress bar on a terminal; silent otherwise."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self._p = None

    def __enter__(self) -> "_Progress":
        if self.enabled:

            self._p = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                               TimeElapsedColumn(), TimeRemainingColumn(), console=Console(stderr=True), transient=False)
            self._p.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self._p is not None:
            self._p.__exit__(*exc)

    def add(self, description: str, total: int):
        return self._p.add_task(description, total=total) if self._p is not None else None

    def advance(self, tid, n: int = 1) -> None:
        if self._p is not None and tid is not None:
            self._p.advance(tid, n)


# ----------------------------------------------------------------- running
def _fill_cache(plan: Plan, pending: list[Task], jobs: int, progress: _Progress, setup=None) -> list[str]:
    """Compute the missing (or damaged) feature cache entries of ``pending``; notes on damaged ones."""
    ds = plan.dataset
    notes: list[str] = []
    cache = FeatureCache(plan.cache_root)
    needed: dict[str, tuple[str, dict, int | None]] = {}
    for t in pending:
        crop_train = t.fold.crop is not None and t.fold.crop.train
        for s in t.sets:
            if s.fold_dependent:
                continue
            if not crop_train:
                needed.setdefault(s.key_full, (s.name, s.params, None))
            if s.key_crop is not None:
                needed.setdefault(s.key_crop, (s.name, s.params, t.crop_frames))
    for key, (name, params, crop) in needed.items():
        problem = cache.problem(key)
        if problem is None:
            continue
        caps = crop_captures(ds.captures, crop)
        label = name + (f" (first {crop} frames)" if crop is not None else "")
        if problem != "missing":
            notes.append(f"the cached features of {label} were not used ({problem}): computed again")
        tid = progress.add(f"features {label}", len(caps))
        cache.compute(
            key, partial(make_feature_set, name, params, ds.sensor), caps, jobs=jobs,
            info={"dataset_hash": ds.content_hash, "name": name, "params": params, "crop": crop},
            on_chunk=lambda n, tid=tid: progress.advance(tid, n), setup=setup,
        )
    return notes


def _dataset_copy(plan: Plan) -> Path:
    """A Parquet copy of the (filtered) dataset for parallel workers."""
    path = plan.cache_root.parent / "engine-datasets" / f"{plan.dataset.content_hash[:32]}.parquet"
    if path.is_file():
        try:
            TouchDataset.from_parquet(path, verify=True)
            return path
        except TouchbenchError:  # damaged: written again below
            pass
    plan.dataset.to_parquet(path)
    return path


def _reports_current(store: ResultStore, plan: Plan, notes: list[str]) -> bool:
    """The merged files are those of this plan, as the last merge wrote them (a damaged or edited
    one adds a note: they are rebuilt from the fragments)."""
    m = store.read_manifest()
    if not m:
        return False
    if m.get("run", {}).get("run_id") != plan.run_id or m.get("tasks", {}).get("ids_hash") != plan.ids_hash:
        return False
    if m.get("tasks", {}).get("merged") != len(plan.tasks):
        return False
    version = check_schema(m.get("results_schema"), store.manifest_path)
    if version < SCHEMA_VERSION:
        notes.append(f"the merged files have the layout of results schema {version}: merged again in schema "
                     f"{SCHEMA_VERSION}")
        return False
    problems = store.merged_problems(m.get("tasks", {}).get("merged_files"))
    if problems:
        notes.append("; ".join(problems) + ": merged again from the results of each task")
        return False
    return True


def _damaged_notes(plan: Plan, problems: dict[str, str]) -> list[str]:
    """A note per task of the plan whose saved results could not be trusted (run again)."""
    by_id = {t.task_id: t for t in plan.tasks}
    return [f"the saved results of {t.features_label} | {t.classifier_label}, fold {t.fold.name} (repetition "
            f"{t.repetition}) were not used: {problems[tid]}; run again"
            for tid, t in by_id.items() if tid in problems]


def default_ledger(protocol: Protocol, out: str | Path) -> Path:
    """The ledger of the results root: the parent of the protocol's results folder (which holds one
    folder per evaluation when the protocol has several)."""
    folder = Path(out).parent if protocol.evaluation else Path(out)
    return folder.parent / LEDGER_NAME


def plan_test_set(plan: Plan) -> str:
    """The hash of every capture some task of the plan tests (:func:`touchbench.results.ledger.test_set_hash`)."""
    idx = sorted({int(i) for t in plan.tasks for i in t.fold.test})
    ds = plan.dataset
    return test_set_hash([ds.captures[i] for i in idx], ds.meta[plan.protocol.target].astype(str).to_numpy()[idx])


def plan_methods(plan: Plan) -> list[str]:
    """The methods a plan evaluates, as ``features / classifier`` labels."""
    return sorted({f"{t.features_label} / {t.classifier_label}" for t in plan.tasks})


def run_plan(plan: Plan, out: str | Path | None = None, *, jobs: int = 1, force: bool = False,
             retry_failed: bool = False, progress: bool | None = None, worker_setup=None,
             wait: float = 0.0, fail_fast: bool = False, final: bool = False, force_final: bool = False,
             ledger: str | Path | None = None, methods: Sequence[str] | None = None) -> RunResult:
    """Execute the pending tasks of ``plan`` and write the reports (see the module docstring).

    ``methods`` (classifier or method labels of the plan) runs only their tasks: the tables
    still hold every finished task of the plan, the others stay pending (a slow method can
    wait, a new one can join a finished run).

    ``worker_setup`` is a picklable function each worker process calls once
    before its first task (to register plug-in components in the workers).
    One run at a time writes a results folder: another run holding ``out`` is
    waited for up to ``wait`` seconds, then refused with who holds it.
    ``fail_fast`` stops at the first task that fails: the tasks finished so
    far are kept and merged, the others are left pending.

    A run that scores its test set (a task to run, or ``final``) is recorded
    in ``ledger`` (default: :func:`default_ledger`) before any task;
    ``final`` marks the run to report and is refused when the test set had
    a final run with other methods, unless ``force_final``
    (:func:`touchbench.results.ledger.check_final`).
    """
    out = Path(out) if out is not None else default_results_dir(plan.protocol)
    store = ResultStore(out)
    ledger = Path(ledger) if ledger is not None else default_ledger(plan.protocol, out)
    only = check_methods(plan, methods)
    with store.lock(wait=wait, command=f"touchbench run {plan.protocol.name}"):
        return _run_locked(plan, store, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                           worker_setup=worker_setup, fail_fast=fail_fast, final=final, force_final=force_final,
                           ledger=ledger, methods=only)


def method_labels(plan: Plan) -> list[str]:
    """The method labels (``--method``'s values) of ``plan``'s tasks, in plan order."""
    return list(dict.fromkeys(t.classifier_label for t in plan.tasks))


def check_methods(plan: Plan, methods: Sequence[str] | None) -> set[str] | None:
    """The method labels ``methods`` names in ``plan`` (None: all); an unknown one is refused naming the known."""
    if not methods:
        return None
    known = method_labels(plan)
    unknown = [m for m in methods if m not in known]
    if unknown:
        raise TouchbenchError(f"{unknown[0]!r} is not a method of {plan.protocol.name}"
                              + (f" / {plan.protocol.evaluation}" if plan.protocol.evaluation else "")
                              + f" (its methods: {', '.join(known)})")
    return set(methods)


def _design_captures(plan: Plan) -> list[str] | None:
    """The ids of the captures the protocol's ``design`` names (None without one)."""
    design = plan.protocol.design
    if design is None:
        return None
    meta = plan.dataset.meta
    keep = np.ones(len(meta), dtype=bool)
    for col, values in design.filters().items():
        if col not in meta.columns:
            raise plan.protocol.error_at(("design",), f"the dataset has no metadata column {col!r}")
        keep &= meta[col].astype(str).isin(values).to_numpy()
    return meta["capture_id"].astype(str)[keep].tolist()


def _record_look(plan: Plan, ledger: Path, final: bool, force_final: bool, n_pending: int) -> tuple[str, list[str]]:
    """The plan's test-set hash; the look recorded in the ledger (when the run scores the test set)."""
    test_set = plan_test_set(plan)
    methods = plan_methods(plan)
    notes = check_final(ledger, test_set, methods, force_final) if final else []
    if n_pending or final:
        record_look(ledger, {"time": now_iso(), "protocol": plan.protocol.name, "evaluation": plan.protocol.evaluation,
                             "test_set": test_set, "run_id": plan.run_id, "methods": methods, "tasks": n_pending,
                             "final": final, "forced": bool(notes)})
    return test_set, notes


def _run_locked(plan: Plan, store: ResultStore, *, jobs: int, force: bool, retry_failed: bool,
                progress: bool | None, worker_setup, fail_fast: bool = False, final: bool = False,
                force_final: bool = False, ledger: Path, methods: set[str] | None = None) -> RunResult:
    t_start = time.perf_counter()
    started_at = now_iso()
    protocol = plan.protocol
    out = store.root
    store.clean_stale_temporaries()
    if is_local_backend():
        jobs, warning = local_jobs(jobs)
        if warning:
            warnings.warn(warning, RuntimeWarning, stacklevel=2)
    else:
        check_jobs(jobs)
    if force:
        store.forget(plan.task_ids)
    damaged: dict[str, str] = {}
    finished = store.finished(damaged)
    notes = list(plan.notes) + _damaged_notes(plan, damaged)
    pending = [t for t in plan.tasks
               if t.task_id not in finished or (retry_failed and finished[t.task_id] == "failed")]
    if methods is not None:  # only these methods run; every finished task is still merged
        pending = [t for t in pending if t.classifier_label in methods]
    show = sys.stderr.isatty() if progress is None else progress
    design_captures = _design_captures(plan)  # a design naming an unknown column is refused before any task

    if not pending and not final and _reports_current(store, plan, notes):
        scores = read_results_table(store.scores_path)
        preds = None
        if protocol.expected is not None:
            preds = read_results_table(store.predictions_path, columns=["task_id", TRUE, PREDICTED])
        return RunResult(out=out, run_id=plan.run_id, n_tasks=len(plan.tasks), n_ran=0, n_skipped=len(plan.tasks),
                         n_failed=int((scores["status"] == "failed").sum()), noop=True,
                         seconds=time.perf_counter() - t_start, scores=scores, summary=summarize(scores, metrics=protocol.metrics),
                         expected=check_expected(protocol.expected, scores, preds), notes=notes)

    test_set, final_notes = _record_look(plan, ledger, final, force_final, len(pending))  # before any task
    notes += final_notes
    n_ran = 0
    stopped = False
    with _Progress(show) as prog:
        if pending:
            notes += _fill_cache(plan, pending, jobs, prog, worker_setup)
            ds_path = _dataset_copy(plan) if jobs > 1 and len(pending) > 1 else None
            ctx = RunContext(plan.dataset, protocol.target, plan.cache_root, ds_path, setup=worker_setup)
            tid = prog.add(f"{protocol.name}: tasks", len(pending))
            if jobs == 1 or len(pending) == 1:
                results = (execute_task(t, ctx) for t in pending)
            else:  # never more workers than tasks
                results = parallel(min(jobs, len(pending)), ordered=False)(
                    delayed(execute_task)(t, ctx) for t in pending)
            for row, preds in results:
                if preds is not None:
                    preds.insert(0, "run_id", plan.run_id)
                row["run_id"] = plan.run_id
                store.write_task(row["task_id"], row, preds)
                n_ran += 1
                prog.advance(tid)
                if fail_fast and row.get("status") == "failed":
                    stopped = True
                    break
            if hasattr(results, "close"):
                results.close()  # a generator left early: joblib cancels what it has not started

    stamp = {"run_id": plan.run_id, "protocol": protocol.name, "protocol_hash": protocol.text_hash}
    per_task = {col: {t.task_id: t.base_row.get(col, "") for t in plan.tasks} for col in ("leakage", "selection")}
    merged = store.merge(plan.task_ids, stamp, protocol.metrics, notes, per_task)
    scores = merged["scores"]
    expected = check_expected(protocol.expected, scores, merged["predictions"])
    status = store.finished()
    n_failed = sum(1 for t in plan.task_ids if status.get(t) == "failed")
    session = {"started_at": started_at, "finished_at": now_iso(), "jobs": jobs, "ran": n_ran,
               "skipped": len(plan.tasks) - len(pending), "force": force,
               "seconds": round(time.perf_counter() - t_start, 3)}
    manifest = update_manifest(
        store.read_manifest(),
        run={"run_id": plan.run_id, "results_dir": str(out)},
        protocol={"name": protocol.name, "path": str(protocol.path) if protocol.path else None,
                  "text": protocol.text, "text_hash": protocol.text_hash, "content_hash": protocol.content_hash,
                  "seed": protocol.seed, "repetitions": protocol.repetitions, "scheme": protocol.scheme.name,
                  "evaluation": protocol.evaluation,
                  "design": protocol.design.model_dump(mode="json") if protocol.design is not None else None},
        dataset={"ref": protocol.dataset.name, "resolved": plan.dataset_ref, "hash": plan.dataset.content_hash,
                 "source_hash": plan.source_hash, "captures": len(plan.dataset),
                 "filters": protocol.dataset.filters, "exclude": protocol.dataset.exclude,
                 "sensor": plan.dataset.sensor.to_dict(), "provenance": plan.dataset.provenance},
        identity={"packages": plan.package_versions,
                  "components": {label: {"digest": i.digest, "modules": list(i.modules)}
                                 for label, i in plan.identities.items()}},
        session=session,
        tasks={"total": len(plan.tasks), "merged": len(scores), "failed": n_failed, "folds": plan.n_folds,
               "ids_hash": plan.ids_hash, "task_ids": plan.task_ids, "merged_files": store.merged_checksums()},
        notes=notes,
        expected=expected,
    )
    manifest["ledger"] = {"path": os.path.relpath(ledger, out), "test_set": test_set, "final": final}
    manifest["protocol"]["design_captures"] = design_captures
    store.write_manifest(manifest)
    return RunResult(out=out, run_id=plan.run_id, n_tasks=len(plan.tasks), n_ran=n_ran,
                     n_skipped=len(plan.tasks) - len(pending), n_failed=n_failed, noop=False,
                     seconds=time.perf_counter() - t_start, scores=scores, summary=summarize(scores, metrics=protocol.metrics),
                     expected=expected, notes=notes, stopped_early=stopped)


def results_dirs(protocol: Protocol, out: str | Path | None = None) -> list[tuple[Protocol, Path]]:
    """Each evaluation of ``protocol`` with its results folder: ``out`` (default
    ``results/<name>``) itself, or ``out/<evaluation>`` for a protocol with several."""
    root = Path(out) if out is not None else Path("results") / protocol.name
    return [(sub, root / sub.evaluation if sub.evaluation else root) for sub in protocol.evaluation_protocols()]


def run_protocol(protocol: Protocol | str | Path, out: str | Path | None = None, *, jobs: int = 1,
                 force: bool = False, retry_failed: bool = False, progress: bool | None = None,
                 cache_root: str | Path | None = None, dataset: TouchDataset | None = None,
                 worker_setup=None, wait: float = 0.0, fail_fast: bool = False, final: bool = False,
                 force_final: bool = False, ledger: str | Path | None = None,
                 methods: Sequence[str] | None = None) -> RunResult | list[RunResult]:
    """Validate, plan and run a protocol (a :class:`Protocol` or a file path): its result, or one
    result per evaluation (in order) for a protocol with ``evaluations``. ``methods``: run only
    these methods' tasks (:func:`run_plan`)."""
    if not isinstance(protocol, Protocol):
        protocol = load_protocol(protocol)
    out_list = []
    for sub, folder in results_dirs(protocol, out):
        plan = plan_run(sub, cache_root=cache_root, dataset=dataset)
        labels = set(method_labels(plan))
        present = [m for m in methods or () if m in labels]
        out_list.append(run_plan(plan, folder, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                                 worker_setup=worker_setup, wait=wait, fail_fast=fail_fast, final=final,
                                 force_final=force_final, ledger=ledger, methods=present or methods))
    return out_list if protocol.evaluations else out_list[0]
