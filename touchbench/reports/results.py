"""Reading and combining results directories for the reports.

A results directory is what the run engine writes (``scores.parquet``,
``predictions.parquet``, ``manifest.json``; see
:mod:`touchbench.results.store`). :func:`load_results` reads any number of
them (a path may also be a folder holding many, searched recursively) and
adds the columns the reports need:

- ``method_id``: a hash of the method's parameters -- target, feature sets
  with their parameters, classifier name with its parameters, and the
  number of frames seen (``early`` scheme) -- never of its label. The same
  method run by two protocols, twice, or on two machines has one id, so its
  folds are combined into one leaderboard row; two methods that share a
  label but differ in any parameter have two ids.
- ``fold_key``: which test captures a fold scored (a hash of the fold's
  sorted capture ids, read from the predictions; without predictions, the
  protocol seed, repetition and fold name). Methods are paired on it. A
  point of a data curve (its ``curve``) is keyed by the point
  (``subjects:3|``) before its base fold's protocol seed, repetition and
  name: the points stay apart, a point's random draws (which may score
  different captures: a calibration pool is drawn per draw) are replicates
  of its base fold, and :mod:`touchbench.reports.curves` pairs the points
  of a base fold on what follows ``|``.
- ``machine``: a short hash of the manifest's platform description
  (platform string, architecture, processor, CPU count), ``machine_desc``
  its readable form. Timings are compared only within one machine.
- ``scheme_label``: the scheme with its parameters, read from the protocol
  text in the manifest (``kfold(k=10,grouped=false)``); the parameters a
  scheme sweeps over (``Splitter.swept_params``: the frame list of the
  ``early`` scheme) are left out so runs with different lists combine.
- ``frame_rate``: the dataset's frame rate from the manifest (to express
  frames seen in seconds).
- ``table_key``: the table a row belongs to: dataset (content hash), target
  and scheme label, and for a method adapted to the test data (its
  ``adaptation``, e.g. to each test subject's unlabelled captures) that
  adaptation too, so such a method is ranked, tested and put on a Pareto
  front only with methods adapted the same way; for a point of a data
  curve, the curve (``subjects``, ``calibration``), so two curves never
  share a table.

A run interrupted before its reports were merged is read from its task
fragments (``fragments/*.scores.parquet``). The merged files of any other are
checked against the SHA-256 its manifest records
(:func:`touchbench.results.checksums.changed_since_run`): each one changed or
missing since the run wrote it is a logged warning and a note of the source
(``changed``) that the leaderboard's tables repeat; the results are still read.

A task that appears twice (the same results directory given twice, or a run
copied) is counted once: rows with the same method, fold and classifier seed
are duplicates, and the last one (by ``finished_at``) is kept for accuracy.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd
import yaml

from ..core.errors import TouchbenchError
from ..core.paths import results_root
from ..core.yamlsafe import safe_load
from ..methods.base import SUBJECT_ID_LEAK
from ..protocols.schemes.base import scheme_class
from ..results.checksums import changed_since_run
from ..results.ledger import LEDGER_NAME, Looks, looks, old_ledgers
from ..results.manifest import LEFT_OUT
from ..results.store import PREDICTED, PROBA_PREFIX, TRUE, ResultStore, check_schema, read_results_table

__all__ = ["ResultSet", "find_result_dirs", "load_results", "machine_id", "method_id", "read_manifest", "scheme_label"]

log = logging.getLogger("touchbench.reports")

PREDICTION_COLUMNS = ["task_id", "fold", "capture_id", "subject", TRUE, PREDICTED, "correct"]


def _short_hash(obj: Any, n: int = 10) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str).encode()).hexdigest()[:n]


def method_id(target: str, feature_params: str, classifier_name: str, classifier_params: str,
              early_frames: float | None, variant: str = "") -> str:
    """The hash that identifies a method (see the module docstring); ``variant`` tells a leaky
    variant of a method (its subject id as a feature) from the method itself."""
    def _parse(s: str) -> Any:
        try:
            return json.loads(s)
        except (TypeError, ValueError):
            return s

    frames = None if early_frames is None or (isinstance(early_frames, float) and math.isnan(early_frames)) else int(early_frames)
    ident = {"target": target, "features": _parse(feature_params), "classifier": classifier_name,
             "params": _parse(classifier_params), "early_frames": frames}
    if variant:
        ident["variant"] = variant
    return _short_hash(ident)


def machine_id(platform: dict[str, Any] | None) -> tuple[str, str]:
    """``(id, description)`` of the machine a manifest's ``platform`` block describes."""
    if not platform:
        return "unknown", "unknown machine (no manifest)"
    key = {k: platform.get(k) for k in ("platform", "machine", "processor", "cpu_count")}
    # the CPU model names the machine; the id leaves it out, so results written before it was recorded keep theirs
    model = f"{platform['cpu_model']}, " if platform.get("cpu_model") else ""
    desc = f"{platform.get('platform') or '?'}, {model}{platform.get('cpu_count') or '?'} CPUs"
    return "m-" + _short_hash(key, 6), desc


def _fmt(v: Any, limit: int | None = None) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, dict):
        return "{" + ",".join(f"{k}={_fmt(v[k], limit)}" for k in sorted(v)) + "}"
    if isinstance(v, list):
        return "[" + ",".join(_fmt(x, limit) for x in v) + "]"
    return "…" if limit is not None and len(str(v)) > limit else str(v)


def scheme_label(scheme: Any, fallback: str = "?", limit: int | None = None, dataset: str | None = None) -> str:
    """``name(param=value,...)`` of a protocol's ``scheme`` entry (string or mapping); with ``limit``,
    a value (a parameter's, or one inside a list or mapping) longer than ``limit`` characters, such as
    a file-name pattern, is written ``…``; with the protocol's ``dataset``, a scheme that names itself
    as a person would (``Splitter.heading``: ``cross-dataset: trained on haart, tested on other``)
    does so."""
    if isinstance(scheme, str):
        return scheme
    if not isinstance(scheme, dict) or "name" not in scheme:
        return fallback
    params = {k: v for k, v in scheme.items() if k != "name"}
    cls = scheme_class(str(scheme["name"]))
    heading = cls.heading(params, dataset) if cls is not None and dataset is not None else None
    if heading:
        return heading
    written = {k: _fmt(v, limit) for k, v in params.items()}
    if cls is not None:
        for k in cls.swept_params:
            written.pop(k, None)
        if cls.base_param is not None and isinstance(params.get(cls.base_param), dict):
            written[cls.base_param] = scheme_label(params[cls.base_param], limit=limit, dataset=dataset)
    if not written:
        return str(scheme["name"])
    return f"{scheme['name']}(" + ",".join(f"{k}={written[k]}" for k in sorted(written)) + ")"


@dataclass
class ResultSet:
    """Scores (and predictions) of one or more results directories, combined."""

    scores: pd.DataFrame
    predictions: pd.DataFrame | None
    sources: list[dict[str, Any]] = field(default_factory=list)

    def source(self, path: str) -> dict[str, Any]:
        """The source entry of a results folder (its ``path`` as in the ``source`` column)."""
        return next((s for s in self.sources if s["path"] == path), {})

    @property
    def ok(self) -> pd.DataFrame:
        """Successful rows, duplicates removed (one row per method, fold and seed)."""
        s = self.scores[self.scores["status"] == "ok"]
        s = s.sort_values("finished_at", kind="stable")
        return s.drop_duplicates(["table_key", "method_id", "fold_key", "seed"], keep="last")


def find_result_dirs(path: Path) -> list[Path]:
    if path.is_file():
        if path.name == "scores.parquet":
            return [path.parent]
        raise TouchbenchError(f"{path}: not a results directory or scores.parquet")
    if not path.is_dir():
        raise TouchbenchError(f"{path}: no such results directory")
    if (path / "scores.parquet").is_file() or _fragments_only(path):
        return [path]
    found = {p.parent for p in path.rglob("scores.parquet") if "fragments" not in p.parts}
    found |= {p.parent.parent for p in path.rglob("fragments/*.scores.parquet") if _fragments_only(p.parent.parent)}
    found = sorted(found)
    if not found:
        raise TouchbenchError(f"{path}: no scores.parquet in it or below it (run `touchbench run` first)")
    return found


def _fragments_only(d: Path) -> bool:
    """An interrupted run: task fragments but no merged ``scores.parquet`` yet."""
    return not (d / "scores.parquet").is_file() and any((d / "fragments").glob("*.scores.parquet"))


def read_manifest(d: Path) -> dict[str, Any]:
    """A results folder's manifest ({} when it has none or it cannot be read; a newer layout is refused)."""
    p = d / "manifest.json"
    if not p.is_file():
        return {}
    try:
        m = json.loads(p.read_text())
    except (OSError, ValueError):
        return {}
    if isinstance(m, dict):
        check_schema(m.get("results_schema"), p)
    return m


def _protocol_scheme(manifest: dict[str, Any]) -> Any:
    """The run's scheme entry: the protocol's, or for one of several evaluations that evaluation's
    (so that two evaluations of one dataset under differently set schemes get their own tables)."""
    proto = manifest.get("protocol") or {}
    text = proto.get("text")
    if not text:
        return None
    try:
        doc = safe_load(text) or {}
    except yaml.YAMLError:
        return None
    for ev in doc.get("evaluations") or []:
        if isinstance(ev, dict) and ev.get("name") == proto.get("evaluation") and "scheme" in ev:
            return ev["scheme"]
    return doc.get("scheme")


_CROP_PREFIX = re.compile(r"^first[^/]*/")
#: a data curve's point before its base fold's name (``n3#1/subject=s01``, ``k2#0/subject=s01``)
_CURVE_PREFIX = re.compile(r"^[^/#]*#\d+/")


def _curve_keys(s: pd.DataFrame, by_name: pd.Series) -> list[str]:
    """The fold keys of ``s``, a point of a data curve's the point before its base fold's key by name
    (``by_name``: protocol seed, repetition and base fold)."""
    if "curve" not in s:
        return list(s["fold_key"])
    return [f"{c}:{z:g}|{n}" if c else k
            for c, z, n, k in zip(s["curve"].astype(str), s["curve_size"], by_name, s["fold_key"])]


def _result_dirs(paths: Iterable[str | Path]) -> list[Path]:
    """The results directories found under ``paths``, each once, in the order met."""
    dirs: list[Path] = []
    for p in paths:
        for d in find_result_dirs(Path(p)):
            if d.resolve() not in [x.resolve() for x in dirs]:
                dirs.append(d)
    if not dirs:
        raise TouchbenchError("no results given")
    return dirs


def _read_scores(d: Path) -> tuple[pd.DataFrame, ResultStore | None]:
    """The scores of results directory ``d`` and, when it holds fragments alone, the store that merged them."""
    store = None
    if _fragments_only(d):  # fragments that are not what their tasks wrote are refused, naming them
        ResultStore(d).verify_fragments()
    try:
        if _fragments_only(d):  # merge on read (touchbench.results.store)
            store = ResultStore(d)
            s = store.read_scores()
        else:
            s = read_results_table(d / "scores.parquet")
    except Exception as e:
        raise TouchbenchError(f"{d / 'scores.parquet'}: cannot read: {type(e).__name__}: {e}") from None
    return s, store


def _labelled_scores(s: pd.DataFrame, d: Path, m: dict[str, Any], mid: str, mdesc: str) -> pd.DataFrame:
    """The scores of ``d`` with the columns that place them: source, machine, frame rate, scheme label,
    method id, table key and fold key (``m``: the run's manifest)."""
    sensor = (m.get("dataset") or {}).get("sensor") or {}
    scheme = _protocol_scheme(m)
    proto_seed = (m.get("protocol") or {}).get("seed")
    s = s.copy()
    s["source"] = str(d)
    s["machine"] = mid
    s["machine_desc"] = mdesc
    s["frame_rate"] = float(sensor.get("frame_rate")) if sensor.get("frame_rate") else np.nan
    s["scheme_label"] = scheme_label(scheme, fallback=str(s["scheme"].iloc[0])) if scheme is not None else s["scheme"].astype(str)
    variants = ["subject-id" if SUBJECT_ID_LEAK in str(x) else "" for x in s["leakage"]]
    s["method_id"] = [
        method_id(t, fp, cn, cp, ef, v)
        for t, fp, cn, cp, ef, v in zip(s["target"], s["feature_params"], s["classifier_name"],
                                        s["classifier_params"], s["early_frames"], variants)
    ]
    s["table_key"] = [  # a method adapted to the test data is never tabled with plain ones, nor two curves' points
        _short_hash([dh, t, sc] + ([a] if a else []) + ([f"curve={c}"] if c else []), 8)
        for dh, t, sc, a, c in zip(s["dataset_hash"], s["target"], s["scheme_label"], s["adaptation"].astype(str),
                                   s["curve"].astype(str) if "curve" in s else [""] * len(s))
    ]
    base_fold = s["fold"].astype(str).str.replace(_CROP_PREFIX, "", regex=True)
    on_curve = s["curve"].astype(str) != "" if "curve" in s else pd.Series(False, index=s.index)
    base_fold = base_fold.where(~on_curve, base_fold.str.replace(_CURVE_PREFIX, "", regex=True))
    s["fold_key"] = [f"{proto_seed}/{r}/{f}" for r, f in zip(s["repetition"], base_fold)]
    s["finished_at"] = s["finished_at"].astype(str) if "finished_at" in s else ""
    return s


def _read_predictions(d: Path, store: ResultStore | None) -> pd.DataFrame | None:
    """The predictions of results directory ``d`` (None: none, or unreadable)."""
    ppath = d / "predictions.parquet"
    try:
        if store is not None:
            return store.read_predictions()
        if ppath.is_file():
            return read_results_table(ppath)
    except Exception:
        return None
    return None


def _labelled_predictions(p: pd.DataFrame, s: pd.DataFrame, d: Path) -> pd.DataFrame:
    """The prediction columns of ``p`` with their task's method, fold key, seed, time and table (from ``s``)."""
    keep = [c for c in PREDICTION_COLUMNS if c in p.columns] + [c for c in p.columns if c.startswith(PROBA_PREFIX)]
    pp = p[keep].copy()
    info = s.drop_duplicates("task_id").set_index("task_id")[
        ["method_id", "fold_key", "repetition", "seed", "finished_at", "table_key"]]
    pp = pp.join(info, on="task_id", how="inner")
    pp["source"] = str(d)
    return pp


def _source_record(d: Path, m: dict[str, Any], s: pd.DataFrame, mid: str, mdesc: str,
                   changed: list[str]) -> dict[str, Any]:
    """What a results directory says about its run: protocol, machine, versions, design, looks, the
    files changed since the run wrote them (``changed``)..."""
    return {
        "path": str(d), "run_id": (m.get("run") or {}).get("run_id") or str(s["run_id"].iloc[0]),
        "protocol": (m.get("protocol") or {}).get("name") or str(s["protocol"].iloc[0]),
        "evaluation": (m.get("protocol") or {}).get("evaluation") or "", "scheme": _protocol_scheme(m),
        "protocol_path": (m.get("protocol") or {}).get("path"),
        "machine": mid, "machine_desc": mdesc, "dataset": str(s["dataset"].iloc[0]),
        "started_at": m.get("started_at"), "finished_at": m.get("finished_at"),
        "versions": m.get("packages") or {}, "touchbench_version": m.get("touchbench_version"),
        "git": m.get("git") or {}, "n_tasks": int(len(s)), "n_failed": int((s["status"] != "ok").sum()),
        "seconds": sum(float(x.get("seconds") or 0) for x in (m.get("sessions") or [])),
        "design": (m.get("protocol") or {}).get("design"),
        "design_captures": (m.get("protocol") or {}).get("design_captures"),
        "report": (m.get("protocol") or {}).get("report"),
        "looks": _looks(m, d), "test_set": (m.get("ledger") or {}).get("test_set"),
        "left_out": [n for n in (m.get("notes") or []) if str(n).startswith(LEFT_OUT)],
        "changed": changed,
    }


def _looks(manifest: dict[str, Any], folder: Path) -> Looks | None:
    """How often the run's test set was scored: the ledger its manifest names (relative to the
    results folder), the ledger of its results root and those earlier versions kept below it, not
    yet merged into it (None: the manifest names no ledger)."""
    info = manifest.get("ledger") or {}
    if not info.get("path") or not info.get("test_set"):
        return None
    root = results_root(folder)
    ledgers = [folder / info["path"]] + ([root / LEDGER_NAME, *old_ledgers(root)] if root is not None else [])
    return looks(ledgers, info["test_set"])


def _changed(d: Path, manifest: dict[str, Any], store: ResultStore | None) -> list[str]:
    """The warnings, logged here and kept for the tables' notes, of the merged files of ``d`` that are
    not those its run wrote (:func:`touchbench.results.checksums.changed_since_run`); none for a
    run read from its task fragments (``store``), whose merged files are not read."""
    changed = [] if store is not None else changed_since_run(d, manifest)
    if store is None and not (d / "manifest.json").is_file():
        changed.append(f"{d}: manifest.json is missing: these results cannot be verified against the files "
                       "their run wrote")
    for warning in changed:
        log.warning("%s", warning)
    return changed


def load_results(paths: Iterable[str | Path], *, predictions: bool = True) -> ResultSet:
    """Read and combine results directories (see the module docstring)."""
    dirs = _result_dirs(paths)
    score_frames, pred_frames, sources = [], [], []
    for d in dirs:
        s, store = _read_scores(d)
        if s.empty:
            continue
        m = read_manifest(d)
        changed = _changed(d, m, store)
        mid, mdesc = machine_id(m.get("platform"))
        s = _labelled_scores(s, d, m, mid, mdesc)
        p = _read_predictions(d, store)
        by_name = s["fold_key"].copy()
        if p is not None and len(p):
            keys = (
                p.groupby("task_id", sort=False)["capture_id"]
                .apply(lambda c: "c:" + hashlib.sha256("\n".join(sorted(map(str, c))).encode()).hexdigest()[:12])
            )
            s["fold_key"] = [keys.get(t, fk) for t, fk in zip(s["task_id"], s["fold_key"])]
        s["fold_key"] = _curve_keys(s, by_name)
        if p is not None and len(p) and predictions:
            pred_frames.append(_labelled_predictions(p, s, d))
        score_frames.append(s)
        sources.append(_source_record(d, m, s, mid, mdesc, changed))
    if not score_frames:
        raise TouchbenchError(f"no scores in {', '.join(map(str, dirs))} (every run is empty)")
    scores = pd.concat(score_frames, ignore_index=True, sort=False)
    scores["early_frames"] = scores["early_frames"].astype("float64")
    preds = None
    if predictions and pred_frames:
        preds = pd.concat(pred_frames, ignore_index=True, sort=False)
    return ResultSet(scores=scores, predictions=preds, sources=sources)
