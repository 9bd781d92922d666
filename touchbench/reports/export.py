"""Results in other tools' formats: tsml-eval's classifier results files.

tsml-eval (and aeon's benchmarking, which reads the same files) keeps one file per classifier,
problem and resample::

    OUT/<classifier>/Predictions/<problem>/testResample<i>.csv

line 1 ``problem,classifier,TEST,i,MILLISECONDS,description``; line 2 the classifier's parameters;
line 3 ``accuracy,fit time,predict time,benchmark time,memory,number of classes,train estimate
method,train estimate time,fit and estimate time``; then one line per test case: the true class's
index, the predicted class's index, an empty field and the class probabilities (the format of
``tsml_eval.utils.results_writing.write_classification_results``, read back in the tests by its
``load_classifier_results``).

Mapping: a *classifier* is a method (features and classifier, ``msd-gaus-rf``), a *problem* a
table of the results (its dataset; dataset, scheme and target when several tables share a dataset),
a *resample* one (repetition, fold) of the scheme, numbered 0, 1, ... in the order of the run's
folds, repetition after repetition. Per scheme, a resample is:

==========================  ============================================================
``challenge``               the single train/test split (one per repetition)
``loso``                    one subject (or ``column`` value) left out
``kfold``                   one fold of one repeat (``repeats`` x ``k`` resamples)
``within-subject``          one fold inside one subject
``leave-recording-out``     one direction: train on one recording, test on the other
``person-independent``      one party of subjects tested
``transfer``                one ordered pair of groups (``A->B``)
``early``                   a resample of its base scheme; each length of cut is a classifier
                            of its own (``... @ 8 frames``)
==========================  ============================================================

The description of line 1 names the fold and repetition, and the class indices are
positions in the sorted class names, listed there too. Probabilities are the classifier's, or 1 for
the predicted class when it gives none; times are the task's fit and predict times in milliseconds;
benchmark time and memory are not measured (-1).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..core.atomic import atomic_write_bytes
from ..results.store import PREDICTED, PROBA_PREFIX, TRUE
from .labels import method_labels
from .leaderboard import Leaderboard
from .figures import slug, unique_stem
from .results import ResultSet

__all__ = ["export_tsml"]


def _name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._+-]+", "-", text).strip("-") or "x"


def export_tsml(rs: ResultSet, lbs: list[Leaderboard], out: str | Path) -> list[Path]:
    """Write every method's test predictions of every table as tsml-eval results files; returns them."""
    if rs.predictions is None or rs.predictions.empty:
        raise ValueError("no predictions to export (predictions.parquet is missing)")
    out = Path(out)
    written: list[Path] = []
    for lb, problem in zip(lbs, _problems(lbs)):
        taken: set[str] = set()
        labels = {mid: unique_stem(_name(lab.replace(" / ", "-")), taken)
                  for mid, lab in method_labels(lb.rows).items()}
        preds = rs.predictions[rs.predictions["table_key"] == lb.key]
        scores = rs.scores[(rs.scores["table_key"] == lb.key) & (rs.scores["status"] == "ok")]
        classes = sorted(set(preds[TRUE].astype(str)) | set(preds[PREDICTED].astype(str)))
        index = {c: i for i, c in enumerate(classes)}
        for mid, tasks in scores.groupby("method_id", sort=False):
            estimator = labels.get(mid) or _name(str(mid))
            tasks = tasks.drop_duplicates("task_id")
            for i, (_, task) in enumerate(tasks.iterrows()):
                p = preds[preds["task_id"] == task["task_id"]]
                if p.empty:
                    continue
                true = p[TRUE].astype(str).map(index).to_numpy()
                pred = p[PREDICTED].astype(str).map(index).to_numpy()
                cols = [f"{PROBA_PREFIX}{c}" for c in classes]
                if all(c in p.columns for c in cols) and p[cols].notna().all().all():
                    P = p[cols].to_numpy(dtype=np.float64)
                else:  # no probabilities: the prediction, certain
                    P = np.eye(len(classes))[pred]
                acc = float(np.mean(true == pred))
                line1 = (f"{problem},{estimator},TEST,{i},MILLISECONDS,fold {task['fold']} repetition "
                         f"{int(task['repetition'])}; classes {' '.join(classes)}").replace("\n", " ")
                line2 = str(task.get("classifier_params", "")).replace("\n", " ")
                fit_ms = _ms(task.get("fit_seconds"))
                pred_ms = _ms(task.get("predict_seconds"))
                line3 = f"{acc},{fit_ms},{pred_ms},-1,-1,{len(classes)},,-1,-1"
                rows = [f"{t},{q},," + ",".join(repr(float(v)) for v in probs) for t, q, probs in zip(true, pred, P)]
                path = out / estimator / "Predictions" / problem / f"testResample{i}.csv"
                atomic_write_bytes(path, ("\n".join([line1, line2, line3, *rows]) + "\n").encode())
                written.append(path)
    return written


def _problems(lbs: list[Leaderboard]) -> list[str]:
    """A problem name per table: its dataset (a file's name without its suffix) when the tables'
    datasets differ, else the table's slug (dataset, scheme, target...); unique either way."""
    names = [Path(lb.dataset).stem if lb.dataset.endswith((".parquet", ".csv", ".gz")) else lb.dataset
             for lb in lbs]
    distinct = len(set(names)) == len(names)
    taken: set[str] = set()
    return [unique_stem(_name(n) if distinct else slug(lb), taken) for n, lb in zip(names, lbs)]


def _ms(seconds) -> int:
    try:
        v = float(seconds)
    except (TypeError, ValueError):
        return -1
    return int(round(1000 * v)) if np.isfinite(v) else -1
