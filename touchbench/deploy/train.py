"""``touchbench train``: fit one method of a protocol on an evaluation's training side and save it.

A *method* is what a leaderboard row names: ``FEATURES/METHOD`` as the
results write it (for example ``msd+sd/gaus-rf``, or ``sd/rf100`` for a
classifier entry labelled ``rf100``), or the method's label alone when it
is unique (``touch-et``); see :meth:`Protocol.evaluated_methods`.

The training data is the evaluation's training side, never one of its test
captures (:func:`touchbench.engine.planning.training_side`): the captures
some fold trains on -- every capture under cross-validation, the released
training set of a challenge split, the training dataset of a cross-dataset
transfer -- or the training part of one fold (``fold="subject=s01"``, or
``"s01"`` for short, under LOSO: every subject but s01; ``fold="challenge"``
under the challenge split), optionally narrowed further by ``--where
COL=V1,V2`` and ``--exclude COL=V1,V2``. A protocol with several evaluations
names one with ``evaluation``.

Seeds: the estimator's ``random_state`` is derived from the protocol seed
as the engine derives it. For a fold it is the seed of that fold's task in
repetition 0, so ``train --fold F`` fits the same estimator, on the same
features, as the run engine did for fold F (their test predictions agree).
An evaluation of a single fold (a challenge split, a cross-dataset
transfer: its training side is that fold's training part) trains as that
fold without ``--fold``: the saved model is the run's repetition-0 model
and scores its accuracy. For the training side of several folds it is
``derive_seed(seed, "train", method id)``.

A stream evaluation (the ``stream`` scheme) trains on windows of its
recogniser's lengths, cut every ``train_hop_s``, as its tasks do; ``windows``
and ``train_hop`` given here replace them. Its model file also records every
decision rule the evaluation declares, fitted on the same training captures
as its tasks fit them (``stream_rules``: the gate's and onset's ``level:
auto`` written in as ``level``), and the rule ``touchbench stream`` uses by
default (``stream_rule``, :func:`default_stream_rule`, with
``stream_rule_source``, where it came from).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import pandas as pd

from ..core.errors import TouchbenchError
from ..engine.live import choose_rule, live_samples, with_idle
from ..engine.planning import Prepared, fold_seed, prepare_evaluation, serving_protocol, training_side
from ..methods import Method, method_name, named_methods
from ..protocols.library import find_protocol
from ..protocols.checks import require_extras
from ..protocols.loading import load_protocol
from ..protocols.schema import Protocol, resolve_dataset_ref
from ..protocols.seeding import derive_seed
from ..protocols.schemes import Fold
from ..streams.replay import LiveSpec
from ..streams.rules import fitted_declaration, stream_rule
from .model import TrainedModel, fit_model

__all__ = ["default_stream_rule", "parse_selection", "select", "stream_rules_manifest", "train_from_protocol"]


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


def _choose(proto: Protocol, method: str | None) -> Method:
    """The protocol's method named ``FEATURES/METHOD`` or by a unique label
    (:func:`touchbench.methods.named_methods`; optional when the protocol has one)."""
    methods = proto.evaluated_methods()
    names = [method_name(m) for m in methods]
    if method is None:
        if len(methods) == 1:
            return methods[0]
        raise TouchbenchError(f"protocol {proto.name!r} has {len(methods)} methods; choose one with --method "
                              f"({', '.join(names)})")
    hit = named_methods(methods, method, f"protocol {proto.name!r}")
    if len(hit) > 1:
        raise TouchbenchError(f"{method!r} names {len(hit)} methods of protocol {proto.name!r}; choose one with "
                              f"--method ({', '.join(method_name(m) for m in hit)})")
    return hit[0]


def _evaluation(proto: Protocol, name: str | None) -> Protocol:
    """The evaluation ``name`` of a protocol (the protocol itself when it has none)."""
    subs = proto.evaluations_named([name] if name is not None else [])
    if len(subs) > 1:
        raise TouchbenchError(f"protocol {proto.name!r} has {len(subs)} evaluations; choose one with --evaluation "
                              f"({', '.join(s.evaluation for s in subs)})")
    return subs[0]


def _fold(proto: Protocol, prepared: Prepared, fold: str) -> Fold:
    """The fold of the first repetition named ``fold`` (or by its value alone when that is unique)."""
    folds = prepared.folds[0]
    names = [f.name for f in folds]
    named = [f for f in folds if f.name == fold] or [f for f in folds if f.name.split("=", 1)[-1] == fold]
    if len(named) != 1:
        raise TouchbenchError(f"scheme {proto.scheme.name!r} of {proto.name!r} has no fold {fold!r} "
                              f"(folds: {', '.join(names)})")
    if named[0].crop_frames(prepared.dataset.sensor.frame_rate) is not None:
        raise TouchbenchError(f"fold {named[0].name!r} crops captures (early recognition); train on whole captures instead")
    return named[0]


def _single_fold(prepared: Prepared) -> Fold | None:
    """The evaluation's one fold (a single test set: its training side is that fold's training part),
    or None when it has several or cuts captures."""
    folds = prepared.folds[0]
    return folds[0] if len(folds) == 1 and folds[0].crop_frames(prepared.dataset.sensor.frame_rate) is None else None


def train_from_protocol(
    protocol: str | Path,
    method: str | None = None,
    *,
    fold: str | None = None,
    evaluation: str | None = None,
    where: dict[str, list[str]] | None = None,
    exclude: dict[str, list[str]] | None = None,
    windows: Sequence[float] | None = None,
    train_hop: float | None = None,
    seed: int | None = None,
) -> TrainedModel:
    """Fit the protocol's ``method`` (see the module docstring) and return the model."""
    path = find_protocol(str(protocol))
    proto = _evaluation(load_protocol(path), evaluation)
    m = _choose(proto, method)
    require_extras(proto, {m.label})  # the chosen method's extra, not the others'
    prepared = prepare_evaluation(proto)  # loads the data, applies the filters, builds the folds
    served, left_out = serving_protocol(prepared)  # refuses what cannot serve the sensor
    if m not in served.evaluated_methods():
        raise TouchbenchError(f"method {m.label!r} cannot serve this evaluation: {'; '.join(left_out)}")
    ds = prepared.dataset
    parts = [f"protocol {proto.name} filters"] if (proto.dataset.filters or proto.dataset.exclude) else []
    single = _single_fold(prepared)
    if fold is not None:
        chosen = _fold(proto, prepared, fold)
        fold, idx, default_seed = chosen.name, np.asarray(chosen.train), fold_seed(prepared, m, chosen)
        parts.append(f"training part of fold {fold} ({proto.scheme.name})")
    else:
        # one fold (a single test set): its training part, with its task's seed of repetition 0
        idx = training_side(prepared) if single is None else np.asarray(single.train)
        default_seed = derive_seed(proto.seed, "train", m.method_id) if single is None else fold_seed(prepared, m, single)
        if len(idx) < len(ds):
            parts.append(f"the training side of {proto.scheme.name} ({len(ds) - len(idx)} test captures left out)")
        elif not parts:
            parts.append("all captures")
    if where or exclude:
        idx = idx[select(ds.meta.iloc[idx].reset_index(drop=True), where or {}, exclude or {})]
        parts += [f"where {k}={','.join(v)}" for k, v in (where or {}).items()]
        parts += [f"exclude {k}={','.join(v)}" for k, v in (exclude or {}).items()]
    if len(idx) == 0:
        raise TouchbenchError("the selection leaves no captures to train on")
    source: dict[str, Any] = {
        "ref": proto.dataset.name, "resolved": resolve_dataset_ref(proto), "source_hash": prepared.source.content_hash,
        "protocol": {"name": proto.name, "path": str(path), "content_hash": proto.content_hash,
                     "text_hash": proto.text_hash, "seed": proto.seed, "scheme": proto.scheme.name,
                     "evaluation": proto.evaluation},
        "fold": fold, "where": where or {}, "exclude": exclude or {},
    }
    seed = default_seed if seed is None else seed
    live = prepared.folds[0][0].extra(LiveSpec)  # a stream evaluation trains as its tasks do, unless told otherwise
    if live is None:
        return fit_model(ds.subset(idx), m.spec, seed=seed, target=proto.target, windows=windows,
                         train_hop=train_hop, features_label=m.features_label, label=m.label,
                         selection="; ".join(parts), source=source)
    return _stream_model(proto, prepared, m, idx, fold or "train", seed, windows, train_hop,
                         dict(features_label=m.features_label, label=m.label, selection="; ".join(parts),
                              source=source))


def _stream_model(proto: Protocol, prepared: Prepared, m: Method, idx: np.ndarray, key: str, seed: int,
                  windows: Sequence[float] | None, train_hop: float | None, named: dict[str, Any]) -> TrainedModel:
    """A model of a stream evaluation, trained on ``idx`` as a fold named ``key`` trains (its windows, or
    windows of its training streams; the estimator given the idle class), with every declared rule
    fitted and the default rule chosen (:func:`default_stream_rule`) in its manifest. ``windows`` and
    ``train_hop`` given here replace the evaluation's windows cut from captures."""
    ds = prepared.dataset
    live = proto.splitter().training_spec(ds.meta, idx, key)
    y = ds.meta[proto.target].astype(str).to_numpy()
    spec, samples = with_idle(m.spec, live.idle), None
    if windows is None and live.train_on == "streams":
        samples = live_samples(ds, y, idx, live, live.train_streams)
        windows, train_hop = list(live.windows_s), live.train_hop_s or live.hop_s
    elif windows is None and live.train_on == "windows":
        windows, train_hop = list(live.windows_s), live.train_hop_s if train_hop is None else train_hop
    train = ds.subset(idx)
    model = fit_model(train, spec, seed=seed, target=proto.target, windows=windows, train_hop=train_hop,
                      samples=samples, **named)
    default, why = default_stream_rule(live, train.captures, train.meta[proto.target], train.sensor,
                                       chosen=(lambda: choose_rule(m.spec, seed, ds, y, live)) if live.inner else None)
    model.manifest.update(stream_rules_manifest(live, train.captures, train.meta[proto.target], train.sensor,
                                                (default, why)))
    return model


def default_stream_rule(live: LiveSpec, captures: Sequence[np.ndarray], labels: Sequence[str], sensor: Any,
                        chosen: Callable[[], dict[str, Any]] | None = None) -> tuple[dict[str, Any], str]:
    """The rule ``touchbench stream`` decides with by default for a model trained on the stream
    evaluation ``live`` (its training ``captures`` and ``labels``), fitted, and a short sentence of
    where it came from: with ``choose_rule`` (``chosen`` runs :func:`touchbench.engine.live.choose_rule`
    on the model's own training side), the rule its inner folds chose, so the default is chosen on the
    sensor it will serve; else the toolkit's :data:`touchbench.streams.rules.DEFAULT_RULE`."""
    if chosen is None:
        return stream_rule(live.idle, captures, labels, sensor), "the toolkit's default rule"
    c = chosen()
    k, most, fa = c["rule"], c["max_false_per_min"], c["false_per_idle_min"][c["rule"]]
    why = f"chosen by {c['inner_folds']} inner folds over the model's training subjects: " + (
        f"the best mean frame accuracy ({100 * c['frame_accuracy'][k]:.1f} %) among the rules with at most "
        f"{most:g} false activations per idle minute ({fa:.1f})" if fa <= most else
        f"no rule stayed within {most:g} false activations per idle minute, so the one with the fewest ({fa:.1f}; "
        f"mean frame accuracy {100 * c['frame_accuracy'][k]:.1f} %)")
    return fitted_declaration(live.rules[k], captures, labels, sensor), why


def stream_rules_manifest(live: LiveSpec, captures: Sequence[np.ndarray], labels: Sequence[str], sensor: Any,
                          default: tuple[dict[str, Any], str] | None = None) -> dict[str, Any]:
    """A stream model's manifest keys: ``stream_rules`` (every rule the evaluation declares, fitted on
    the training captures as its tasks fit them: declarations with the fitted ``level`` written in),
    ``stream_rule`` (the default, :func:`default_stream_rule` unless given) and ``stream_rule_source``."""
    rule, why = default if default is not None else default_stream_rule(live, captures, labels, sensor)
    return {"stream_rules": [fitted_declaration(r, captures, labels, sensor) for r in live.rules],
            "stream_rule": rule, "stream_rule_source": why}
