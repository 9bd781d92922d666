"""The result store: one Parquet fragment per task, written atomically, merged on read.

Layout of a results directory (``results/<protocol name>/`` by default)::

    fragments/<task_id>.predictions.parquet   one row per test capture
    fragments/<task_id>.scores.parquet        one row: the task's scores (written last)
    scores.parquet  predictions.parquet  confusion.parquet  confusion_pooled.parquet  manifest.json

A task is finished when its scores fragment exists: the predictions fragment
is written first, the scores fragment second, each to a temporary file that
is renamed into place, so a run killed at any point leaves either a finished
task or no trace of it (a stray predictions fragment is overwritten when the
task is run again). The merged files are derived from the fragments of the
tasks the protocol currently names; they are rewritten, atomically, at the
end of every run that changed something. Fragments of tasks a protocol no
longer names (after an edit) stay in ``fragments/`` but are not merged.

Merged tables are stamped with the current ``run_id`` and protocol hash at
merge time, so adding a classifier to a protocol reuses the finished tasks
and the report describes the protocol as it is now.

Trust nothing on disk: a scores fragment counts as a finished task only when
it is readable, names the task of its file name, and (for a task that
succeeded) its predictions fragment is readable with one row per test
capture, and its fragments match the checksums written when it finished
(:mod:`touchbench.results.fragments`); anything else is a damaged task, run
again (:meth:`finished` says which and why). A merge refuses a task whose
scores disagree with its predictions. The manifest records the SHA-256 of each merged file as it
was written (:meth:`merged_checksums`); a merged file that no longer matches
is rebuilt from the fragments (:meth:`merged_problems`).

One run at a time per results folder: :meth:`ResultStore.lock` holds an
operating-system lock on ``.touchbench.lock`` (released by the kernel when the
process ends, however it ends) and writes who holds it there; a second run
waits for it or says who holds it (:mod:`touchbench.results.locking`).
"""

from __future__ import annotations

import json
import time
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from ..core.atomic import atomic_write_bytes, atomic_write_parquet
from ..core.errors import TouchbenchError
from ..scoring.metrics import scorer_values
from .locking import hold
from .checksums import changed_files, file_checksums
from .fragments import FragmentError, check_scores_agree, checksum_path, checksum_problem, write_checksums


__all__ = ["PREDICTED", "PROBA_PREFIX", "SCHEMA_VERSION", "TRUE", "OtherResultsError", "ResultStore", "TaskWriter", "atomic_write_bytes",
           "atomic_write_parquet", "check_schema", "confusion_table", "read_results_table", "task_metrics",
           "upgrade", "write_results_table"]

class OtherResultsError(TouchbenchError):
    """A results folder that holds another protocol's (or evaluation's) results."""


#: what the plan says of a task: the first columns of its scores row (:func:`task_row`)
PLAN_COLUMNS = (
    "task_id", "protocol", "dataset", "dataset_hash", "target", "scheme", "repetition", "fold", "fold_group",
    "early_frames", "features", "feature_sets", "feature_params", "classifier", "classifier_name",
    "classifier_params", "seed", "n_train", "n_test", "leakage", "selection", "adaptation",
    "curve", "curve_size", "curve_draw", "curve_added", "curve_added_min",
)
#: plan columns that results written before touchbench recorded them lack, with the value they read as
#: (no method of those versions adapted to the test data, and no task was a point of a curve; the
#: calibration captures really added were not recorded)
LATER_PLANNED = {"adaptation": "", "curve": "", "curve_size": np.nan, "curve_draw": 0, "curve_added": np.nan,
                 "curve_added_min": np.nan}
#: what running a task measures, each with its value before (or without) a measurement
MEASURED = {
    "status": "ok", "error": "", "accuracy": np.nan, "balanced_accuracy": np.nan, "macro_f1": np.nan,
    "feature_seconds_per_capture": np.nan, "feature_fit_seconds": np.nan, "fit_seconds": np.nan,
    "predict_seconds": np.nan, "latency_ms": np.nan, "latency_cpu_ms": np.nan, "load_avg": np.nan,
    "usable_cpus": np.nan, "n_classes_train": 0, "notes": "", "finished_at": "", "live": "",
}
#: measured columns that results written before touchbench measured them lack, with the value they read as:
#: the CPU time of labelling one capture, the machine's 1-minute load average and the CPUs the run could
#: use (NaN); a stream evaluation's replays and scores (``live``, JSON: ``engine.live``; "" for captures)
LATER_MEASURED = {"latency_cpu_ms": np.nan, "load_avg": np.nan, "usable_cpus": np.nan, "live": ""}
# Columns of the scores table, in order: the run's stamp, the plan's, the measured ones.
SCORE_COLUMNS = [
    "run_id", "task_id", "protocol", "protocol_hash", "dataset", "dataset_hash", "target", "scheme",
    "repetition", "fold", "fold_group", "early_frames", "features", "feature_sets", "feature_params", "classifier",
    "classifier_name", "classifier_params", "seed", "n_train", "n_test", "n_classes_train",
    "accuracy", "balanced_accuracy", "macro_f1",
    "feature_seconds_per_capture", "feature_fit_seconds", "fit_seconds", "predict_seconds", "latency_ms",
    "latency_cpu_ms", "load_avg", "usable_cpus", "status", "error", "notes", "finished_at", "leakage", "selection",
    "adaptation", "curve", "curve_size", "curve_draw", "curve_added", "curve_added_min", "live",
]


def task_row(planned: dict[str, Any]) -> dict[str, Any]:
    """A task's scores row before it runs: the plan's columns (exactly :data:`PLAN_COLUMNS`), then
    every measured column at its value without a measurement (:data:`MEASURED`). The one place a
    scores row is defined: the planner, the task and the fake runs of the tests all start here."""
    if set(planned) != set(PLAN_COLUMNS):
        extra, missing = sorted(set(planned) - set(PLAN_COLUMNS)), sorted(set(PLAN_COLUMNS) - set(planned))
        raise ValueError(f"a task's planned columns are {', '.join(PLAN_COLUMNS)}; extra {extra}, missing {missing}")
    return {**{k: planned[k] for k in PLAN_COLUMNS}, **MEASURED}


#: the label columns of predictions and confusion tables (``true`` is a keyword in SQL engines)
TRUE, PREDICTED = "true_label", "predicted_label"
PREDICTION_COLUMNS = [
    "run_id", "task_id", "repetition", "fold", "fold_group", "early_frames", "features", "classifier",
    "capture_id", "subject", "gesture", TRUE, PREDICTED, "correct", "leakage",
]
#: the class probabilities of a prediction are the columns ``proba_<class>``
PROBA_PREFIX = "proba_"
#: version of the layout of the files above, in each file's metadata (``touchbench_results_schema``) and
#: the manifest: 1 (no version written) named the label columns ``true`` / ``predicted`` and kept the
#: pooled confusion rows in ``confusion.parquet``; 2 had no ``leakage`` column in scores and
#: predictions (read as ``NOT_RECORDED``); 3 is this layout. Readers upgrade older tables.
SCHEMA_VERSION = 3
#: the leakage of a result row written before touchbench recorded it: unknown, so never read as honest
NOT_RECORDED = "not recorded (results written before touchbench recorded leakage)"
SCHEMA_KEY = "touchbench_results_schema"
_LEGACY = {"true": TRUE, "predicted": PREDICTED}


def upgrade(df: pd.DataFrame, pooled: bool = False) -> pd.DataFrame:
    """A results table of any earlier layout in this one: the label columns renamed; a version-1
    confusion table (per-task and pooled rows in one file, told apart by ``scope``) keeps the rows
    of one kind without that column: the ``pooled`` ones (without ``task_id`` / ``fold``) or the
    per-task ones. Scores without the columns measured since (:data:`LATER_MEASURED`) get them
    at their value then (:data:`LATER_MEASURED`), and the plan columns recorded since (:data:`LATER_PLANNED`) at their value then."""
    old = {k: v for k, v in _LEGACY.items() if k in df.columns and v not in df.columns}
    if old:
        df = df.rename(columns=old)
    if "leakage" not in df.columns and ("status" in df.columns or "capture_id" in df.columns):
        df = df.assign(leakage=NOT_RECORDED)  # scores or predictions of schema 1 or 2
    later = {c: v for c, v in LATER_MEASURED.items() if c not in df.columns}
    if later and "status" in df.columns:  # scores written before these were measured
        df = df.assign(**later)
    planned = {c: v for c, v in LATER_PLANNED.items() if c not in df.columns}
    if planned and "status" in df.columns:  # scores written before these were recorded
        df = df.assign(**planned)
    if "scope" in df.columns:
        df = df[df["scope"] == ("pooled" if pooled else "task")].drop(columns="scope").reset_index(drop=True)
        if pooled:
            df = df.drop(columns=[c for c in ("task_id", "fold") if c in df.columns])
    return df


def check_schema(version: Any, where: str | Path) -> int:
    """``version`` (a results-schema version as a file or manifest states it; none: 1) as an int;
    a newer one than this touchbench reads is refused with both versions."""
    try:
        v = 1 if version is None else int(version)
    except (TypeError, ValueError):
        v = 1
    if v > SCHEMA_VERSION:
        raise TouchbenchError(f"{where}: written by a newer touchbench (results schema {v}; this version "
                              f"reads up to {SCHEMA_VERSION}): upgrade touchbench to read it")
    return v


def schema_version(path: str | Path) -> int:
    """The results-schema version a Parquet file of a results folder was written with (1: none said)."""
    meta = pq.read_schema(path).metadata or {}
    try:
        return int(meta.get(SCHEMA_KEY.encode(), b"1"))
    except ValueError:
        return 1


def read_results_table(path: str | Path, columns: list[str] | None = None, *, pooled: bool = False) -> pd.DataFrame:
    """A table of a results folder (merged file or fragment), in this version's layout; a file of a
    newer layout is refused with both versions. ``pooled``: of a version-1 ``confusion.parquet``,
    the pooled rows (see :func:`upgrade`)."""
    path = Path(path)
    version = check_schema(schema_version(path), path)
    if columns is None or version >= 2:
        return upgrade(pq.read_table(path, columns=columns).to_pandas(), pooled)
    back = {v: k for k, v in _LEGACY.items()}
    have = set(pq.read_schema(path).names)
    wanted = [back.get(c, c) if back.get(c, c) in have else c for c in columns]
    if "scope" in have:
        wanted.append("scope")
    return upgrade(pq.read_table(path, columns=wanted).to_pandas(), pooled)[list(columns)]


def write_results_table(path: Path, df: pd.DataFrame) -> None:
    atomic_write_parquet(path, df, {SCHEMA_KEY: str(SCHEMA_VERSION)})



def _concat(frames: list[pd.DataFrame], columns: list[str]) -> pd.DataFrame:
    frames = [f for f in frames if len(f)]
    if not frames:
        return pd.DataFrame(columns=columns)
    df = pd.concat(frames, ignore_index=True, sort=False)
    front = [c for c in columns if c in df.columns]
    rest = [c for c in df.columns if c not in front]
    return df[front + sorted(rest)]


def confusion_table(predictions: pd.DataFrame, pooled: bool = False) -> pd.DataFrame:
    """Counts per true / predicted label: per task (``task_id``, ``fold``), or ``pooled`` over every
    fold and repetition of one configuration (feature combination x classifier x early length). The
    two live in separate files, so that summing a file's counts never counts a capture twice."""
    keys = (["run_id", "features", "classifier", "early_frames", TRUE, PREDICTED] if pooled else
            ["run_id", "task_id", "fold", "features", "classifier", "early_frames", TRUE, PREDICTED])
    if predictions.empty:
        return pd.DataFrame(columns=[*keys, "count"])
    p = predictions.copy()
    p["early_frames"] = p["early_frames"].fillna(-1)
    out = p.groupby(keys, dropna=False, sort=True).size().rename("count").reset_index()
    out["early_frames"] = out["early_frames"].astype("float64").where(out["early_frames"] >= 0)
    out["count"] = out["count"].astype("int64")
    return out


def task_metrics(predictions: pd.DataFrame, names: Sequence[str], notes: list[str] | None = None) -> pd.DataFrame:
    """Each scikit-learn scorer of ``names`` per task (one row per ``task_id``), from the task's
    labels and its stored probabilities (``proba_<class>``: the classes of its training fold)
    through :func:`touchbench.scoring.metrics.scorer_values`. A scorer not computed for some
    tasks gets one note in ``notes``: how many, and the first reason."""
    rows: dict[str, dict[str, float]] = {}
    missed: dict[str, list[str]] = {}
    for tid, p in predictions.groupby("task_id", sort=False):
        proba = {c[len(PROBA_PREFIX):]: p[c].to_numpy(dtype=np.float64) for c in p.columns
                 if c.startswith(PROBA_PREFIX) and p[c].notna().all()}
        problems: dict[str, str] = {}
        rows[str(tid)] = scorer_values(names, p[TRUE].to_numpy(), p[PREDICTED].to_numpy(), proba or None, problems)
        for name, why in problems.items():
            missed.setdefault(name, []).append(why)
    if notes is not None:
        notes += [f"metric {name}: not computed for {len(why)} of {len(rows)} tasks ({why[0]})"
                  for name, why in missed.items()]
    return pd.DataFrame.from_dict(rows, orient="index", columns=list(names))


class TaskWriter:
    """Writes tasks' fragments (:meth:`ResultStore.write_task`) in a thread of its own, in the order
    given, so that a task's fragments are written while the next task computes.

    Each write is the store's (atomic, predictions before scores). :meth:`write` first waits for the
    write before it and raises its error (:class:`touchbench.core.errors.WriteError`); leaving the
    ``with`` block waits for every write, also when the run is interrupted (the finished tasks are
    kept), and raises the last write's error."""

    def __init__(self, store: "ResultStore"):
        self.store = store
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="touchbench-fragments")
        self._last: Future | None = None

    def write(self, task_id: str, score: dict[str, Any], predictions: pd.DataFrame | None) -> None:
        self._wait()
        self._last = self._pool.submit(self.store.write_task, task_id, score, predictions)

    def _wait(self) -> None:
        last, self._last = self._last, None
        if last is not None:
            last.result()

    def __enter__(self) -> "TaskWriter":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self._pool.shutdown(wait=True)
        if exc_type is None:
            self._wait()


class ResultStore:
    """Fragments and merged reports of one results directory."""

    def __init__(self, root: str | Path):
        self.root = Path(root)
        self.fragments = self.root / "fragments"
        #: task id -> (scores, predictions) as this object wrote them: the merge takes these from
        #: memory and reads from disk only the tasks of earlier sessions
        self._written: dict[str, tuple[pd.DataFrame, pd.DataFrame | None]] = {}

    # ----------------------------------------------------------- paths
    def scores_fragment(self, task_id: str) -> Path:
        return self.fragments / f"{task_id}.scores.parquet"

    def predictions_fragment(self, task_id: str) -> Path:
        return self.fragments / f"{task_id}.predictions.parquet"

    @property
    def scores_path(self) -> Path:
        return self.root / "scores.parquet"

    @property
    def predictions_path(self) -> Path:
        return self.root / "predictions.parquet"

    @property
    def confusion_path(self) -> Path:
        return self.root / "confusion.parquet"

    @property
    def confusion_pooled_path(self) -> Path:
        return self.root / "confusion_pooled.parquet"

    @property
    def manifest_path(self) -> Path:
        return self.root / "manifest.json"

    # ----------------------------------------------------------- state
    def finished(self, problems: dict[str, str] | None = None) -> dict[str, str]:
        """task_id -> status (``ok`` / ``failed``) of every finished task.

        A damaged task is left out (so it runs again) and, when ``problems`` is given, recorded
        there with the reason: an unreadable scores fragment, one that holds another task, or a
        succeeded task whose predictions fragment is missing, unreadable, holds another task or
        has not one row per test capture.
        """
        out: dict[str, str] = {}
        if not self.fragments.is_dir():
            return out
        problems = {} if problems is None else problems
        for p in self.fragments.glob("*.scores.parquet"):
            tid = p.name[: -len(".scores.parquet")]
            problem = self._fragment_problem(tid, p)
            if isinstance(problem, str):
                problems[tid] = problem
            else:
                out[tid] = problem[0]
        return out

    def status(self, tid: str) -> str | None:
        """The status (``ok`` / ``failed``) of a task whose fragments are sound, else None (none, or
        damaged: :meth:`finished`)."""
        path = self.scores_fragment(tid)
        if not path.is_file():
            return None
        problem = self._fragment_problem(tid, path)
        return None if isinstance(problem, str) else problem[0]

    def _fragment_problem(self, tid: str, path: Path) -> str | tuple[str]:
        """The reason a task's fragments cannot be trusted, or ``(status,)``: what is wrong with their
        content first, then whether they are those its task wrote (:func:`checksum_problem`)."""
        problem = self._content_problem(tid, path)
        return problem if isinstance(problem, str) else (checksum_problem(self.fragments, tid) or problem)

    def _content_problem(self, tid: str, path: Path) -> str | tuple[str]:
        """The reason a task's fragments cannot be read as its results, or ``(status,)``."""
        try:
            row = pq.read_table(path, columns=["task_id", "status", "n_test"]).to_pylist()
        except Exception as e:  # noqa: BLE001 - pyarrow raises several types for a damaged file
            return f"its scores file is unreadable ({type(e).__name__})"
        if len(row) != 1:
            return f"its scores file holds {len(row)} rows, not one"
        if row[0]["task_id"] != tid:
            return f"its scores file holds the results of another task ({row[0]['task_id']})"
        status = row[0]["status"]
        if status != "ok":
            return (status,)
        pred = self.predictions_fragment(tid)
        try:
            ids = pq.read_table(pred, columns=["task_id"]).column("task_id").unique().to_pylist()
            rows = pq.read_metadata(pred).num_rows
        except FileNotFoundError:
            return "its predictions file is missing"
        except Exception as e:  # noqa: BLE001
            return f"its predictions file is unreadable ({type(e).__name__})"
        if ids != [tid]:
            return "its predictions file holds the results of another task"
        if row[0]["n_test"] is not None and rows != row[0]["n_test"]:
            return f"its predictions file has {rows} rows for {row[0]['n_test']} test captures"
        return (status,)

    # ----------------------------------------------------------- one run at a time
    def lock(self, wait: float = 0.0, command: str = "touchbench run"):
        """Hold the results folder for one run (:func:`touchbench.results.locking.hold`)."""
        return hold(self.root, wait, command)

    def check_owner(self, name: str, evaluation: str | None = None) -> None:
        """Refuse a folder whose merged tables are another protocol's (or another evaluation's): a run of
        ``name`` there would replace them."""
        m = self.read_manifest() or {}
        held = m.get("protocol") if isinstance(m.get("protocol"), dict) else {}
        other, other_ev = held.get("name"), held.get("evaluation")
        if other is None or (other, other_ev) == (name, evaluation):
            return
        what = f"{other!r}" + (f" (evaluation {other_ev!r})" if other_ev else "")
        mine = f"{name!r}" + (f" (evaluation {evaluation!r})" if evaluation else "")
        raise OtherResultsError(f"{self.root}: holds the results of protocol {what}, not of {mine}: a run here would "
                                "replace its merged tables; choose another results folder with --out (by default "
                                "results/<protocol name>), or remove this one first")

    def clean_stale_temporaries(self, older_than: float = 3600.0) -> int:
        """Remove temporary files an interrupted run left (older than ``older_than`` s)."""
        n = 0
        now = time.time()
        for d in (self.root, self.fragments):
            if not d.is_dir():
                continue
            for p in d.glob(".*.tmp"):
                try:
                    if now - p.stat().st_mtime > older_than:
                        p.unlink()
                        n += 1
                except FileNotFoundError:
                    pass
        return n

    def forget(self, task_ids: Iterable[str]) -> None:
        """Delete the fragments of ``task_ids`` (``--force``)."""
        for tid in task_ids:
            self._written.pop(tid, None)
            self.scores_fragment(tid).unlink(missing_ok=True)
            self.predictions_fragment(tid).unlink(missing_ok=True)
            checksum_path(self.fragments, tid).unlink(missing_ok=True)

    def verify_fragments(self) -> None:
        """Refuse (:class:`FragmentError`, naming it) a fragment that does not match the checksum its
        task wrote, or a task whose scores disagree with its predictions: before reading an
        interrupted run's fragments as its results."""
        for tid in self._ids(None, ".scores.parquet"):
            problem = checksum_problem(self.fragments, tid)
            if problem:
                raise FragmentError(f"{self.scores_fragment(tid)}: {problem}: these are not the results its task "
                                    "wrote; run the protocol again to compute it anew")
        check_scores_agree(self.read_scores(), self.read_predictions(), self.fragments)

    # ----------------------------------------------------------- writing
    def write_task(self, task_id: str, score: dict[str, Any], predictions: pd.DataFrame | None) -> None:
        """Predictions first, scores last: the scores fragment marks the task finished. Both tables
        are kept for this object's merge (:meth:`read_scores`, :meth:`read_predictions`)."""
        self._written.pop(task_id, None)
        kept = predictions if predictions is not None and len(predictions) else None
        if kept is not None:
            write_results_table(self.predictions_fragment(task_id), kept)
        else:
            self.predictions_fragment(task_id).unlink(missing_ok=True)
        scores = pd.DataFrame([score])
        write_results_table(self.scores_fragment(task_id), scores)
        write_checksums(self.fragments, task_id)
        self._written[task_id] = (scores, kept)

    # ----------------------------------------------------------- reading (merge on read)
    def read_scores(self, task_ids: Iterable[str] | None = None) -> pd.DataFrame:
        """The scores rows of ``task_ids`` (default: every fragment), in that order."""
        ids = self._ids(task_ids, ".scores.parquet")
        return _concat([f for f in (self._fragment(t, 0) for t in ids) if f is not None], SCORE_COLUMNS)

    def read_predictions(self, task_ids: Iterable[str] | None = None) -> pd.DataFrame:
        """The predictions of ``task_ids`` (default: every fragment), in that order."""
        ids = self._ids(task_ids, ".predictions.parquet")
        return _concat([f for f in (self._fragment(t, 1) for t in ids) if f is not None], PREDICTION_COLUMNS)

    def _fragment(self, task_id: str, which: int) -> pd.DataFrame | None:
        """A task's scores (``which`` 0) or predictions (1): as this object wrote them, else read
        from its fragment (None when there is none)."""
        if task_id in self._written:
            return self._written[task_id][which]
        path = (self.scores_fragment, self.predictions_fragment)[which](task_id)
        return read_results_table(path) if path.is_file() else None

    def _ids(self, task_ids: Iterable[str] | None, suffix: str) -> list[str]:
        if task_ids is not None:
            return list(task_ids)
        if not self.fragments.is_dir():
            return []
        return sorted(p.name[: -len(suffix)] for p in self.fragments.glob(f"*{suffix}"))

    def merge(self, task_ids: list[str], stamp: dict[str, Any], metrics: Sequence[str] = (),
              notes: list[str] | None = None, per_task: dict[str, dict[str, Any]] | None = None,
              finished: dict[str, str] | None = None) -> dict[str, pd.DataFrame]:
        """Write ``scores``, ``predictions``, ``confusion`` and ``confusion_pooled`` for ``task_ids``.

        ``stamp`` (``run_id``, ``protocol_hash``...) overwrites those columns,
        so the merged report describes the current protocol. Rows keep the
        order of ``task_ids`` (the plan's order), independent of the order
        tasks finished in. ``per_task`` (column -> task id -> value: the
        evaluation's leakage, the method's names) overwrites those columns of each task's rows in
        both tables, so a fragment written before the column existed is
        labelled as the plan says. ``metrics`` (scikit-learn scorer names) add one
        scores column each, computed from each task's stored predictions
        (:func:`task_metrics`), so naming a new metric refits nothing; why a
        metric could not be computed goes to ``notes``. ``finished``: the
        state :meth:`finished` gives, when the caller holds it already.
        """
        finished = self.finished() if finished is None else finished
        done = [t for t in task_ids if t in finished]
        scores = self.read_scores(done)
        preds = self.read_predictions(done)
        check_scores_agree(scores, preds, self.fragments)
        for df in (scores, preds):
            for k, v in stamp.items():
                if k in df.columns or df is scores:
                    df[k] = v
        for col, values in (per_task or {}).items():
            for df in (scores, preds):
                if len(df) and (df is scores or col in PREDICTION_COLUMNS):
                    df[col] = df["task_id"].map(values).fillna("").astype(str)
        order = {t: i for i, t in enumerate(task_ids)}
        if len(scores):
            scores = scores.sort_values("task_id", key=lambda s: s.map(order), kind="stable").reset_index(drop=True)
        if len(preds):
            preds = preds.sort_values("task_id", key=lambda s: s.map(order), kind="stable").reset_index(drop=True)
        if metrics:
            values = task_metrics(preds, metrics, notes)
            for name in metrics:
                scores[name] = scores["task_id"].map(values[name]) if len(scores) else []
        scores = _concat([scores], SCORE_COLUMNS)
        preds = _concat([preds], PREDICTION_COLUMNS)
        confusion = confusion_table(preds)
        pooled = confusion_table(preds, pooled=True)
        write_results_table(self.predictions_path, preds)
        write_results_table(self.confusion_path, confusion)
        write_results_table(self.confusion_pooled_path, pooled)
        write_results_table(self.scores_path, scores)
        return {"scores": scores, "predictions": preds, "confusion": confusion, "confusion_pooled": pooled}

    # ----------------------------------------------------------- merged files
    def merged_paths(self) -> dict[str, Path]:
        return {p.name: p for p in (self.scores_path, self.predictions_path, self.confusion_path,
                                    self.confusion_pooled_path)}

    def merged_checksums(self) -> dict[str, str]:
        """SHA-256 of each merged file as it is now (recorded in the manifest after a merge)."""
        return file_checksums(self.root, self.merged_paths())

    def merged_problems(self, recorded: dict[str, str] | None) -> list[str]:
        """Why the merged files cannot be trusted against the checksums ``recorded`` at the last
        merge: missing, or changed since (edited, truncated, damaged). Empty when they can."""
        if not recorded:
            return ["the merged files have no recorded checksums"]
        return changed_files(self.root, recorded, self.merged_paths())

    def read_confusion(self, pooled: bool = False) -> pd.DataFrame:
        """The merged confusion counts per task, or ``pooled`` over the folds of each configuration;
        a run of the first layout (both in ``confusion.parquet``) gives the same two tables."""
        if pooled and self.confusion_pooled_path.is_file():
            return read_results_table(self.confusion_pooled_path)
        return read_results_table(self.confusion_path, pooled=pooled)

    def read_manifest(self) -> dict[str, Any] | None:
        """The manifest (``None`` when missing or unreadable); one of a newer results schema is refused."""
        if not self.manifest_path.is_file():
            return None
        try:
            manifest = json.loads(self.manifest_path.read_text())
        except (OSError, json.JSONDecodeError):
            return None
        if isinstance(manifest, dict):
            check_schema(manifest.get("results_schema"), self.manifest_path)
        return manifest

    def write_manifest(self, manifest: dict[str, Any]) -> None:
        atomic_write_bytes(self.manifest_path, (json.dumps(manifest, indent=2, default=str) + "\n").encode())
