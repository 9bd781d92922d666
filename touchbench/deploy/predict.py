"""``touchbench predict``: label the captures of a dataset with a trained model.

The data is anything a touchbench reader reads: a registered dataset name,
``scene:NAME``, a touchbench Parquet file, or a file in one of the
registered file formats (:mod:`touchbench.datasets.formats`; what a file
does not say, such as the ``long`` format's grid, frame rate and value
range, is the model's sensor's). The data's sensor must match the model's
(:func:`touchbench.deploy.model.sensor_differences`), or nothing is labelled.

A model trained on windows labels a capture from the windows of the
model's lengths cut from it (every training hop), by the mean of their
probabilities; a capture shorter than every window is labelled whole
(``whole=True`` labels every capture whole). Otherwise the label is the
classifier's own prediction and the probabilities are its
``predict_proba``.

A model that adapts to each session from its unlabelled captures
(``touch-et-adapt``: :attr:`.model.TrainedModel.adapts_to_session`) is
adapted to the captures of the data it is given before labelling them:
each subject's captures as a session where the data has a ``subject``
column, else all of them as one (:func:`adaptation_sessions`); the command
says so (:func:`adaptation_text`), and warns of a session of one capture, which it
centres to zeros (:func:`adaptation_warning`).

A model file records a checksum of every capture it was trained on: the
``trained_on`` column says which captures of the data the model has seen
(the same frames, whichever reader read them), and :func:`accuracy_text`
scores the others only, counting the seen ones apart. A model file without
those checksums (an older one) gets no ``trained_on`` column, and its
accuracy says it cannot be separated.

The same capture cut with another window, or with one value changed, has
other frames: the model file also records its training subjects, recordings
(subject and capture id) and sessions, and the columns
``trained_on_subject``, ``trained_on_recording`` and (where the data and the
model have sessions) ``trained_on_session`` say which captures share them.
:func:`accuracy_text` scores the captures of unseen subjects apart from
those of subjects the model was trained on, and says that the latter's
accuracy is not on unseen people; a model file that does not record its
subjects says they may be people it was trained on.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..catalog import load_dataset
from ..classifiers.adapt import adapt_each_session
from ..core.atomic import atomic_write_bytes, atomic_write_parquet
from ..core.errors import TouchbenchError
from ..datasets.formats import FORMATS
from ..datasets.model import TouchDataset
from ..results.store import PREDICTED, PROBA_PREFIX, TRUE
from .model import TrainedModel
from ..datasets.windows import cut_windows

__all__ = ["TRAINED_ON", "accuracy_text", "adaptation_sessions", "adaptation_text", "adaptation_warning", "predict_dataset", "read_data",
           "write_table"]

#: the column that says whether the model was trained on a capture
TRAINED_ON = "trained_on"


def read_data(source: str, fmt: str = "auto", model: TrainedModel | None = None, **options) -> TouchDataset:
    """Read ``source`` in the registered file format ``fmt`` with its ``options``
    (``auto``: :func:`touchbench.catalog.load_dataset`); the model's sensor fills what the file does not say."""
    if fmt == "auto":
        given = sorted(k for k, v in options.items() if v is not None)
        if given:
            raise TouchbenchError(f"--{given[0].replace('_', '-')} goes with --format (the reader it is for)")
        return load_dataset(source)
    return FORMATS.get(fmt).read(source, like=None if model is None else model.sensor, **options)


def predict_dataset(model: TrainedModel, ds: TouchDataset, *, whole: bool = False, source: str | None = None) -> pd.DataFrame:
    """One row per capture: id, subject, true label (if known), predicted, probability, ``proba_<class>``."""
    model.check_sensor(ds.sensor, source or ds.name)
    classes = [str(c) for c in model.classes]
    w = model.manifest.get("windows")
    sessions = adaptation_sessions(model, ds)
    if w and not whole:
        windows, src = cut_windows(ds.captures, w["lengths_frames"], w["train_hop_frames"])
        Pw, _ = _label(model, model.transform(windows), None if sessions is None else sessions[src])
        P = np.zeros((len(ds), len(classes)))
        np.add.at(P, src, Pw)
        P /= np.bincount(src, minlength=len(ds))[:, None]
        pred = np.array(classes, dtype=object)[np.argmax(P, axis=1)]
        n_windows = np.bincount(src, minlength=len(ds))
    else:
        P, pred = _label(model, model.transform(ds.captures), sessions)
        n_windows = np.ones(len(ds), dtype=np.int64)
    meta = ds.meta
    out = pd.DataFrame({"capture_id": meta["capture_id"].astype(str).to_numpy()})
    if "subject" in meta:
        out["subject"] = meta["subject"].astype(str).to_numpy()
    target = model.manifest.get("target", "gesture")
    if target in meta:
        out[TRUE] = meta[target].astype(str).to_numpy()
    out[PREDICTED] = np.asarray(pred, dtype=object).astype(str)
    col = {c: i for i, c in enumerate(classes)}
    out["probability"] = P[np.arange(len(ds)), [col[p] for p in out[PREDICTED]]]
    out["n_windows"] = n_windows
    seen = model.seen_in_training(ds.captures)
    if seen is not None:
        out[TRAINED_ON] = seen
    for what, hit in (model.seen_people(meta) or {}).items():
        out[f"{TRAINED_ON}_{what}"] = hit
    for i, c in enumerate(classes):
        out[f"{PROBA_PREFIX}{c}"] = P[:, i]
    return out


def adaptation_sessions(model: TrainedModel, ds: TouchDataset) -> np.ndarray | None:
    """The session each capture is adapted with, for a model that adapts to sessions: its subject
    (every dataset has a ``subject`` column); None for any other model."""
    return ds.meta["subject"].astype(str).to_numpy() if model.adapts_to_session else None


def adaptation_text(model: TrainedModel, ds: TouchDataset) -> str | None:
    """What ``predict`` says of a model that adapts to sessions (None for any other model)."""
    sessions = adaptation_sessions(model, ds)
    if sessions is None:
        return None
    n = len(np.unique(sessions))
    return (f"adapted to the data's unlabelled captures, each of its {n} subject{'s' if n > 1 else ''} as a "
            "session: these labels used the test captures themselves, not only the model")


def adaptation_warning(model: TrainedModel, ds: TouchDataset) -> str | None:
    """For a model that adapts to sessions: the sessions of one capture only, which it centres to
    zeros (one capture cannot give a session's statistics), so that every such capture gets the
    same label whatever it holds; None when there is none (or the model does not adapt)."""
    sessions = adaptation_sessions(model, ds)
    if sessions is None:
        return None
    names, counts = np.unique(sessions, return_counts=True)
    alone = [str(n) for n, c in zip(names, counts) if c == 1]
    if not alone:
        return None
    shown = ", ".join(alone[:5]) + (f" and {len(alone) - 5} more" if len(alone) > 5 else "")
    return (f"{len(alone)} of the data's {len(names)} subject(s) have one capture only ({shown}): one capture cannot "
            "give a session's statistics, so the model centres it to zeros and labels every such capture alike, "
            "whatever it holds; give the model several captures of each subject")


def _label(model: TrainedModel, X: np.ndarray, sessions: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """``(probabilities, labels)`` of the feature rows ``X``; with ``sessions`` the model is adapted
    to each session's rows before they are labelled (:func:`adapt_each_session`)."""
    if sessions is None:
        return model.proba_from_features(X, fast=True), model.predict_from_features(X)
    P = np.zeros((len(X), len(model.classes)), dtype=np.float64)
    pred = np.empty(len(X), dtype=object)
    for rows in adapt_each_session(model.estimator, X, sessions):
        P[rows] = model.proba_from_features(X[rows], fast=True)
        pred[rows] = model.predict_from_features(X[rows])
    return P, pred


def accuracy_text(model: TrainedModel, table: pd.DataFrame) -> str | None:
    """The accuracy line of ``predict``: on the captures of the model's classes it was not trained
    on, the seen ones counted apart, those of subjects it was trained on scored apart (never called
    unseen); None when the data has no true labels of the model's classes."""
    if TRUE not in table.columns:
        return None
    known = table[TRUE].isin([str(c) for c in model.classes]).to_numpy()
    correct = (table[TRUE] == table[PREDICTED]).to_numpy()
    if TRAINED_ON not in table.columns:
        if not known.any():
            return None
        return (f"accuracy {100 * correct[known].mean():.1f} % on {int(known.sum())} captures of known classes "
                "(this model file does not record the captures it was trained on: accuracy on unseen captures "
                "cannot be separated)")
    seen = table[TRAINED_ON].to_numpy(dtype=bool)
    scored = known & ~seen
    apart = f"{int(seen.sum())} captures the model was trained on are not scored" if seen.any() else ""
    if not scored.any():
        return "no unseen captures of the model's classes to score" + (f"; {apart}" if apart else "")
    return "; ".join([*_scores_by_subject(table, scored, correct), *([apart] if apart else [])])


def _scores_by_subject(table: pd.DataFrame, scored: np.ndarray, correct: np.ndarray) -> list[str]:
    """The accuracy on the scored captures of subjects the model never saw, and apart, on those of
    subjects it was trained on (saying how many are its training recordings or sessions)."""
    col = f"{TRAINED_ON}_subject"
    if col not in table.columns:
        return [f"accuracy {100 * correct[scored].mean():.1f} % on {int(scored.sum())} captures the model was not "
                "trained on (this model file does not record its training subjects: they may be people it was "
                "trained on)"]
    known_subject = table[col].to_numpy(dtype=bool)
    out = []
    new, old = scored & ~known_subject, scored & known_subject
    if new.any():
        out.append(f"accuracy {100 * correct[new].mean():.1f} % on {int(new.sum())} captures of unseen subjects")
    if old.any():
        same = [f"{int((old & table[f'{TRAINED_ON}_{what}'].to_numpy(dtype=bool)).sum())} of them {label}"
                for what, label in (("recording", "recordings it was trained on, with other frames"),
                                    ("session", "from sessions it was trained on"))
                if f"{TRAINED_ON}_{what}" in table.columns]
        out.append(f"accuracy {100 * correct[old].mean():.1f} % on {int(old.sum())} captures of subjects the model "
                   f"was trained on{' (' + '; '.join(same) + ')' if same else ''}: this accuracy is not on "
                   "unseen people")
    return out


def write_table(df: pd.DataFrame, path: str | Path) -> Path:
    """CSV or Parquet by suffix, written atomically."""
    path = Path(path)
    if path.suffix == ".parquet":
        atomic_write_parquet(path, df)
    else:
        atomic_write_bytes(path, df.to_csv(index=False).encode())
    return path
