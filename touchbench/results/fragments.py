"""What keeps a task's fragments honest between the task that wrote them and the tables that show them.

- **Checksums**: when a task finishes, after its predictions and scores fragments, the SHA-256 of
  each is written beside them (``fragments/<task>.sha256``, JSON, atomically). A fragment that no
  longer matches is not the task's result: ``run`` computes that task again (a run note names it),
  and a report reading an interrupted run's fragments refuses it, naming the file. A task without
  the file (results of versions that did not write it, or a run killed between the two writes) is
  read as before, and checked as below.
- **Scores agree with their predictions**: a succeeded task's ``accuracy`` must be the share of its
  predictions whose predicted label is the true one; a task whose scores say otherwise is refused
  (:func:`check_scores_agree`), naming its scores fragment.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.atomic import atomic_path
from ..core.errors import TouchbenchError
from .checksums import file_sha256

__all__ = ["FragmentError", "check_scores_agree", "checksum_path", "checksum_problem", "write_checksums"]

_KINDS = ("scores", "predictions")


class FragmentError(TouchbenchError):
    """A task's fragment that is not what its task wrote."""


def checksum_path(fragments: Path, task_id: str) -> Path:
    return fragments / f"{task_id}.sha256"


def _fragment(fragments: Path, task_id: str, kind: str) -> Path:
    return fragments / f"{task_id}.{kind}.parquet"


def write_checksums(fragments: Path, task_id: str) -> None:
    """Record the SHA-256 of the task's fragments as they are now (the scores one written last)."""
    sums = {k: file_sha256(p) if (p := _fragment(fragments, task_id, k)).is_file() else None for k in _KINDS}
    with atomic_path(checksum_path(fragments, task_id)) as tmp:
        Path(tmp).write_text(json.dumps(sums, sort_keys=True))


def checksum_problem(fragments: Path, task_id: str) -> str:
    """Why the task's fragments are not those its task wrote ("" when they are, or when no checksum
    was recorded)."""
    path = checksum_path(fragments, task_id)
    if not path.is_file():
        return ""
    try:
        sums = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return "its checksum file is unreadable"
    for kind in _KINDS:
        p, want = _fragment(fragments, task_id, kind), (sums or {}).get(kind) if isinstance(sums, dict) else None
        have = file_sha256(p) if p.is_file() else None
        if have != want:
            return (f"{p.name} does not match the checksum written when its task finished (edited or damaged)"
                    if have is not None else f"{p.name}, written when its task finished, is missing")
    return ""


def check_scores_agree(scores: pd.DataFrame, predictions: pd.DataFrame, fragments: Path,
                       true: str = "true_label", predicted: str = "predicted_label") -> None:
    """Refuse a succeeded task whose ``accuracy`` is not the share of its predictions that are right
    (a live stream's task, scored frame by frame, and a task without predictions are not checked)."""
    if scores.empty or predictions.empty or "accuracy" not in scores:
        return
    right = (predictions[true].astype(str) == predictions[predicted].astype(str)).groupby(predictions["task_id"])
    share = right.mean()
    live = scores["live"].astype(str) if "live" in scores else pd.Series("", index=scores.index)
    for tid, status, acc, stream in zip(scores["task_id"], scores["status"], scores["accuracy"], live):
        if status != "ok" or stream or tid not in share.index or not np.isfinite(acc):
            continue
        if not np.isclose(float(acc), float(share[tid]), rtol=0.0, atol=1e-9):
            raise FragmentError(
                f"{_fragment(fragments, tid, 'scores')}: its accuracy {float(acc):.6g} is not that of its "
                f"predictions ({float(share[tid]):.6g}, {_fragment(fragments, tid, 'predictions').name}): the "
                "scores were edited or damaged; remove the task's fragments and run the protocol again")
