"""One run's dealings with its results folder: what remains to be done, the finished tasks, the end.

The engine asks its results folder one question and hands it its finished tasks::

    with open_results(out, protocol=..., evaluation=..., run_id=..., ids_hash=..., task_ids=...) as store:
        todo = store.remaining(selected, force=..., retry_failed=..., report=..., final=..., ...)
        taken = store.adopt(todo.pending, other_folders)  # finished elsewhere: not computed again
        for row, predictions in computed(t for t in todo.pending if t not in taken):
            store.add(row, predictions)
        tables = store.finish(stamp=..., metrics=..., per_task=..., notes=..., describe=..., ended=...)

Behind it: :func:`open_results` holds the folder (:meth:`ResultStore.lock`), refuses another
protocol's folder (:meth:`ResultStore.check_owner`) and removes an interrupted run's stale
temporaries; :meth:`Results.remaining` trusts only sound fragments (contents and checksums:
:meth:`ResultStore.finished`), tells whether the merged files are still this plan's (their
checksums, schema, run and task ids), and, for a run that scores its test set, records the look
in the ledger before any task (:mod:`touchbench.results.ledger`); :meth:`Results.add` writes a
task's fragments while the next one computes (:class:`TaskWriter`); :meth:`Results.finish` merges,
writes ``manifest.json`` and ends the look.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import pandas as pd

from ..core.paths import results_root
from .ledger import LEDGER_NAME, check_final, end_look, merge_ledgers, old_ledgers, record_look, start_look
from .manifest import now_iso, update_manifest
from .store import PREDICTED, SCHEMA_VERSION, TRUE, ResultStore, TaskWriter, check_schema, read_results_table

__all__ = ["Results", "Todo", "default_ledger", "open_results"]


def default_ledger(out: str | Path, evaluation: str | None = None) -> Path:
    """The ledger of the results root (:func:`touchbench.core.paths.results_root`: the nearest
    ``results`` folder above ``out``); outside one, of the parent of the protocol's results folder
    (which holds one folder per ``evaluation`` when the protocol has several)."""
    root = results_root(out)
    if root is not None:
        return root / LEDGER_NAME
    folder = Path(out).parent if evaluation else Path(out)
    return folder.parent / LEDGER_NAME


@dataclass
class Todo:
    """The store's answer to :meth:`Results.remaining`."""

    #: the ids of the tasks asked about that still need computing, in the order asked
    pending: list[str]
    #: task id -> why its saved results were not used (they run again), of every fragment of the folder
    damaged: dict[str, str] = field(default_factory=dict)
    #: what the store has to say: merged files rebuilt (and why), a forced final run
    notes: list[str] = field(default_factory=list)
    #: nothing to compute and the merged files are this plan's, as its last merge wrote them
    current: bool = False


@contextlib.contextmanager
def open_results(folder: str | Path, *, protocol: str, evaluation: str | None, run_id: str, ids_hash: str,
                 task_ids: Sequence[str], ledger: str | Path | None = None, wait: float = 0.0) -> Iterator["Results"]:
    """Hold results folder ``folder`` for a run of ``protocol`` (its ``evaluation``) whose plan is
    ``run_id`` with the tasks ``task_ids`` (hashed ``ids_hash``): another run holding it is waited
    for up to ``wait`` seconds, then refused with who holds it; a folder of another protocol is
    refused; temporary files an interrupted run left are removed. ``ledger``: the ledger of looks
    (default: :func:`default_ledger`). Leaving the block waits for every fragment being written
    (also when the run is interrupted: its finished tasks are kept)."""
    store = ResultStore(folder)
    ledger = Path(ledger) if ledger is not None else default_ledger(folder, evaluation)
    with store.lock(wait=wait, command=f"touchbench run {protocol}"):
        store.check_owner(protocol, evaluation)
        store.clean_stale_temporaries()
        results = Results(store, ledger, protocol, evaluation, run_id, ids_hash, list(task_ids))
        try:
            yield results
        except BaseException as e:
            results._close(type(e))
            raise
        results._close(None)


class Results:
    """A results folder held for one run (:func:`open_results`)."""

    def __init__(self, store: ResultStore, ledger: Path, protocol: str, evaluation: str | None, run_id: str,
                 ids_hash: str, task_ids: list[str]):
        self._store, self._ledger = store, ledger
        self._protocol, self._evaluation = protocol, evaluation
        self._run_id, self._ids_hash, self._task_ids = run_id, ids_hash, task_ids
        self._status: dict[str, str] = {}  # task id -> ok / failed, of every finished task
        self._writer: TaskWriter | None = None
        self._current = False
        self._look: dict[str, Any] = {}  # the manifest's ``ledger`` block

    # ----------------------------------------------------------- the question
    def remaining(self, task_ids: Sequence[str], *, test_set: Callable[[], str], force: bool = False,
                  retry_failed: bool = False, report: dict[str, Any] | None = None, final: bool = False,
                  force_final: bool = False, methods: Sequence[str] = (), only: Sequence[str] | None = None) -> Todo:
        """Which of ``task_ids`` (tasks of the plan) still need computing: those without sound
        results (a damaged task is named in :attr:`Todo.damaged` and runs again), and with
        ``retry_failed`` the failed ones; ``force`` first forgets the results of every task of the
        plan. When something is to be done (a task, a ``final`` run, merged files that are not
        this plan's: its ``report`` block, ``report``, is part of them), the look at the test set
        (``test_set``, asked only then) is checked and recorded in the ledger before any task
        (:func:`touchbench.results.ledger.check_final`: ``methods`` the ``features / method``
        labels the run scores, ``only`` the method names it was limited to)."""
        if force:
            self._store.forget(self._task_ids)
        damaged: dict[str, str] = {}
        self._status = self._store.finished(damaged)
        pending = [t for t in task_ids
                   if t not in self._status or (retry_failed and self._status[t] == "failed")]
        todo = Todo(pending, damaged)
        manifest = self._store.read_manifest() or {}
        same_report = (manifest.get("protocol") or {}).get("report") == report  # added later: merge again
        if not pending and not final and same_report and self._merged_current(manifest, todo.notes):
            todo.current = self._current = True
            return todo
        todo.notes += self._record_look(test_set(), final, force_final, list(methods), len(pending), only)
        return todo

    def _merged_current(self, m: dict[str, Any], notes: list[str]) -> bool:
        """The merged files are those of this plan, as the last merge wrote them (a damaged or
        edited one adds a note: they are rebuilt from the fragments)."""
        if not m:
            return False
        if m.get("run", {}).get("run_id") != self._run_id or m.get("tasks", {}).get("ids_hash") != self._ids_hash:
            return False
        if m.get("tasks", {}).get("merged") != len(self._task_ids):
            return False
        version = check_schema(m.get("results_schema"), self._store.manifest_path)
        if version < SCHEMA_VERSION:
            notes.append(f"the merged files have the layout of results schema {version}: merged again in schema "
                         f"{SCHEMA_VERSION}")
            return False
        problems = self._store.merged_problems(m.get("tasks", {}).get("merged_files"))
        if problems:
            notes.append("; ".join(problems) + ": merged again from the results of each task")
            return False
        return True

    def _record_look(self, test_set: str, final: bool, force_final: bool, methods: list[str], n_pending: int,
                     only: Sequence[str] | None) -> list[str]:
        """The look recorded in the ledger, when the run scores the test set (the session that
        resumes an interrupted run records that run's look id again); the notes of a forced final run."""
        root = results_root(self._store.root)
        if root is not None and self._ledger == root / LEDGER_NAME:  # earlier versions' ledgers, deeper in the root
            merge_ledgers(self._ledger, old_ledgers(root))
        notes = check_final(self._ledger, test_set, methods, force_final) if final else []
        if n_pending or final:
            look, resumed = start_look(self._store.root, {"run_id": self._run_id, "final": final,
                                                          "methods": sorted(only) if only is not None else None})
            record_look(self._ledger, {"time": now_iso(), "protocol": self._protocol, "evaluation": self._evaluation,
                                       "test_set": test_set, "run_id": self._run_id, "methods": methods,
                                       "tasks": n_pending, "final": final, "forced": bool(notes), "look": look,
                                       "resumed": resumed, "results": str(self._store.root)})
        self._look = {"path": os.path.relpath(self._ledger, self._store.root), "test_set": test_set, "final": final}
        return notes

    # ----------------------------------------------------------- finished tasks
    def add(self, row: dict[str, Any], predictions: pd.DataFrame | None) -> None:
        """A finished task (its scores row, its predictions), stamped with the run id: its fragments
        are written, with their checksums, while the next task computes; the error of the write
        before it, if any, is raised here."""
        if self._writer is None:
            self._writer = TaskWriter(self._store).__enter__()
        if predictions is not None:
            predictions.insert(0, "run_id", self._run_id)
        row["run_id"] = self._run_id
        self._writer.write(row["task_id"], row, predictions)
        self._status[row["task_id"]] = row["status"]

    def adopt(self, task_ids: Sequence[str], sources: Sequence[str | Path]) -> dict[str, Path]:
        """Those of ``task_ids`` that finished with status ``ok`` in another results folder of
        ``sources`` (the first holding it), added here as if computed now (:meth:`add`: fragments and
        checksums of their own, this run's id): each id taken with the folder it came from, in the
        order asked. A task's id hashes everything its result depends on (data, fold, method, seed
        and the code of its components), so a sound fragment with the same id elsewhere is its
        result; the merge relabels its rows as this plan names them. A source whose fragment is
        damaged, failed or missing gives nothing."""
        wanted, taken = list(task_ids), {}
        for source in sources:
            other = ResultStore(source)
            if other.root.resolve() == self._store.root.resolve():
                continue
            for tid in [t for t in wanted if t not in taken and other.status(t) == "ok"]:
                row = other.read_scores([tid]).drop(columns="run_id").iloc[0].to_dict()
                preds = other.read_predictions([tid]).drop(columns="run_id")
                self.add(row, preds if len(preds) else None)
                taken[tid] = other.root
        return {t: taken[t] for t in wanted if t in taken}

    def _close(self, exc_type: type[BaseException] | None) -> None:
        """Wait for every fragment being written (raising the last write's error unless the run
        is already leaving on an error of its own)."""
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.__exit__(exc_type, None, None)

    # ----------------------------------------------------------- the end
    def finish(self, *, stamp: dict[str, Any] | None = None, metrics: Sequence[str] = (),
               per_task: dict[str, dict[str, Any]] | None = None, notes: list[str] | None = None,
               describe: Callable[[dict[str, pd.DataFrame]], dict[str, Any]] | None = None,
               folds: int = 0, ended: bool = True, predictions: bool = True) -> dict[str, pd.DataFrame | None]:
        """The plan's merged tables (``scores``, ``predictions``...).

        When :meth:`remaining` found them current and nothing was added they are read as they
        are (``predictions``: the predictions' task ids and labels, else None) and nothing is
        written. Otherwise every finished task of the plan is merged
        (:meth:`ResultStore.merge`: ``stamp``, ``metrics``, ``per_task``; a metric's note goes
        to ``notes``) and ``manifest.json`` written: ``describe`` gives, from the merged tables,
        its ``run``, ``protocol``, ``dataset``, ``identity``, ``session`` and ``expected`` blocks
        (:func:`touchbench.results.manifest.update_manifest`), the store its ``tasks`` (the plan
        has ``folds`` folds), ``notes`` and ``ledger``. ``ended``: the run ended (the next run is
        another look); false for a run stopped at a failed task."""
        if self._current and self._writer is None:
            store = self._store
            return {"scores": read_results_table(store.scores_path),
                    "predictions": read_results_table(store.predictions_path, columns=["task_id", TRUE, PREDICTED])
                    if predictions else None}
        self._close(None)
        notes = [] if notes is None else notes
        merged = self._store.merge(self._task_ids, stamp or {}, metrics, notes, per_task, self._status)
        blocks = describe(merged) if describe is not None else {}
        manifest = update_manifest(
            self._store.read_manifest(), **blocks,
            tasks={"total": len(self._task_ids), "merged": len(merged["scores"]),
                   "failed": sum(1 for t in self._task_ids if self._status.get(t) == "failed"), "folds": folds,
                   "ids_hash": self._ids_hash, "task_ids": self._task_ids,
                   "merged_files": self._store.merged_checksums()},
            notes=notes)
        manifest["ledger"] = self._look
        self._store.write_manifest(manifest)
        if ended:
            end_look(self._store.root)
        return merged
