"""Running a plan: pending tasks -> feature cache -> tasks (in parallel) -> stored results.

The plan comes from :mod:`touchbench.engine.planning` (prepare -> serve ->
plan). ``run_plan`` then

1. skips finished tasks (their scores fragment exists; ``force`` recomputes,
   ``retry_failed`` reruns failed ones; ``methods`` runs only some methods'
   tasks),
2. records the look at the test set in the ledger, before any task,
3. computes the fold-independent features of the pending tasks once, into
   the on-disk feature cache (``engine.cache``),
4. runs the pending tasks, in parallel with joblib when ``jobs > 1``, each
   result written as soon as it arrives (one atomic fragment per task),
5. merges the fragments into ``scores`` / ``predictions`` / ``confusion``
   and writes ``manifest.json``.

A rerun of a finished run loads the dataset, rebuilds the plan, sees that
every task is finished and the reports are current, and does nothing else.
:func:`run_protocol` is the one entry point that runs a protocol, every
evaluation of it into its own folder.
"""

from __future__ import annotations

import sys
import time
import warnings
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
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

from ..core.errors import TouchbenchError
from ..datasets.model import TouchDataset
from ..methods import method_name
from ..protocols.checks import require_extras
from ..protocols.loading import load_protocol
from ..protocols.schema import Protocol
from ..protocols.specs import design_blocks
from ..results.manifest import now_iso
from ..results.session import Results, open_results
from ..results.summary import check_expected, summarize
from .backends import check_jobs, is_local_backend, local_jobs, parallel
from .cache import FeatureCache, crop_captures
from .planning import Plan, check_methods, names_a_method, plan_method_list, plan_methods, plan_run, plan_test_set
from .tasks import RunContext, Task, execute_task, make_feature_set

__all__ = ["RunResult", "default_results_dir", "fill_features", "plan_protocol", "results_dirs", "run_plan",
           "run_protocol"]


def default_results_dir(protocol: Protocol) -> Path:
    """``results/<protocol name>/`` under the current directory (``results/<protocol name>/<evaluation>/``
    for one evaluation of a protocol with several)."""
    root = Path("results") / protocol.name
    return root / protocol.evaluation if protocol.evaluation else root


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
    """Compute the missing (or damaged) feature cache entries of ``pending``; notes on damaged ones.

    The missing sets of one crop are computed together, chunk by chunk (one pass over the
    captures; a preprocessing they share computed once per chunk), each into its own entry."""
    ds = plan.dataset
    notes: list[str] = []
    cache = FeatureCache(plan.cache_root)
    needed: dict[str, tuple[str, dict, int | None]] = {}
    for t in pending:
        crop_train = t.fold.crops_training()
        for s in t.sets:
            if s.fold_dependent:
                continue
            if not crop_train:
                needed.setdefault(s.key_full, (s.name, s.params, None))
            if s.key_crop is not None:
                needed.setdefault(s.key_crop, (s.name, s.params, t.crop_frames))
    by_crop: dict[int | None, list[tuple[str, str, dict]]] = {}
    for key, (name, params, crop) in needed.items():
        problem = cache.problem(key)
        if problem is None:
            continue
        label = name + (f" (first {crop} frames)" if crop is not None else "")
        if problem != "missing":
            notes.append(f"the cached features of {label} were not used ({problem}): computed again")
        by_crop.setdefault(crop, []).append((key, name, params))
    for crop, group in by_crop.items():
        caps = crop_captures(ds.captures, crop)
        names = ", ".join(dict.fromkeys(name for _, name, _ in group))
        tid = progress.add(f"features {names}" + (f" (first {crop} frames)" if crop is not None else ""), len(caps))
        entries = [(key, partial(make_feature_set, name, params, ds.sensor),
                    {"dataset_hash": ds.content_hash, "name": name, "params": params, "crop": crop})
                   for key, name, params in group]
        cache.compute(entries, caps, jobs=jobs, on_chunk=lambda n, tid=tid: progress.advance(tid, n), setup=setup)
    return notes


def fill_features(plans: Sequence[tuple[Plan, Path]], *, jobs: int = 1, progress: bool | None = None) -> list[str]:
    """Compute the missing feature-cache entries that the unfinished tasks of several plans read
    (each plan with its results folder: a task whose scores fragment is there is finished), the
    plans of one dataset together: one pass per crop over its captures for the sets of all of
    them, so a set two plans use is computed once and a preprocessing their sets share (the Zhou
    sets' frame descriptors) once. Each plan's run then finds its entries. Notes on damaged entries."""
    by_dataset: dict[tuple[str, Path], tuple[Plan, list[Task]]] = {}
    for plan, out in plans:
        folder = Path(out) / "fragments"
        done = {p.name[:-len(".scores.parquet")] for p in folder.glob("*.scores.parquet")} if folder.is_dir() else set()
        _, tasks = by_dataset.setdefault((plan.dataset.content_hash, plan.cache_root), (plan, []))
        tasks.extend(t for t in plan.tasks if t.task_id not in done)
    notes: list[str] = []
    with _Progress(sys.stderr.isatty() if progress is None else progress) as prog:
        for plan, tasks in by_dataset.values():
            notes += _fill_cache(plan, tasks, _jobs_for_backend(jobs), prog)
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


def _damaged_notes(plan: Plan, problems: dict[str, str]) -> list[str]:
    """A note per task of the plan whose saved results could not be trusted (run again)."""
    by_id = {t.task_id: t for t in plan.tasks}
    return [f"the saved results of {t.method.features_label} | {t.method.label}, fold {t.fold.name} (repetition "
            f"{t.repetition}) were not used: {problems[tid]}; run again"
            for tid, t in by_id.items() if tid in problems]


def run_plan(plan: Plan, out: str | Path | None = None, *, jobs: int = 1, force: bool = False,
             retry_failed: bool = False, progress: bool | None = None, worker_setup=None,
             wait: float = 0.0, fail_fast: bool = False, final: bool = False, force_final: bool = False,
             ledger: str | Path | None = None, methods: Sequence[str] | None = None,
             reuse: Sequence[str | Path] = ()) -> RunResult:
    """Execute the pending tasks of ``plan`` and write the reports (see the module docstring).

    ``methods`` (method names of the plan, ``FEATURES/LABEL`` or a label alone:
    :func:`touchbench.methods.named_methods`) runs only their tasks: the tables
    still hold every finished task of the plan, the others stay pending (a slow method can
    wait, a new one can join a finished run).

    ``worker_setup`` is a picklable function each worker process calls once
    before its first task (to register plug-in components in the workers).
    One run at a time writes a results folder: another run holding ``out`` is
    waited for up to ``wait`` seconds, then refused with who holds it.
    ``fail_fast`` stops at the first task that fails: the tasks finished so
    far are kept and merged, the others are left pending.

    A run that scores its test set (a task to run, or ``final``) is recorded
    in ``ledger`` (default: :func:`touchbench.results.session.default_ledger`) before any task;
    ``final`` marks the run to report and is refused when the test set had
    a final run with other methods, unless ``force_final``
    (:func:`touchbench.results.ledger.check_final`).

    ``reuse``: other results folders (of the same or another protocol) whose finished tasks a
    pending task takes instead of computing, when its id is there (the same data, fold, method,
    seed and component code: :meth:`touchbench.results.session.Results.adopt`); not with ``force``.
    """
    out = Path(out) if out is not None else default_results_dir(plan.protocol)
    only = check_methods(plan, methods)
    with open_results(out, protocol=plan.protocol.name, evaluation=plan.protocol.evaluation, run_id=plan.run_id,
                      ids_hash=plan.ids_hash, task_ids=plan.task_ids, ledger=ledger, wait=wait) as store:
        return _run_held(plan, store, out, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                         worker_setup=worker_setup, fail_fast=fail_fast, final=final, force_final=force_final,
                         methods=only, reuse=() if force else reuse)


def _design_captures(plan: Plan) -> list[str] | list[list[str]] | None:
    """The ids of the captures the protocol's ``design`` names (None without one); a list of blocks
    gives a list per block, in its order."""
    blocks = design_blocks(plan.protocol.design)
    if not blocks:
        return None
    meta = plan.dataset.meta
    per_block = []
    for i, block in enumerate(blocks):
        keep = np.ones(len(meta), dtype=bool)
        loc = ("design", i) if isinstance(plan.protocol.design, list) else ("design",)
        for col, values in block.filters().items():
            if col not in meta.columns:
                raise plan.protocol.error_at(loc, f"the dataset has no metadata column {col!r}")
            keep &= meta[col].astype(str).isin(values).to_numpy()
        per_block.append(meta["capture_id"].astype(str)[keep].tolist())
    return per_block if isinstance(plan.protocol.design, list) else per_block[0]


def _design_json(design: Any) -> Any:
    """The manifest's ``design``: a block's fields, a list of them, or None."""
    if isinstance(design, list):
        return [b.model_dump(mode="json") for b in design]
    return design.model_dump(mode="json") if design is not None else None


def _report_block(plan: Plan) -> dict[str, Any] | None:
    """The protocol's ``report`` with, per ``by`` column, the ids of the captures of each of its values
    (what :mod:`touchbench.reports.breakdown` reads from the manifest); a column the dataset lacks, or
    a class its target never takes, is refused at its field before any task."""
    report, meta = plan.protocol.report, plan.dataset.meta
    if report is None:
        return None
    classes = set(meta[plan.protocol.target].astype(str)) if plan.protocol.target in meta.columns else set()
    for i, c in enumerate(report.recall):
        if c not in classes:
            raise plan.protocol.error_at(("report", "recall", i), f"{c!r} is not a value of the target "
                                         f"{plan.protocol.target!r} ({', '.join(sorted(classes))})")
    rows: dict[str, dict[str, list[str]]] = {}
    for i, col in enumerate(report.by):
        if col not in meta.columns:
            raise plan.protocol.error_at(("report", "by", i), f"the dataset has no metadata column {col!r} "
                                         f"(columns: {', '.join(map(str, meta.columns))})")
        known = meta[meta[col].notna()]
        rows[col] = {str(v): g["capture_id"].astype(str).tolist() for v, g in known.groupby(known[col].astype(str))}
    return {"recall": list(report.recall), "by": list(report.by), "rows": rows}


def _jobs_for_backend(jobs: int) -> int:
    """``jobs`` capped to the CPUs on the local backend (a warning), checked on a cluster."""
    if is_local_backend():
        jobs, warning = local_jobs(jobs)
        if warning:
            warnings.warn(warning, RuntimeWarning, stacklevel=3)
    else:
        check_jobs(jobs)
    return jobs


def _selected(plan: Plan, methods: set[str] | None) -> list[Task]:
    """The tasks of the methods this run is about (all of them without ``methods``)."""
    return [t for t in plan.tasks if methods is None or method_name(t.method) in methods]


def _noop_result(plan: Plan, store: Results, out: Path, selected: list[str], notes: list[str],
                 t_start: float) -> RunResult:
    """The result of a run with nothing to do: the merged tables as they are (counts: the tasks of
    the ``selected`` ids)."""
    protocol = plan.protocol
    tables = store.finish(predictions=protocol.expected is not None)
    scores = tables["scores"]
    failed = scores["task_id"].isin(selected) & (scores["status"] == "failed")
    return RunResult(out=out, run_id=plan.run_id, n_tasks=len(selected), n_ran=0, n_skipped=len(selected),
                     n_failed=int(failed.sum()), noop=True,
                     seconds=time.perf_counter() - t_start, scores=scores,
                     summary=summarize(scores, metrics=protocol.metrics),
                     expected=check_expected(protocol.expected, scores, tables["predictions"],
                                             protocol.features_label_of),
                     notes=notes)


def _execute(plan: Plan, store: Results, pending: list[Task], jobs: int, prog: "_Progress", worker_setup,
             fail_fast: bool) -> tuple[int, bool]:
    """Run ``pending``, each result handed to the store as it arrives (its fragments are written
    while the next task computes): (tasks run, stopped at a failure)."""
    ds_path = _dataset_copy(plan) if jobs > 1 and len(pending) > 1 else None
    ctx = RunContext(plan.dataset, plan.protocol.target, plan.cache_root, ds_path, setup=worker_setup)
    tid = prog.add(f"{plan.protocol.name}: tasks", len(pending))
    if jobs == 1 or len(pending) == 1:
        results = (execute_task(t, ctx) for t in pending)
    else:  # never more workers than tasks
        results = parallel(min(jobs, len(pending)), ordered=False)(delayed(execute_task)(t, ctx) for t in pending)
    n_ran, stopped = 0, False
    for row, preds in results:
        store.add(row, preds)
        n_ran += 1
        prog.advance(tid)
        if fail_fast and row.get("status") == "failed":
            stopped = True
            break
    if hasattr(results, "close"):
        results.close()  # a generator left early: joblib cancels what it has not started
    return n_ran, stopped


def _manifest_blocks(plan: Plan, out: Path) -> dict[str, Any]:
    """The manifest's description of the run's protocol, dataset and component identities."""
    protocol = plan.protocol
    return dict(
        run={"run_id": plan.run_id, "results_dir": str(out)},
        protocol={"name": protocol.name, "path": str(protocol.path) if protocol.path else None,
                  "text": protocol.text, "text_hash": protocol.text_hash, "content_hash": protocol.content_hash,
                  "seed": protocol.seed, "repetitions": protocol.repetitions, "scheme": protocol.scheme.name,
                  "evaluation": protocol.evaluation,
                  "design": _design_json(protocol.design)},
        dataset={"ref": protocol.dataset.name, "resolved": plan.dataset_ref, "hash": plan.dataset.content_hash,
                 "source_hash": plan.source_hash, "captures": len(plan.dataset),
                 "filters": protocol.dataset.filters, "exclude": protocol.dataset.exclude,
                 "sensor": plan.dataset.sensor.to_dict(), "provenance": plan.dataset.provenance},
        identity={"packages": plan.package_versions,
                  "components": {label: {"digest": i.digest, "modules": list(i.modules)}
                                 for label, i in plan.identities.items()}},
    )


@dataclass
class _Session:
    """What one invocation did, for the manifest and the result."""

    started_at: str
    t_start: float
    jobs: int
    force: bool
    selected: list[str]  # the ids of the tasks this run is about
    n_pending: int
    n_ran: int = 0
    stopped: bool = False
    notes: list[str] = field(default_factory=list)

    def block(self) -> dict[str, Any]:
        return {"started_at": self.started_at, "finished_at": now_iso(), "jobs": self.jobs, "ran": self.n_ran,
                "skipped": len(self.selected) - self.n_pending, "force": self.force,
                "seconds": round(time.perf_counter() - self.t_start, 3)}


def _merge_and_record(plan: Plan, store: Results, out: Path, session: _Session,
                      design_captures: list[str] | None, report: dict[str, Any] | None = None) -> RunResult:
    """Merge every finished task of the plan into the tables and write the manifest."""
    protocol = plan.protocol
    stamp = {"run_id": plan.run_id, "protocol": protocol.name, "protocol_hash": protocol.text_hash}
    # what the plan says of each task, over what its fragment says: how it leaks, and how it is named
    # (a label renamed in the protocol changes no task, only the name its rows carry)
    per_task = {col: {t.task_id: t.base_row.get(col, "") for t in plan.tasks}
                for col in ("leakage", "selection", "adaptation", "features", "classifier")}
    expected: list[dict[str, Any]] = []

    def describe(merged: dict[str, pd.DataFrame]) -> dict[str, Any]:
        expected[:] = check_expected(protocol.expected, merged["scores"], merged["predictions"],
                                     protocol.features_label_of)
        blocks = _manifest_blocks(plan, out)
        blocks["protocol"].update(design_captures=design_captures, report=report)
        return {**blocks, "session": session.block(), "expected": expected}

    merged = store.finish(stamp=stamp, metrics=protocol.metrics, per_task=per_task, notes=session.notes,
                          describe=describe, folds=plan.n_folds, ended=not session.stopped)
    scores = merged["scores"]
    selected = scores["task_id"].isin(session.selected)
    return RunResult(out=out, run_id=plan.run_id, n_tasks=len(session.selected), n_ran=session.n_ran,
                     n_skipped=len(session.selected) - session.n_pending,
                     n_failed=int((selected & (scores["status"] == "failed")).sum()), noop=False,
                     seconds=time.perf_counter() - session.t_start, scores=scores,
                     summary=summarize(scores, metrics=protocol.metrics), expected=expected, notes=session.notes,
                     stopped_early=session.stopped)


def _run_held(plan: Plan, store: Results, out: Path, *, jobs: int, force: bool, retry_failed: bool,
              progress: bool | None, worker_setup, fail_fast: bool = False, final: bool = False,
              force_final: bool = False, methods: set[str] | None = None,
              reuse: Sequence[str | Path] = ()) -> RunResult:
    t_start, started_at = time.perf_counter(), now_iso()
    jobs = _jobs_for_backend(jobs)
    design_captures = _design_captures(plan)  # a design naming an unknown column is refused before any task
    report = _report_block(plan)  # so is a report naming an unknown column or class
    selected = _selected(plan, methods)  # only these run; every finished task of the plan is still merged
    todo = store.remaining([t.task_id for t in selected], force=force, retry_failed=retry_failed, report=report,
                           final=final, force_final=force_final, methods=plan_methods(plan, methods),
                           only=sorted(methods) if methods is not None else None,
                           test_set=partial(plan_test_set, plan))  # the look recorded before any task
    notes = list(plan.notes) + _damaged_notes(plan, todo.damaged) + todo.notes
    if todo.current:
        return _noop_result(plan, store, out, [t.task_id for t in selected], notes, t_start)
    left = set(todo.pending)
    pending = [t for t in selected if t.task_id in left]
    if reuse and pending:
        taken = store.adopt([t.task_id for t in pending], reuse)
        pending = [t for t in pending if t.task_id not in taken]
        if taken:
            notes.append(f"{len(taken)} tasks had finished with the same data, fold, method and seed in "
                         f"{', '.join(map(str, dict.fromkeys(taken.values())))}: their results were taken "
                         "from there, not computed again")
    session = _Session(started_at, t_start, jobs, force, [t.task_id for t in selected], len(pending), notes=notes)
    with _Progress(sys.stderr.isatty() if progress is None else progress) as prog:
        if pending:
            session.notes += _fill_cache(plan, pending, jobs, prog, worker_setup)
            session.n_ran, session.stopped = _execute(plan, store, pending, jobs, prog, worker_setup, fail_fast)
    return _merge_and_record(plan, store, out, session, design_captures, report)


def results_dirs(protocol: Protocol, out: str | Path | None = None) -> list[tuple[Protocol, Path]]:
    """Each evaluation of ``protocol`` with its results folder: ``out`` (default
    ``results/<name>``) itself, or ``out/<evaluation>`` for a protocol with several."""
    root = Path(out) if out is not None else Path("results") / protocol.name
    return [(sub, root / sub.evaluation if sub.evaluation else root) for sub in protocol.evaluation_protocols()]


def plan_protocol(protocol: Protocol, out: str | Path | None = None, *, cache_root: str | Path | None = None,
                  dataset: TouchDataset | None = None, evaluations: Sequence[str] | None = None,
                  methods: Sequence[str] | None = None) -> list[tuple[Plan, Path]]:
    """Every evaluation of ``protocol`` (only those named in ``evaluations``) planned, each with its
    results folder: every check of every evaluation is done before any task runs, among them that
    the methods to run (those of ``methods`` the plans hold; all of them without) have their
    optional extras installed (:func:`touchbench.protocols.checks.require_extras`)."""
    pairs = [(sub, folder) for sub, folder in results_dirs(protocol, out)
             if not evaluations or sub.evaluation in evaluations]
    plans = [(plan_run(sub, cache_root=cache_root, dataset=dataset), folder) for sub, folder in pairs]
    chosen = {m.label for plan, _ in plans
              for m in plan_method_list(plan, [t for t in methods if names_a_method(plan, t)] if methods else None)}
    require_extras(protocol, chosen)
    return plans


def run_protocol(protocol: Protocol | str | Path, out: str | Path | None = None, *, jobs: int = 1,
                 force: bool = False, retry_failed: bool = False, progress: bool | None = None,
                 cache_root: str | Path | None = None, dataset: TouchDataset | None = None,
                 worker_setup=None, wait: float = 0.0, fail_fast: bool = False, final: bool = False,
                 force_final: bool = False, ledger: str | Path | None = None,
                 methods: Sequence[str] | None = None, reuse: Sequence[str | Path] = ()) -> RunResult | list[RunResult]:
    """Validate, plan and run a protocol (a :class:`Protocol` or a file path): its result, or one
    result per evaluation (in order) for a protocol with ``evaluations``. Every evaluation is planned
    before any runs. ``methods``: run only these methods' tasks; ``reuse``: results folders whose
    finished tasks a pending task with the same id takes (:func:`run_plan`)."""
    if not isinstance(protocol, Protocol):
        protocol = load_protocol(protocol)
    out_list = []
    for plan, folder in plan_protocol(protocol, out, cache_root=cache_root, dataset=dataset, methods=methods):
        present = [m for m in methods or () if names_a_method(plan, m)]
        out_list.append(run_plan(plan, folder, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                                 worker_setup=worker_setup, wait=wait, fail_fast=fail_fast, final=final,
                                 force_final=force_final, ledger=ledger, methods=present or methods, reuse=reuse))
    return out_list if protocol.evaluations else out_list[0]
