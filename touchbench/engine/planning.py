"""Planning a run in stages, each handing plain data to the next.

1. **read**: :func:`touchbench.protocols.loading.load_protocol` validates the
   file and reads every spelling of a method into a
   :class:`touchbench.methods.Method` (``Protocol.evaluated_methods``).
2. **prepare** (:func:`prepare_evaluation`): one evaluation's data -- the
   dataset loaded and filtered, what the scheme makes of it (windows, a
   second dataset), the target checked -- and its folds, one list per
   repetition. Nothing here knows the methods; ``touchbench train`` stops
   here and fits on the evaluation's training side (:func:`training_side`).
3. **serve** (:func:`serving_protocol`): a component that cannot serve the
   evaluation's sensor is refused (a protocol of one evaluation) or left out
   of this evaluation, said in a note, before any task exists.
4. **plan** (:func:`plan_tasks`): pure: (repetition x fold x method) ->
   :class:`touchbench.engine.tasks.Task` with stable ids and seeds.

:func:`plan_run` chains them; :mod:`touchbench.engine.runner` runs a plan.

Identity and seeds: a task id is a hash of everything that determines its
result: the dataset's content hash (recomputed from the data when it is
loaded), target, scheme and its parameters, repetition, fold name and
indices, the method (feature sets and estimator with their parameters and
their code identities, :mod:`touchbench.engine.identity`) and the protocol
seed. The estimator's ``random_state`` is ``derive_seed(seed, "task",
evaluation, repetition, fold, method id)``: the method's content
(:attr:`touchbench.methods.Method.key`), never its display label.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..classifiers import make_classifier
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.introspect import sensor_problem
from ..core.paths import cache_dir
from ..core.suggest import did_you_mean
from ..datasets.model import SensorSpec, TouchDataset
from ..features.base import feature_set_refusal, learns_from_data
from ..methods import METHODS, Method, expand_candidates, method_name, method_spec, named_methods, stops_on_test
from ..protocols.entries import expand_grid
from ..protocols.schema import Protocol, resolve_dataset_ref
from ..protocols.seeding import derive_seed
from ..protocols.schemes import Fold, SplitError
from ..results.ledger import test_set_hash_of
from ..results.manifest import LEFT_OUT
from ..results.store import task_row
from .cache import FeatureCache
from .evaluation_data import apply_filters, evaluation_dataset, load_spec
from .identity import MAX_MODULES, Identity, classifier_identity, feature_set_identity
from .tasks import SetSpec, Task, make_feature_set

__all__ = ["Components", "Plan", "Prepared", "check_methods", "default_cache_root", "fold_seed", "method_labels", "names_a_method", "plan_method_list", "plan_methods", "plan_run", "plan_tasks", "plan_test_set",
           "prepare_evaluation", "sensor_refusals", "serving_protocol", "training_side"]


def default_cache_root() -> Path:
    """The feature cache a run uses unless told otherwise."""
    return cache_dir() / "features"


# ----------------------------------------------------------------- prepare
@dataclass
class Prepared:
    """One evaluation's data and folds: what every later stage reads."""

    protocol: Protocol
    source: TouchDataset  # the dataset as loaded, before filters
    dataset: TouchDataset  # what the scheme evaluates
    folds: list[list[Fold]]  # one list per repetition
    notes: list[str] = field(default_factory=list)

    @property
    def crop_frames(self) -> list[int]:
        """The frame counts the folds cut captures to (the early scheme), in fold order."""
        rate = self.dataset.sensor.frame_rate
        return [n for folds in self.folds for f in folds if (n := f.crop_frames(rate)) is not None]

    @property
    def min_frames(self) -> int:
        """The shortest capture a task will see."""
        return int(min([int(self.dataset.n_frames.min()), *self.crop_frames]))


def prepare_evaluation(protocol: Protocol, dataset: TouchDataset | None = None) -> Prepared:
    """The evaluation's data (loaded unless ``dataset`` is given, filtered, made what the scheme
    evaluates) with its target checked, and its folds for every repetition."""
    notes: list[str] = []
    source = dataset if dataset is not None else load_spec(protocol, protocol.dataset, ("dataset",), notes)
    ds = evaluation_dataset(protocol, apply_filters(protocol, source), notes)
    _check_target(protocol, ds)
    folds = [_folds(protocol, ds, r, notes) for r in range(protocol.repetitions)]
    return Prepared(protocol, source, ds, folds, notes)


def _check_target(protocol: Protocol, ds: TouchDataset) -> None:
    """Refuse a target the data has not, leaves without a value, or holds a single value of."""
    target = protocol.target
    if target not in ds.meta.columns:
        cols = sorted(c for c in ds.meta.columns if c != "capture_id")
        raise protocol.error_at(("target",), f"the dataset has no {target!r} column{did_you_mean(target, cols)} "
                                             f"(its metadata columns: {', '.join(cols)})")
    if ds.meta[target].isna().any():
        raise protocol.error_at(("target",), f"{int(ds.meta[target].isna().sum())} captures have no {target!r} value")
    classes = sorted({str(v) for v in ds.meta[target]})
    if len(classes) < 2:
        raise protocol.error_at(("target",), f"after the filters the target {target!r} has a single value "
                                             f"{classes}: nothing to classify")


def _folds(protocol: Protocol, ds: TouchDataset, repetition: int, notes: list[str]) -> list[Fold]:
    """The scheme's folds of ``repetition`` (a scheme that cannot split the data is refused)."""
    splitter = protocol.splitter(repetition)
    try:
        folds = splitter.folds(ds.meta)
    except SplitError as e:
        raise protocol.error_at(("scheme", *e.field), str(e)) from None
    prefix = f"repetition {repetition}: " if protocol.repetitions > 1 else ""
    notes += [prefix + n for n in splitter.notes_]
    unseen = _unseen_class_note(ds.meta[protocol.target].astype(str).to_numpy(), folds)
    if unseen:
        notes.append(prefix + unseen)
    return folds


def _unseen_class_note(y: np.ndarray, folds: Sequence[Fold]) -> str:
    """A note naming the classes some fold tests without training on any of their captures (a class with
    a single capture always is, under every scheme): those test captures cannot be labelled right. When
    every test capture is such, it says the accuracy is 0 % by construction. Empty when there is none."""
    unseen: set[str] = set()
    n_unseen = n_test = 0
    for fold in folds:
        test = y[np.asarray(fold.test, dtype=np.int64)]
        missing = ~np.isin(test, y[np.asarray(fold.train, dtype=np.int64)])
        unseen.update(test[missing].tolist())
        n_unseen, n_test = n_unseen + int(missing.sum()), n_test + len(test)
    if not unseen:
        return ""
    values, counts = np.unique(y, return_counts=True)
    count = dict(zip(values.tolist(), counts.tolist()))
    names = ", ".join(f"{c!r} ({count[c]} capture{'s' if count[c] > 1 else ''})" for c in sorted(unseen))
    note = (f"class(es) {names} tested in a fold that trains on none of their captures: those {n_unseen} of "
            f"{n_test} test captures cannot be labelled right")
    return note + ("; that is every test capture: accuracy is 0 % by construction" if n_unseen == n_test else "")


def training_side(prepared: Prepared) -> np.ndarray:
    """The positions of the captures some fold trains on (first repetition): every capture under
    cross-validation; the training set of a challenge split; the training dataset of a transfer.
    A capture that is only ever tested is never part of it."""
    folds = prepared.folds[0]
    return np.unique(np.concatenate([np.asarray(f.train, dtype=np.int64) for f in folds]))


# ----------------------------------------------------------------- serve
def sensor_refusals(protocol: Protocol, sensor: SensorSpec, min_frames: int) -> list[tuple[tuple, str]]:
    """Every component of the protocol that cannot serve ``sensor``: ``(field, message)`` pairs.

    Every feature set and classifier (with each of its parameter settings)
    is built with the sensor and asked (:func:`touchbench.core.introspect.sensor_problem`);
    ``min_frames`` is the shortest capture a task will see. One pair per
    entry (feature combination, classifier or method), its first reason. A
    feature set that rejects its parameters with this sensor is refused at
    its field (:class:`touchbench.protocols.errors.ProtocolError`).
    """
    out: list[tuple[tuple, str]] = []
    for i, combo in enumerate(protocol.features):
        problem = _sets_refusal(protocol, combo, ("features", i), sensor, min_frames)
        if problem:
            out.append(problem)
    refused_methods = set()
    for j, m in enumerate(protocol.methods):
        problem = _sets_refusal(protocol, m.features or [], ("methods", j, "features"), sensor, min_frames)
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


def _sets_refusal(protocol: Protocol, refs: Sequence[Any], field: tuple, sensor: SensorSpec,
                  min_frames: int) -> tuple[tuple, str] | None:
    """The first feature set of ``refs`` (any of its parameter settings) that cannot serve ``sensor``:
    its protocol field (``field`` + its index) and the message, or None. Every set is built first: one
    that rejects its parameters with this sensor is refused at its field, whatever else is refused."""
    first = None
    for k, ref in enumerate(refs):
        for p in expand_grid(ref.params):
            try:
                fs = make_feature_set(ref.name, p, sensor)
            except Exception as e:
                raise protocol.error_at((*field, k), f"feature set {ref.name!r} rejects {p}: "
                                                     f"{type(e).__name__}: {e}") from None
            problem = None if first else sensor_problem(fs, sensor, min_frames)
            if problem:
                first = (*field, k), f"feature set {ref.name!r} cannot serve sensor {sensor.describe()}: {problem}"
    return first


def _classifier_refusal(name: str, params: dict, sensor: SensorSpec, min_frames: int) -> str | None:
    """Why the classifier or named method ``name`` (any of its parameter settings) cannot serve ``sensor``."""
    kind = "method" if name in METHODS else "classifier"
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
            return f"{kind} {name!r} rejects {p}: {type(e).__name__}: {e}"
        problem = sensor_problem(est, sensor, min_frames)
        if problem:
            return f"{kind} {name!r} cannot serve sensor {sensor.describe()}: {problem}"
    return None


def _without(protocol: Protocol, refusals: list[tuple[tuple, str]]) -> Protocol:
    """``protocol`` without the entries ``refusals`` name (a feature combination, classifier or method)."""
    drop: dict[str, set[int]] = {"features": set(), "classifiers": set(), "methods": set()}
    for loc, _ in refusals:
        drop[loc[0]].add(int(loc[1]))
    update = {k: [x for i, x in enumerate(getattr(protocol, k)) if i not in drop[k]] for k in drop}
    return protocol.model_copy(update=update)


def serving_protocol(prepared: Prepared) -> tuple[Protocol, list[str]]:
    """The protocol with what cannot serve the evaluation's sensor removed, and a note for each.

    One of several evaluations leaves such a component out of itself alone; a
    protocol of one evaluation (or one left with nothing) is refused at the
    first such field."""
    protocol, sensor = prepared.protocol, prepared.dataset.sensor
    refusals = sensor_refusals(protocol, sensor, prepared.min_frames)
    if not refusals:
        return protocol, []
    reduced = _without(protocol, refusals) if protocol.evaluation else None
    if reduced is None or not reduced.evaluated_methods():
        raise protocol.error_at(*refusals[0])
    return reduced, [f"{LEFT_OUT}{protocol.evaluation!r}: {msg}" for _, msg in refusals]


# ----------------------------------------------------------------- plan
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


def _label(kind: str, name: str, params: dict[str, Any]) -> str:
    return f"{kind} {name}" + (f" {canonical_json(params)}" if params else "")


@dataclass
class Components:
    """The code identity of every feature set and estimator the methods use."""

    identities: dict[str, Identity] = field(default_factory=dict)
    sets: dict[tuple, tuple[bool, str]] = field(default_factory=dict)  # (name, params) -> (fold-dependent, digest)
    estimators: dict[tuple, str] = field(default_factory=dict)  # (name, params) -> digest

    @classmethod
    def of(cls, methods: list[Method]) -> "Components":
        out = cls()
        for m in methods:
            for name, params in m.spec.feature_sets:
                k = (name, canonical_json(params))
                if k not in out.sets:
                    ident = out.identities[_label("feature set", name, params)] = feature_set_identity(name, params)
                    out.sets[k] = (learns_from_data(name), ident.digest)
            est, est_params = m.spec.estimator, m.spec.estimator_params
            k = (est, canonical_json(est_params))
            if k not in out.estimators:
                ident = out.identities[_label("classifier", est, est_params)] = classifier_identity(est, est_params)
                out.estimators[k] = ident.digest
        return out

    def notes(self) -> list[str]:
        return [f"the {label} imports more than {MAX_MODULES} modules of its own: edits beyond the first ones "
                "found are not noticed (use --force after editing them)"
                for label, ident in self.identities.items() if ident.incomplete]

    def set_digest(self, name: str, params: dict) -> str:
        return self.sets[(name, canonical_json(params))][1]

    def estimator_digest(self, m: Method) -> str:
        return self.estimators[(m.spec.estimator, canonical_json(m.spec.estimator_params))]


def _input_notes(methods: list[Method], ds: TouchDataset) -> list[str]:
    """A note for a method that takes the captures as recorded beside a stated frame count that
    would have cut or padded them (it is not applied)."""
    lo, hi = int(ds.n_frames.min()), int(ds.n_frames.max())
    return [f"method {m.name!r} takes the captures as recorded ({lo}..{hi} frames); the frames={m.input_frames} "
            f"of raw-window beside it is not applied"
            for m in methods if m.input_frames is not None and (lo != m.input_frames or hi != m.input_frames)]


def _set_specs(m: Method, comps: Components, ds_hash: str, crop_frames: int | None) -> tuple[SetSpec, ...]:
    """The method's feature sets with their cache keys (fold-independent ones)."""
    out = []
    for name, params in m.spec.feature_sets:
        dep, digest = comps.sets[(name, canonical_json(params))]
        out.append(SetSpec(
            name=name, params=params, fold_dependent=dep,
            key_full=None if dep else FeatureCache.key(ds_hash, name, params, digest, None),
            key_crop=None if dep or crop_frames is None else FeatureCache.key(ds_hash, name, params, digest, crop_frames),
        ))
    return tuple(out)


def _evaluation_key(protocol: Protocol, dataset: TouchDataset) -> str:
    """The evaluation's content (dataset, target, scheme), for task seeds: computed once per
    evaluation."""
    return hashlib.sha256(canonical_json([dataset.content_hash, protocol.target,
                                          protocol.scheme_json]).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class _FoldPlace:
    """Where a task sits: the evaluation's content (its key: :func:`_evaluation_key`), the
    repetition and the fold."""

    protocol: Protocol
    dataset: TouchDataset
    evaluation_key: str
    scheme_leak: str
    repetition: int
    fold: Fold

    @property
    def crop_frames(self) -> int | None:
        return self.fold.crop_frames(self.dataset.sensor.frame_rate)


def _task_identity(place: _FoldPlace, m: Method, comps: Components) -> dict[str, Any]:
    """Everything a task's result depends on (hashed into its id)."""
    fold, ds = place.fold, place.dataset
    idx_hash = hashlib.sha256(fold.train.tobytes() + b"|" + fold.test.tobytes()).hexdigest()[:16]
    estimator = [m.spec.estimator, m.spec.estimator_params, comps.estimator_digest(m)]
    identity = {
        "dataset": ds.content_hash, "target": place.protocol.target, "scheme": place.protocol.scheme_json,
        "repetition": place.repetition, "fold": fold.name, "indices": idx_hash,
        "crop": [place.crop_frames, fold.crops_training()],
        "features": [[n, p, comps.set_digest(n, p)] for n, p in m.spec.feature_sets],
        "classifier": [m.name, m.spec.estimator_params, estimator[2]] if m.name == m.spec.estimator
        else [m.name, m.params, estimator],
        "seed": place.protocol.seed,
    }
    if m.subject_id_feature:  # only then: the ids of every other task stay as they were
        identity["subject_id_feature"] = True
    if m.stopped_on_test:
        identity["stopped_on_test"] = True
    identity.update(fold.identity())  # the scheme's extras (a stream fold: its streams and recogniser)
    return identity


def _base_row(place: _FoldPlace, m: Method, task_id: str, seed: int) -> dict[str, Any]:
    """The task's scores row as planned (:func:`touchbench.results.store.task_row`)."""
    fold, protocol, crop = place.fold, place.protocol, place.crop_frames
    return task_row({
        "task_id": task_id, "protocol": protocol.name, "dataset": protocol.dataset.name,
        "dataset_hash": place.dataset.content_hash, "target": protocol.target, "scheme": protocol.scheme.name,
        "repetition": place.repetition, "fold": fold.name, "fold_group": fold.group,
        "early_frames": np.float64(crop) if crop is not None else np.nan,
        "features": m.features_label, "feature_sets": "+".join(m.spec.feature_names),
        "feature_params": canonical_json([[n, p] for n, p in m.spec.feature_sets]),
        "classifier": m.label, "classifier_name": m.name,
        "classifier_params": canonical_json(m.params), "seed": seed,
        "n_train": int(len(fold.train)), "n_test": int(len(fold.test)),
        "leakage": "; ".join(x for x in [place.scheme_leak, *m.leakage] if x),
        "selection": m.tuned_on_test,
        "adaptation": m.adaptation,
        **fold.columns(),
    })


def _task_seed(place: _FoldPlace, m: Method) -> int:
    """The estimator's seed of ``m`` at ``place``: the protocol seed, the evaluation's content, the
    repetition, the fold and the method's content -- never a display label."""
    return derive_seed(place.protocol.seed, "task", place.evaluation_key, place.repetition, place.fold.name,
                       m.method_id)


def fold_seed(prepared: Prepared, m: Method, fold: Fold, repetition: int = 0) -> int:
    """The seed the run engine gives ``m``'s estimator on ``fold`` (``touchbench train --fold``)."""
    protocol = prepared.protocol
    key = _evaluation_key(protocol, prepared.dataset)
    return _task_seed(_FoldPlace(protocol, prepared.dataset, key, "", repetition, fold), m)


def _task(place: _FoldPlace, m: Method, comps: Components, measure_latency: bool) -> Task:
    task_id = hashlib.sha256(canonical_json(_task_identity(place, m, comps)).encode()).hexdigest()[:20]
    seed = _task_seed(place, m)
    return Task(task_id=task_id, repetition=place.repetition, fold=place.fold, method=m,
                sets=_set_specs(m, comps, place.dataset.content_hash, place.crop_frames), seed=seed,
                crop_frames=place.crop_frames, measure_latency=measure_latency,
                base_row=_base_row(place, m, task_id, seed))


def plan_tasks(prepared: Prepared, protocol: Protocol, methods: list[Method], comps: Components) -> list[Task]:
    """Every (repetition x fold x method) task, in that order; the first task of each method (and
    crop) in plan order measures its latency."""
    for m in methods:
        if m.subject_id_feature and not m.spec.feature_sets:
            raise protocol.error_at(("methods",), f"{m.label!r}: subject_id_feature needs a feature matrix; "
                                                  f"{m.spec.estimator!r} takes the captures themselves")
        if m.stopped_on_test and not stops_on_test(m.spec.estimator):
            raise protocol.error_at(("classifiers",), f"{m.label!r}: stopped_on_test needs an estimator that stops "
                                                      f"on test data; {m.spec.estimator!r} does not")
    evaluation = _evaluation_key(protocol, prepared.dataset)
    leak = protocol.splitter(0).leakage()
    tasks: list[Task] = []
    timed: set[tuple] = set()
    for r, folds in enumerate(prepared.folds):
        for fold in folds:
            place = _FoldPlace(protocol, prepared.dataset, evaluation, leak, r, fold)
            for m in methods:
                key = (m.method_id, m.label, place.crop_frames)
                tasks.append(_task(place, m, comps, key not in timed and not m.subject_id_feature))
                timed.add(key)
    ids = [t.task_id for t in tasks]
    if len(set(ids)) != len(ids):
        raise protocol.error_at(("features",), "two entries of the protocol describe the same task "
                                               "(duplicate combination or classifier)")
    return tasks


def plan_run(protocol: Protocol, cache_root: str | Path | None = None, dataset: TouchDataset | None = None) -> Plan:
    """Every check that needs the data, then the list of tasks (no work done): prepare -> serve -> plan."""
    cache_root = Path(cache_root) if cache_root is not None else default_cache_root()
    prepared = prepare_evaluation(protocol, dataset)
    served, left_out = serving_protocol(prepared)
    methods = served.evaluated_methods()
    comps = Components.of(methods)
    ds = prepared.dataset
    tasks = plan_tasks(prepared, served, methods, comps)
    notes = left_out + prepared.notes + _input_notes(methods, ds) + comps.notes()
    # The run is the set of its tasks: a change of protocol, data, component source or
    # package version that changes any task gives another run id.
    ids = [t.task_id for t in tasks]
    run_id = hashlib.sha256(canonical_json(
        {"protocol": served.content_hash, "dataset": ds.content_hash,
         "tasks": hashlib.sha256("\n".join(ids).encode()).hexdigest()}).encode()).hexdigest()[:12]
    return Plan(protocol=served, dataset=ds, dataset_ref=resolve_dataset_ref(served),
                source_hash=prepared.source.content_hash, tasks=tasks, notes=list(dict.fromkeys(notes)),
                run_id=run_id, cache_root=cache_root, n_folds=sum(len(f) for f in prepared.folds),
                identities=comps.identities)


# ----------------------------------------------------------------- reading a plan
def plan_test_set(plan: Plan) -> str:
    """The hash of every capture some task of the plan tests (:func:`touchbench.results.ledger.test_set_hash`)."""
    checksums = plan.dataset.labelled_checksums(plan.protocol.target)
    return test_set_hash_of(checksums[i] for i in sorted({int(i) for t in plan.tasks for i in t.fold.test}))


def plan_methods(plan: Plan, only: set[str] | None = None) -> list[str]:
    """The methods a plan evaluates (those whose :func:`method_name` is in ``only``, when given), as
    ``features / method`` labels."""
    return sorted({f"{t.method.features_label} / {t.method.label}" for t in plan.tasks
                   if only is None or method_name(t.method) in only})


def method_labels(plan: Plan) -> list[str]:
    """The method labels of ``plan``'s tasks, in plan order."""
    return list(dict.fromkeys(t.method.label for t in plan.tasks))


def plan_method_list(plan: Plan, named: Sequence[str] | None = None) -> list[Method]:
    """The methods of ``plan``'s tasks, each once, in plan order (only those the texts ``named`` name,
    when given: :func:`touchbench.methods.named_methods`)."""
    methods = list({method_name(t.method): t.method for t in plan.tasks}.values())
    if named is None:
        return methods
    where = plan.protocol.name + (f" / {plan.protocol.evaluation}" if plan.protocol.evaluation else "")
    chosen = {method_name(m) for text in named for m in named_methods(methods, text, where)}
    return [m for m in methods if method_name(m) in chosen]


def names_a_method(plan: Plan, text: str) -> bool:
    """Whether ``text`` names a method of ``plan`` (:func:`touchbench.methods.named_methods`)."""
    try:
        named_methods(plan_method_list(plan), text, plan.protocol.name)
    except TouchbenchError:
        return False
    return True


def check_methods(plan: Plan, methods: Sequence[str] | None) -> set[str] | None:
    """The full names (:func:`touchbench.methods.method_name`) of the methods ``methods`` names in
    ``plan`` (None: all), each read by :func:`touchbench.methods.named_methods`; an unknown one is
    refused naming the known."""
    return {method_name(m) for m in plan_method_list(plan, methods)} if methods else None
