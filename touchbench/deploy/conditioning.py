"""The conditioning of a protocol's features for LDA: the condition number of the pooled
within-class covariance (:mod:`touchbench.classifiers.covariance`) of each feature combination
the protocol evaluates, on the captures ``touchbench train`` would fit on (the evaluation's
training side, or the training part of one fold), features fitted there as a task fits them:
a feature set that learns nothing is read from the run engine's feature cache when a run computed
it (the same entry a run of the protocol reads), else computed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import TouchbenchError
from ..engine.cache import FeatureCache
from ..engine.planning import plan_run, prepare_evaluation, training_side
from ..engine.tasks import SetSpec
from ..classifiers.covariance import condition_number, pooled_within_class_covariance
from ..features.base import make_feature_set
from ..protocols.library import find_protocol
from ..protocols.loading import load_protocol
from .train import _evaluation, _fold

__all__ = ["within_class_conditioning"]


def within_class_conditioning(protocol: str | Path, *, evaluation: str | None = None,
                              fold: str | None = None) -> list[dict]:
    """One row per feature combination of the protocol (in its order): ``features``, ``captures``,
    ``classes``, ``columns``, ``rank`` (numpy's, of the covariance) and ``condition`` (``inf`` when
    singular); ``selection`` says which captures."""
    proto = _evaluation(load_protocol(find_protocol(str(protocol))), evaluation)
    prepared = prepare_evaluation(proto)
    ds = prepared.dataset
    if fold is not None:
        chosen = _fold(proto, prepared, fold)
        idx, selection = np.asarray(chosen.train, dtype=np.int64), f"training part of fold {chosen.name}"
    else:
        idx, selection = training_side(prepared), f"training side of {proto.scheme.name}"
    captures = [ds.captures[i] for i in idx]
    y = ds.meta[proto.target].astype(str).to_numpy()[idx]
    plan = plan_run(proto, dataset=prepared.source)  # the tasks' feature sets, with their cache keys
    combos: dict[str, tuple[SetSpec, ...]] = {}
    for t in plan.tasks:
        if t.sets:
            combos.setdefault(t.method.features_label, t.sets)
    if not combos:
        raise TouchbenchError(f"protocol {proto.name!r} has no feature sets (its methods take the captures)")
    cache = FeatureCache(plan.cache_root)
    rows = []
    for label, sets in combos.items():
        X = np.hstack([_columns(s, cache, ds.sensor, captures, y, idx) for s in sets])
        cov = pooled_within_class_covariance(X, y)
        rows.append({"features": label, "captures": len(idx), "classes": len(np.unique(y)), "columns": X.shape[1],
                     "rank": int(np.linalg.matrix_rank(cov)), "condition": condition_number(cov),
                     "selection": selection})
    return rows


def _columns(s: SetSpec, cache: FeatureCache, sensor, captures, y, idx) -> np.ndarray:
    """One feature set's float64 columns for the chosen captures: its cache entry when there is one
    (a set that learns nothing), else fitted on those captures and computed."""
    got = cache.load(s.key_full) if not s.fold_dependent and s.key_full else None
    if got is not None:
        return np.asarray(got[0][idx], dtype=np.float64)
    return np.asarray(make_feature_set(s.name, s.params, sensor).fit(captures, y).transform(captures),
                      dtype=np.float64)
