"""Leakage audit: a protocol's methods under the honest scheme and each applicable leaky variant.

Published accuracies on touch data are often measured in ways that let the
test data inform training. :func:`run_audit` evaluates the same methods,
on the same data, under

==================  ==========================================================
``honest``          the protocol's own scheme when it keeps subjects apart and
                    leaks nothing, else leave one subject out
``capture-kfold``   k-fold over captures ignoring subjects (stratified): one
                    person's captures on both sides of a fold
``window-kfold``    the captures cut into windows, stratified k-fold over the
                    windows (shuffled, the protocol's seed): a capture's
                    windows on both sides (a method with sub-windows of its
                    own, the CNN's ``L``, gets the first ``L`` windows of
                    ``floor(frames / L)`` frames of each capture and ``L = 1``:
                    one window is what it saw of a capture; otherwise every
                    window of ``window_seconds``)
``subject-id``      capture-kfold with the subject's id appended to the
                    features (methods with a feature matrix only)
``tuned-on-test``   the honest scheme, a parameter grid (``tune``), only the
                    value with the best mean test accuracy reported
``stopped-on-test`` the honest scheme, each method that trains by epochs
                    (the ``cnn``) given the test fold with its labels: no
                    validation split, the epoch of the best test accuracy
                    kept (early stopping on the held-out subject)
==================  ==========================================================

Each variant is a protocol of its own (written beside its results as
``protocol.yaml``), run by the engine into ``<out>/<variant>/``, so every
number is reproducible and every result row carries its leakage. The
inflation of a variant is its accuracy minus the honest one, in percentage
points; with the protocol's ``expected`` results, each variant is compared
with the published number and its tolerance.

The window variant of a CNN (Al-mashhadani et al. 2021) is the reading of
that paper under which its number comes out. Sec. 2.3, Eq. 3: a capture of
N = 432 frames "can be broken down into" L subsamples of F = floor(N / L)
frames "with the same label"; "the first subsample is picked, and the others
are kept away" (L = 30: F = 14, Table 1's 8 x 8 x 14 input); yet benefit I
says the subsamples "increase the number of samples for training". Table 2
reports leave-one-subject-out, but Table 3 sums to 252 "captures", 36 per
gesture, 80.2 % on its diagonal, which no leave-one-subject-out over HAART's
830 captures gives. Readings of the 252: (a) the challenge's test
split (3 subjects x 12 substrate and cover conditions x 7 gestures = 252;
the converted HAART has 250, two constant captures lacking); (b) a test
fold of windows (e.g. 10 % of the windows of a few captures); (c) one
subject's windows. Under any reading with windows as samples, a capture's
windows, 14 frames apart, fall on both sides of a split. The variant takes
the reading that needs fewest assumptions: every capture cut into its first
L windows of F frames (L = 30: 30 windows of 14 frames, 24,900 for HAART's
830 captures), each window a sample with its capture's label, stratified
k-fold (k = 10) over the windows, shuffled with the protocol's seed (0), the
CNN with L = 1 (one window is its input) and its early-stopping split drawn
over the training windows (``validation_by: rows``; the paper describes no
validation split, and with windows as samples, holding out whole subjects
for it would be the one honest step in a leaky evaluation); ``window_folds``
runs only the first folds of that split (a cheaper estimate of the same
figure). With one window a capture, which windows a CNN is tested on and how
they vote cannot matter: an entry that differs from an earlier one only in
those (``cnn-all-windows`` beside ``cnn``) is the same network, run once and
reported for both (:func:`window_twins`).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import pandas as pd

from ..core.atomic import atomic_write_bytes
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..methods import CAPTURES, METHODS, stops_on_test
from ..methods.base import takes_captures
from ..protocols.derive import derive, protocol_data
from ..protocols.schema import Protocol
from ..protocols.specs import AUDIT_VARIANTS
from ..results.locking import make_results_dir
from .planning import Plan, method_labels, prepare_evaluation
from .runner import plan_protocol, run_plan

__all__ = ["VARIANTS", "Audit", "AuditPlan", "audit_protocols", "plan_audit", "run_audit", "tunable_params"]

VARIANTS = AUDIT_VARIANTS


@dataclass
class Audit:
    """The audit's table (one row per method and variant) and where each variant's results are."""

    table: pd.DataFrame
    folders: dict[str, Path]
    notes: list[str] = field(default_factory=list)
    published: dict[str, dict[str, Any]] = field(default_factory=dict)


def _base_data(protocol: Protocol) -> dict[str, Any]:
    """The protocol's data for its variants: one evaluation, without what the variants decide
    (expected numbers, design data, repetitions, the audit block)."""
    data = protocol_data(protocol)
    for k in ("expected", "evaluations", "evaluation", "design", "repetitions", "audit"):
        data.pop(k, None)
    data["target"] = protocol.target
    return data


def _window_frames(protocol: Protocol, n_frames: int, frame_rate: float,
                   window_seconds: float) -> tuple[int, int | None, str]:
    """The window length in frames, the windows kept per capture (the method's own ``L``, or all:
    None), and how they were chosen."""
    ls = {int(m.params["L"]) for m in protocol.evaluated_methods() if "L" in m.params}
    if len(ls) == 1:
        L = ls.pop()
        return max(1, n_frames // L), L, f"floor({n_frames} / L={L}), the first {L} of each capture"
    return max(1, int(round(window_seconds * frame_rate))), None, f"{window_seconds:g} s"


def _window_scheme(frames: int, per_capture: int | None, k: int, folds: int | None) -> dict[str, Any]:
    """The window variant's scheme: stratified, shuffled k-fold over the windows."""
    scheme: dict[str, Any] = {"name": "window-kfold", "k": k, "frames": frames}
    if per_capture is not None:
        scheme["per_capture"] = per_capture
    if folds is not None and folds < k:
        scheme["folds"] = folds
    return scheme


#: a CNN's parameters that cannot matter with one window a capture (L = 1): the windows it trains and
#: tests on (window 0, whatever they say) and how a capture's windows vote (there is one)
ONE_WINDOW_MOOT = ("train_windows", "test_windows", "vote")


def _entry_name(spec: dict[str, Any]) -> str | None:
    return spec.get("name", spec.get("estimator"))


def _entry_label(spec: Any) -> Any:
    """An entry's label as the protocol gives it (its label, else its name; a bare name as it is)."""
    return (spec.get("label") or _entry_name(spec)) if isinstance(spec, dict) else spec


def _one_window(spec: Any) -> None:
    """An entry with sub-windows of its own (an ``L``) on windows: ``L = 1``, in place; a CNN's early
    stopping drawn over the windows and what cannot matter with one window (:data:`ONE_WINDOW_MOOT`) dropped."""
    if isinstance(spec, dict) and "L" in (spec.get("params") or {}):
        spec["params"]["L"] = 1
        if _entry_name(spec) == "cnn":
            spec["params"]["validation_by"] = "rows"  # early stopping on windows too: they are the samples
            for moot in ONE_WINDOW_MOOT:
                spec["params"].pop(moot, None)


def _twin_key(spec: Any, labels: list[str]) -> str | None:
    """What makes an entry the method it is on windows (its name and parameters once
    :func:`_one_window`), or None for one never merged: a name alone, a grid, a label that is not
    the entry's own."""
    if not isinstance(spec, dict):
        return None
    grid = any(isinstance(v, dict) and "grid" in v for v in (spec.get("params") or {}).values())
    if grid or labels.count(_entry_label(spec)) != 1:
        return None
    spec = copy.deepcopy(spec)
    _one_window(spec)
    return canonical_json([_entry_name(spec), spec.get("params") or {}])


def window_twins(data: dict[str, Any]) -> dict[str, str]:
    """The entries of a protocol's ``data`` that on windows (:func:`_one_window`) are the same method as
    an earlier entry: ``{its label: the earlier one's}`` (``cnn-all-windows`` is ``cnn`` with L = 1)."""
    twins: dict[str, str] = {}
    for key in ("classifiers", "methods"):
        specs = data.get(key) or []
        labels = [_entry_label(s) for s in specs]
        seen: dict[str, str] = {}
        for spec, label in zip(specs, labels):
            ident = _twin_key(spec, labels)
            if ident is not None and ident in seen:
                twins[label] = seen[ident]
            elif ident is not None:
                seen[ident] = label
    return twins


def _window_entries(data: dict[str, Any], frames: int, twins: dict[str, str]) -> dict[str, Any]:
    """The protocol's entries on windows: raw-window's frames set to the window, an L set to 1
    (:func:`_one_window`), an entry that is then an earlier one's twin (``twins``, :func:`window_twins`)
    left out."""
    for combo in data.get("features") or []:
        for ref in (combo if isinstance(combo, list) else [combo]):
            if isinstance(ref, dict) and ref.get("name") == CAPTURES:
                ref.setdefault("params", {})["frames"] = frames
    for key in ("classifiers", "methods"):
        if data.get(key):
            data[key] = [s for s in data[key] if not (isinstance(s, dict) and _entry_label(s) in twins)]
            for spec in data[key]:
                _one_window(spec)
    return data


def _subject_id_entries(protocol: Protocol) -> list[dict[str, Any]]:
    """The protocol's methods that have a feature matrix, as methods with the subject id appended."""
    out = []
    for m in protocol.evaluated_methods():
        if m.name in METHODS:
            out.append({"name": m.name, "params": m.params, "label": m.label, "subject_id_feature": True})
        elif not (m.spec.takes_captures or takes_captures(m.name)):  # on captures: nothing to append the id to
            out.append({"features": [{"name": n, "params": p} for n, p in m.spec.feature_sets],
                        "estimator": m.spec.estimator, "params": m.params, "label": m.label,
                        "subject_id_feature": True})
    return out


def _entry_specs(data: dict[str, Any]) -> list[dict[str, Any]]:
    return [s for s in [*(data.get("classifiers") or []), *(data.get("methods") or [])] if isinstance(s, dict)]


def tunable_params(protocol: Protocol) -> list[str]:
    """The parameters the tuned-on-test variant can choose a value of: those the protocol's classifier
    and method entries state."""
    return sorted({k for spec in _entry_specs(_base_data(protocol)) for k in spec.get("params") or {}})


def _check_tune(protocol: Protocol, tune: dict[str, list[Any]]) -> None:
    known = tunable_params(protocol)
    unknown = [k for k in tune if k not in known]
    if unknown:
        valid = (f"parameters it can tune: {', '.join(known)}" if known
                 else "it states no parameter in its classifier or method entries")
        raise TouchbenchError(f"tune: {unknown[0]!r} is no parameter of {protocol.name}'s classifier or method "
                              f"entries ({valid})")


def _tuned_entries(data: dict[str, Any], tune: dict[str, list[Any]]) -> dict[str, Any] | None:
    """The entries whose estimator takes a tuned parameter, given the grid and ``tuned_on_test``."""
    hit = False
    for spec in _entry_specs(data):
        params = spec.setdefault("params", {})
        for k, values in tune.items():
            if k in params:
                params[k] = {"grid": list(values)}
                spec["tuned_on_test"] = True
                hit = True
    return data if hit else None


def _stopped_entries(data: dict[str, Any]) -> dict[str, Any] | None:
    """The entries whose estimator can stop on test data marked ``stopped_on_test`` (None: there is none)."""
    hit = False
    for spec in _entry_specs(data):
        if stops_on_test(spec.get("estimator") or spec.get("name") or ""):
            spec["stopped_on_test"] = True
            hit = True
    return data if hit else None


def audit_protocols(protocol: Protocol, *, k: int = 10, window_seconds: float = 2.0,
                    tune: dict[str, list[Any]] | None = None, variants: tuple[str, ...] = VARIANTS,
                    window_folds: int | None = None) -> tuple[dict[str, Protocol], list[str]]:
    """The protocol of each applicable variant, and notes on the ones left out (and why). A ``tune``
    parameter that no entry of the protocol states is refused, naming the ones it states.
    ``window_folds``: the window variant runs only the first that many of its ``k`` folds."""
    _check_tune(protocol, tune or {})
    notes: list[str] = []
    own = protocol.splitter(0)
    honest_scheme: dict[str, Any] = ({"name": protocol.scheme.name, **protocol.scheme.params}
                                     if own.keeps_subjects_apart() and not own.leakage() and not own.sample_windows()
                                     else {"name": "loso"})
    if honest_scheme["name"] == "loso" and protocol.scheme.name != "loso":
        notes.append(f"the protocol's scheme {protocol.scheme.name!r} does not keep subjects apart: the honest "
                     "figure is leave one subject out")
    base = _base_data(protocol)
    name = protocol.name + (f"-{protocol.evaluation}" if protocol.evaluation else "")
    out: dict[str, Any] = {}
    kfold = {"name": "kfold", "k": k}
    if "honest" in variants:
        out["honest"] = dict(base, scheme=honest_scheme)
    if "capture-kfold" in variants:
        out["capture-kfold"] = dict(base, scheme=kfold)
    if "window-kfold" in variants:
        ds = prepare_evaluation(protocol).dataset  # the data, to size the windows
        frames, first, why = _window_frames(protocol, int(ds.n_frames.min()), ds.sensor.frame_rate, window_seconds)
        scheme = _window_scheme(frames, first, k, window_folds)
        twins = window_twins(base)
        out["window-kfold"] = _window_entries(dict(copy.deepcopy(base), scheme=scheme), frames, twins)
        notes.append(f"window-kfold: windows of {frames} frames ({why}), no overlap, stratified {k}-fold over "
                     "the windows" + (f", its first {scheme['folds']} folds run" if "folds" in scheme else ""))
        notes += [f"window-kfold: with L = 1 (one window a capture) {twin} is the same method as {kept} (which "
                  "windows it takes and how they vote cannot matter): run once, reported for both"
                  for twin, kept in twins.items()]
    if "subject-id" in variants:
        entries = _subject_id_entries(protocol)
        if entries:
            d = {k2: v for k2, v in base.items() if k2 not in ("features", "classifiers", "methods")}
            out["subject-id"] = dict(d, scheme=kfold, methods=entries)
        else:
            notes.append("subject-id: no method with a feature matrix to append the subject id to")
    if "tuned-on-test" in variants:
        tuned = _tuned_entries(copy.deepcopy(base), tune or {}) if tune else None
        if tuned is not None:
            out["tuned-on-test"] = dict(tuned, scheme=honest_scheme)
        else:
            notes.append("tuned-on-test: give a parameter grid (--tune PARAM=V1,V2,...) that a method takes")
    if "stopped-on-test" in variants:
        stopped = _stopped_entries(copy.deepcopy(base))
        if stopped is not None:
            out["stopped-on-test"] = dict(stopped, scheme=honest_scheme)
        else:
            notes.append("stopped-on-test: no method that trains by epochs (such as cnn) to stop on the test data")
    protos = {}
    for variant, data in out.items():
        data["name"] = f"{name}-{variant}"
        protos[variant] = derive(protocol, data)
    return protos, notes


def _accuracies(scores: pd.DataFrame) -> dict[str, float]:
    """Mean accuracy over folds (repetitions averaged) per ``features / classifier``; an entry tuned on
    test keeps its best grid value, a subject-id entry its label without the suffix."""
    ok = scores[scores["status"] == "ok"]
    out: dict[str, float] = {}
    for (feats, clf, sel), g in ok.groupby(["features", "classifier", "selection"], sort=False):
        acc = float(g.groupby("fold")["accuracy"].mean().mean())
        key = f"{feats} / {sel.split(' (')[0] if sel else clf.removesuffix('+subject-id')}"
        out[key] = max(out.get(key, -math.inf), acc)
    return out


def _window_accuracies(scores: pd.DataFrame, variant: Protocol, honest: Protocol,
                       twins: dict[str, str]) -> dict[str, float]:
    """The window variant's accuracies under the honest protocol's method names (``features /
    classifier``), entry by entry (the variant changes raw-window's frames, so its feature label
    differs); an entry left out as an earlier one's twin (:func:`window_twins`) gets that one's."""
    def name(m) -> str:
        return f"{m.features_label} / {m.label}"

    ours = [name(m) for m in variant.evaluated_methods()]
    theirs = [m for m in honest.evaluated_methods() if m.label not in twins]
    same = dict(zip(ours, map(name, theirs))) if len(ours) == len(theirs) else {}
    accs = {same.get(m, m): a for m, a in _accuracies(scores).items()}
    for m in honest.evaluated_methods():
        if m.label in twins:
            accs[name(m)] = accs.get(f"{m.features_label} / {twins[m.label]}", math.nan)
    return accs


@dataclass
class AuditPlan:
    """Every variant's protocol and plan, made before any task runs (so the audit's size is known)."""

    protocols: dict[str, Protocol]
    plans: dict[str, tuple[Plan, Path]]
    notes: list[str] = field(default_factory=list)
    #: the window variant's entries left out as an earlier entry's twin (:func:`window_twins`)
    twins: dict[str, str] = field(default_factory=dict)

    @property
    def n_tasks(self) -> int:
        return sum(len(plan.tasks) for plan, _ in self.plans.values())

    def describe(self) -> str:
        """One line: the variants and their tasks (folds x methods), e.g. for a message before the audit starts."""
        parts = [f"{v} {len(plan.tasks)} ({_count(plan.n_folds, 'fold')} x {_count(len(method_labels(plan)), 'method')})"
                 for v, (plan, _) in self.plans.items()]
        return f"{len(self.plans)} variants, {self.n_tasks} tasks in all: " + ", ".join(parts)


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def plan_audit(protocol: Protocol, out: str | Path, *, k: int = 10, window_seconds: float = 2.0,
               tune: dict[str, list[Any]] | None = None, variants: tuple[str, ...] = VARIANTS,
               window_folds: int | None = None) -> AuditPlan:
    """Every applicable variant planned into ``<out>/<variant>/`` (nothing runs)."""
    protos, notes = audit_protocols(protocol, k=k, window_seconds=window_seconds, tune=tune, variants=variants,
                                    window_folds=window_folds)
    if "honest" not in protos:
        raise TouchbenchError("the audit needs the honest variant to measure inflation against")
    plans = {variant: plan_protocol(proto, Path(out) / variant)[0] for variant, proto in protos.items()}
    twins = window_twins(_base_data(protocol)) if "window-kfold" in protos else {}
    return AuditPlan(protocols=protos, plans=plans, notes=notes, twins=twins)


def run_audit(protocol: Protocol, out: str | Path, *, jobs: int = 1, k: int = 10, window_seconds: float = 2.0,
              tune: dict[str, list[Any]] | None = None, variants: tuple[str, ...] = VARIANTS,
              progress: bool | None = None, planned: AuditPlan | None = None,
              window_folds: int | None = None, reuse: Sequence[str | Path] = ()) -> Audit:
    """Run every variant (finished tasks are reused) and tabulate accuracy and inflation per method.
    ``planned``: the :func:`plan_audit` of the same arguments, when the caller made it already.
    A variant's task that another variant run before it, or a folder of ``reuse`` (the protocol's
    own run: its honest variant), finished is taken from there (:func:`run_plan`'s ``reuse``): the
    honest variant is the protocol itself, and tuning on test runs the protocol's own setting too."""
    planned = planned or plan_audit(protocol, out, k=k, window_seconds=window_seconds, tune=tune, variants=variants,
                                    window_folds=window_folds)
    protos, notes = planned.protocols, planned.notes
    accs: dict[str, dict[str, float]] = {}
    folders: dict[str, Path] = {}
    for variant, (plan, folder) in planned.plans.items():
        make_results_dir(folder)
        atomic_write_bytes(folder / "protocol.yaml", protos[variant].text.encode())
        res = run_plan(plan, folder, jobs=jobs, progress=progress, reuse=[*reuse, *folders.values()])
        accs[variant] = (_window_accuracies(res.scores, protos[variant], protos["honest"], planned.twins)
                         if variant == "window-kfold" else _accuracies(res.scores))
        folders[variant] = folder
    rows = []
    for method, honest in accs["honest"].items():
        for variant in protos:
            acc = accs[variant].get(method, math.nan)
            rows.append({"method": method, "variant": variant, "accuracy": acc,
                         "inflation_pp": 100.0 * (acc - honest), "leaky": variant != "honest"})
    published = {}
    if protocol.expected is not None:
        for r in protocol.expected.results:
            tol = r.tolerance if r.tolerance is not None else protocol.expected.tolerance
            published[protocol.method_name_of(r)] = {"value": r.value, "tolerance": tol, "source": r.source or protocol.expected.source}
    table = pd.DataFrame(rows)
    if published and len(table):
        pub = table["method"].map(lambda m: published.get(m, {}).get("value", math.nan))
        tol = table["method"].map(lambda m: published.get(m, {}).get("tolerance", math.nan))
        table["published"] = pub
        table["within_tolerance"] = (100.0 * table["accuracy"] - pub).abs() <= tol
    return Audit(table=table, folders=folders, notes=notes, published=published)
