"""``touchbench train``: fit one method of a protocol on its data and save it.

A *method* is what a leaderboard row names: a feature combination label and
a classifier label of the protocol, written ``FEATURES/CLASSIFIER`` (for
example ``msd+sd/gaus-rf``, or ``sd/rf100`` for a classifier entry labelled
``rf100``); the labels are those of the run engine's results
(:meth:`Protocol.combinations`, :meth:`Protocol.classifier_entries`).

The training data is the protocol's dataset after its filters, and then
either all of it, or the training part of one fold of the protocol's scheme
(``fold="subject=s01"``, or ``"s01"`` for short, under LOSO: every
subject but s01; ``fold="challenge"``
under the challenge split: the released training set), optionally narrowed
further by ``--where COL=V1,V2`` and ``--exclude COL=V1,V2``.

Seeds: the classifier's ``random_state`` is derived from the protocol seed
as the engine derives it. For a fold it is the seed of that fold's task in
repetition 0, so ``train --fold F`` fits the same classifier, on the same
features, as the run engine did for fold F (their test predictions agree);
for all the data it is ``derive_seed(seed, "train", features, classifier)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np
import pandas as pd

from ..core.errors import TouchbenchError
from ..core.suggest import did_you_mean
from ..engine.runner import plan_run
from ..methods import resolve_entry
from ..protocols.library import find_protocol
from ..protocols.schema import load_protocol
from ..protocols.seeding import derive_seed
from .model import TrainedModel, fit_model

__all__ = ["parse_selection", "select", "train_from_protocol"]


def parse_selection(items: Sequence[str], option: str) -> dict[str, list[str]]:
    """``["subject=s01,s02", ...]`` -> ``{"subject": ["s01", "s02"]}``."""
    out: dict[str, list[str]] = {}
    for item in items:
        col, sep, values = item.partition("=")
        if not sep or not col.strip() or not values.strip():
            raise TouchbenchError(f"{option} {item!r}: expected COLUMN=VALUE[,VALUE...], e.g. subject=s01")
        out.setdefault(col.strip(), []).extend(v.strip() for v in values.split(",") if v.strip())
    return out


def select(meta: pd.DataFrame, where: dict[str, list[str]], exclude: dict[str, list[str]]) -> np.ndarray:
    """Positions kept by ``where`` (values to keep) and ``exclude`` (values to drop)."""
    keep = np.ones(len(meta), dtype=bool)
    for spec, include, opt in ((where, True, "--where"), (exclude, False, "--exclude")):
        for col, values in spec.items():
            if col not in meta.columns:
                raise TouchbenchError(f"{opt}: the dataset has no column {col!r} (columns: {', '.join(map(str, meta.columns))})")
            col_vals = np.array([str(v) for v in meta[col].tolist()], dtype=object)
            unknown = sorted(set(values) - set(col_vals))
            if unknown:
                raise TouchbenchError(f"{opt}: {col} has no value {', '.join(map(repr, unknown))} "
                                      f"(values: {', '.join(sorted(set(col_vals)))})")
            hit = np.isin(col_vals, values)
            keep &= hit if include else ~hit
    return np.flatnonzero(keep)


def _choose(proto, method: str | None):
    choices = proto.entries()
    names = [f"{c.label}/{k.label}" for c, k in choices]
    if method is None:
        if len(choices) == 1:
            return choices[0]
        raise TouchbenchError(f"protocol {proto.name!r} has {len(choices)} methods; choose one with --method "
                              f"({', '.join(names)})")
    if method in names:
        return choices[names.index(method)]
    hint = did_you_mean(method, names, cutoff=0.4)
    raise TouchbenchError(f"protocol {proto.name!r} has no method {method!r}{hint} (methods: {', '.join(names)})")


def train_from_protocol(
    protocol: str | Path,
    method: str | None = None,
    *,
    fold: str | None = None,
    where: dict[str, list[str]] | None = None,
    exclude: dict[str, list[str]] | None = None,
    windows: Sequence[float] | None = None,
    train_hop: float | None = None,
    seed: int | None = None,
) -> TrainedModel:
    """Fit the protocol's ``method`` (see the module docstring) and return the model."""

    path = find_protocol(str(protocol))
    proto = load_protocol(path)
    combo, clf = _choose(proto, method)
    plan = plan_run(proto)  # loads the data, applies the filters, checks everything
    ds = plan.dataset
    parts = [f"protocol {proto.name} filters" if (proto.dataset.filters or proto.dataset.exclude) else "all captures"]
    idx = np.arange(len(ds))
    if fold is not None:
        folds = list(dict.fromkeys(t.fold.name for t in plan.tasks if t.repetition == 0))
        # a fold by its full name (``subject=s01``) or by the value alone (``s01``) when that is unique
        named = [f for f in folds if f == fold] or [f for f in folds if f.split("=", 1)[-1] == fold]
        if len(named) != 1:
            raise TouchbenchError(f"scheme {proto.scheme.name!r} of {proto.name!r} has no fold {fold!r} "
                                  f"(folds: {', '.join(folds)})")
        fold = named[0]
        tasks = [t for t in plan.tasks if t.repetition == 0 and t.fold.name == fold
                 and t.features_label == combo.label and t.classifier_label == clf.label]
        task = tasks[0]
        if task.crop_frames is not None:
            raise TouchbenchError(f"fold {fold!r} crops captures (early recognition); train on whole captures instead")
        idx = np.asarray(task.fold.train)
        default_seed = task.seed
        parts.append(f"training part of fold {fold} ({proto.scheme.name})")
    else:
        default_seed = derive_seed(proto.seed, "train", combo.label, clf.label)
    if where or exclude:
        keep = select(ds.meta.iloc[idx].reset_index(drop=True), where or {}, exclude or {})
        idx = idx[keep]
        parts += [f"where {k}={','.join(v)}" for k, v in (where or {}).items()]
        parts += [f"exclude {k}={','.join(v)}" for k, v in (exclude or {}).items()]
    if len(idx) == 0:
        raise TouchbenchError("the selection leaves no captures to train on")
    train = ds.subset(idx)
    source: dict[str, Any] = {
        "ref": proto.dataset.name,
        "resolved": plan.dataset_ref,
        "source_hash": plan.source_hash,
        "protocol": {"name": proto.name, "path": str(path), "content_hash": proto.content_hash,
                     "text_hash": proto.text_hash, "seed": proto.seed, "scheme": proto.scheme.name},
        "fold": fold,
        "where": where or {},
        "exclude": exclude or {},
    }
    method = resolve_entry(combo.sets, clf.name, clf.params)  # a named method brings its own feature sets
    return fit_model(
        train, method.feature_sets, method.estimator, method.estimator_params,
        seed=default_seed if seed is None else seed, target=proto.target,
        windows=windows, train_hop=train_hop, features_label=combo.label, classifier_label=clf.label,
        selection="; ".join(parts), source=source,
    )
