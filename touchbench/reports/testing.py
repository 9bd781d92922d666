"""Hand-built results directories for testing the reports (not used by a run).

:func:`write_fake_run` writes ``scores.parquet``, ``predictions.parquet``,
``confusion.parquet``, ``confusion_pooled.parquet`` and ``manifest.json`` in
the engine's layout (columns and schema version of
:mod:`touchbench.results.store`) from a compact description: the captures,
the folds (capture ids tested in each), and per method which test captures
it gets right. Scores are computed from those predictions with the engine's
own metric function, so a test can state accuracies by construction. The
classifier seed of a task is derived from its labels and fold, as the
engine's is, so the same method under another label is a replicate.

A run on a data curve (``curve="subjects"`` or ``"calibration"``) names
its folds as the engine does, the point before the base fold
(``n3#1/subject=s01``: 3 training subjects, draw 1; ``k2#0/subject=s01``: 2
labelled captures per class, draw 0): the scores get the point's ``curve``,
``curve_size`` and ``curve_draw`` and the base fold's name as ``fold_group``.
"""

from __future__ import annotations

import json
import zlib
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd
import yaml

from ..core.hashing import canonical_json
from ..scoring.metrics import metrics
from ..protocols.schemes import CurvePoint, curve_columns
from ..results.store import PREDICTED, SCHEMA_VERSION, TRUE, confusion_table, task_row, write_results_table

__all__ = ["FakeMethod", "write_fake_run"]

DEFAULT_PLATFORM = {"platform": "Linux-test-x86_64", "machine": "x86_64", "processor": "x86_64", "python": "3.11",
                    "cpu_count": 2}


class FakeMethod(dict):
    """A method of a fake run.

    ``wrong``: fold name -> capture ids predicted wrongly (predicted as the
    next class in sorted order); ``predicted``: capture id -> label, for any
    confusion (overrides ``wrong``); timings per fold (constant or a list):
    ``latency_cpu_ms`` as ``latency_ms`` unless given; ``load_avg``: the
    machine's load average while it ran (on the platform's ``cpu_count`` CPUs); ``adaptation``:
    what the method adapted to at test time (the results' column; "" for a plain method); ``live``: fold
    name -> the stream task's payload (the scores' ``live`` column, :mod:`touchbench.engine.live`).
    """

    def __init__(self, features: str, classifier: str, *, classifier_name: str | None = None,
                 classifier_params: dict[str, Any] | None = None, feature_params: list | None = None,
                 wrong: dict[str, Sequence[str]] | None = None, latency_ms: float | Sequence[float] = 1.0,
                 latency_cpu_ms: float | Sequence[float] | None = None, load_avg: float = 0.0,
                 fit_seconds: float | Sequence[float] = 0.5, feature_seconds_per_capture: float | Sequence[float] = 1e-3,
                 early_frames: int | None = None, failed_folds: Sequence[str] = (),
                 predicted: dict[str, str] | None = None, adaptation: str = "",
                 live: dict[str, dict[str, Any]] | None = None):
        super().__init__(
            features=features, classifier=classifier, classifier_name=classifier_name or classifier,
            classifier_params=classifier_params or {},
            feature_params=feature_params if feature_params is not None else [[f, {}] for f in features.split("+")],
            wrong={k: list(v) for k, v in (wrong or {}).items()}, latency_ms=latency_ms,
            latency_cpu_ms=latency_ms if latency_cpu_ms is None else latency_cpu_ms, load_avg=load_avg,
            fit_seconds=fit_seconds,
            feature_seconds_per_capture=feature_seconds_per_capture, early_frames=early_frames,
            failed_folds=list(failed_folds), predicted=dict(predicted or {}), adaptation=adaptation,
            live=dict(live or {}),
        )


def _per_fold(v: Any, i: int) -> float:
    return float(v[i]) if isinstance(v, (list, tuple, np.ndarray)) else float(v)


def _curve_place(fold: str, curve: str) -> tuple[dict[str, Any], str]:
    """The curve columns and base fold of fold name ``fold`` (``n3#1/subject=s01`` on a curve)."""
    if not curve:
        return curve_columns(None), fold
    point, base = fold.split("/", 1)
    size, draw = point[1:].split("#")
    return curve_columns(CurvePoint(curve, float(size), int(draw))), base


def write_fake_run(out: str | Path, captures: pd.DataFrame, folds: dict[str, Sequence[str]], methods: list[FakeMethod], *,
                   dataset: str = "fake", dataset_hash: str = "d" * 64, scheme: Any = None, target: str = "gesture",
                   seed: int = 0, run_id: str = "run1", protocol: str = "fake-protocol",
                   platform: dict[str, Any] | None = None, frame_rate: float | None = None,
                   finished_at: str = "2026-01-01T00:00:00+00:00", seconds: float = 1.0, repetition: int = 0,
                   curve: str = "") -> Path:
    """Write a results directory (see the module docstring); returns its path.

    ``frame_rate``: the fake sensor's (None: the manifest gives none, so
    reports cannot turn frames into seconds); ``repetition``: the tasks' repetition (another one
    gives every task another classifier seed, as the engine's repetitions do); ``curve``: the data
    curve the folds are points of ("": none)."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    scheme = scheme if scheme is not None else {"name": "kfold", "k": len(folds)}
    caps = captures.set_index("capture_id")
    classes = sorted(set(caps[target].astype(str)))
    nxt = {c: classes[(i + 1) % len(classes)] for i, c in enumerate(classes)}
    score_rows, pred_frames = [], []
    for m_i, m in enumerate(methods):
        for f_i, (fold, ids) in enumerate(folds.items()):
            ids = list(ids)
            task_id = f"{run_id}-t{m_i}-{f_i}-{m['features']}-{m['classifier']}"
            fold_name = fold if m["early_frames"] is None else f"first{m['early_frames']}f/{fold}"
            place, group = _curve_place(fold, curve)
            base = task_row({
                "task_id": task_id, "protocol": protocol,
                "dataset": dataset, "dataset_hash": dataset_hash, "target": target,
                "scheme": scheme if isinstance(scheme, str) else scheme["name"], "repetition": repetition,
                "fold": fold_name, "fold_group": group,
                "early_frames": np.nan if m["early_frames"] is None else float(m["early_frames"]),
                "features": m["features"], "feature_sets": "+".join(n for n, _ in m["feature_params"]),
                "feature_params": canonical_json(m["feature_params"]), "classifier": m["classifier"],
                "classifier_name": m["classifier_name"], "classifier_params": canonical_json(m["classifier_params"]),
                "seed": zlib.crc32(f"{m['features']}|{m['classifier']}|{fold_name}".encode()
                                   + (f"|{repetition}".encode() if repetition else b"")),
                "n_train": len(caps) - len(ids), "n_test": len(ids), "leakage": "", "selection": "",
                "adaptation": m["adaptation"], **place,
            })
            base.update(run_id=run_id, protocol_hash="p" * 64, n_classes_train=len(classes), finished_at=finished_at)
            if fold in m["failed_folds"]:
                base.update(status="failed", error="ValueError: fake", accuracy=np.nan, balanced_accuracy=np.nan,
                            macro_f1=np.nan, feature_seconds_per_capture=np.nan, feature_fit_seconds=np.nan,
                            fit_seconds=np.nan, predict_seconds=np.nan, latency_ms=np.nan)
                score_rows.append(base)
                continue
            true = caps.loc[ids, target].astype(str).to_numpy()
            wrong = set(m["wrong"].get(fold, []))
            pred = np.array([m["predicted"].get(cid, nxt[t] if cid in wrong else t) for cid, t in zip(ids, true)],
                            dtype=object)
            base.update(status="ok", error="", **metrics(true, pred),
                        feature_seconds_per_capture=_per_fold(m["feature_seconds_per_capture"], f_i),
                        feature_fit_seconds=0.0, fit_seconds=_per_fold(m["fit_seconds"], f_i), predict_seconds=0.01,
                        latency_ms=_per_fold(m["latency_ms"], f_i), latency_cpu_ms=_per_fold(m["latency_cpu_ms"], f_i),
                        load_avg=m["load_avg"], usable_cpus=(platform or DEFAULT_PLATFORM).get("cpu_count"),
                        live=json.dumps(m["live"][fold]) if fold in m["live"] else "")
            score_rows.append(base)
            pred_frames.append(pd.DataFrame({
                "run_id": run_id, "task_id": task_id, "repetition": repetition, "fold": fold_name, "fold_group": group,
                "early_frames": base["early_frames"], "features": m["features"], "classifier": m["classifier"],
                "capture_id": ids, "subject": caps.loc[ids, "subject"].astype(str).to_numpy(),
                "gesture": caps.loc[ids, "gesture"].astype(str).to_numpy(), TRUE: true, PREDICTED: pred.astype(str),
                "correct": true == pred.astype(str), "leakage": "",
            }))
    return _write_files(out, pd.DataFrame(score_rows), pred_frames, methods, len(caps), dict(
        dataset=dataset, dataset_hash=dataset_hash, scheme=scheme, target=target, seed=seed, run_id=run_id,
        protocol=protocol, platform=platform, frame_rate=frame_rate, finished_at=finished_at, seconds=seconds))


def _write_files(out: Path, scores: pd.DataFrame, pred_frames: list[pd.DataFrame], methods: list[FakeMethod],
                 n_captures: int, run: dict[str, Any]) -> Path:
    """The results files and the manifest of a fake run (``run``: :func:`write_fake_run`'s keywords)."""
    dataset, dataset_hash, scheme, target = run["dataset"], run["dataset_hash"], run["scheme"], run["target"]
    seed, run_id, protocol, platform = run["seed"], run["run_id"], run["protocol"], run["platform"]
    frame_rate, finished_at, seconds = run["frame_rate"], run["finished_at"], run["seconds"]
    preds = pd.concat(pred_frames, ignore_index=True) if pred_frames else pd.DataFrame()
    write_results_table(out / "scores.parquet", scores)
    write_results_table(out / "predictions.parquet", preds)
    write_results_table(out / "confusion.parquet", confusion_table(preds))
    write_results_table(out / "confusion_pooled.parquet", confusion_table(preds, pooled=True))
    text = yaml.safe_dump({"name": protocol, "dataset": dataset, "target": target, "scheme": scheme, "seed": seed,
                           "features": [m["features"].split("+") for m in methods],
                           "classifiers": [m["classifier_name"] for m in methods]}, sort_keys=False)
    manifest = {
        "touchbench_version": "test", "results_schema": SCHEMA_VERSION, "platform": platform or DEFAULT_PLATFORM, "packages": {"python": "3.11"},
        "run": {"run_id": run_id, "results_dir": str(out)},
        "protocol": {"name": protocol, "text": text, "seed": seed, "scheme": scheme if isinstance(scheme, str) else scheme["name"]},
        "dataset": {"ref": dataset, "hash": dataset_hash, "captures": n_captures,
                    "sensor": {"name": "fake", "grid": [8, 8], "frame_rate": frame_rate}},
        "started_at": finished_at, "finished_at": finished_at,
        "sessions": [{"started_at": finished_at, "finished_at": finished_at, "seconds": seconds}],
        "tasks": {"total": len(scores)}, "notes": [], "expected": [],
    }
    (out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return out
