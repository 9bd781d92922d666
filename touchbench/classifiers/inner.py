"""Candidate methods fitted inside the training captures: the pieces ``nested-select`` and ``fusion`` share.

Both classifiers take the captures as recorded and a list of candidate
methods (feature sets -> an estimator with its parameters), cut the
training captures they are given into inner folds over the training
subjects, fit each candidate on every inner training part and judge it on
the inner test part, then refit on all training captures. What they do
with the inner predictions differs (:mod:`touchbench.classifiers.search`
keeps the best candidate, :mod:`touchbench.classifiers.fusion` weighs
them); how a candidate is spelled, refused, split, fitted and asked for
probabilities is here, once:

- :func:`candidate` / :func:`candidate_list`: the spelling
  ``{label, features, estimator, params}`` (a registered method's name is
  written out before, by :func:`touchbench.methods.expand_candidates`);
- :func:`candidate_refusal`: why a candidate's feature set or estimator
  cannot serve a sensor;
- :func:`inner_splits`: one training subject left out at a time, k folds
  of whole subjects (``GroupKFold``), or, with fewer than two subjects,
  stratified folds (at most k or 5, at most the rarest class's count);
- :func:`inner_fits`: a candidate fitted on every inner training part. A
  feature set that learns nothing (``fold_dependent = False``) is computed
  once per ``fit`` over all training captures (once for every candidate
  that shares it, through ``cache``); one that learns is refitted on every
  inner training part. The estimator is fitted through the one fit path
  (:func:`touchbench.classifiers.fitting.fit_on_codes`: contiguous codes
  of the classes the part holds, no estimator for one class);
- :func:`refit`: a candidate fitted on all training captures;
- :func:`proba_over`: a fitted candidate's probabilities as columns of
  given classes (0 for a class it never saw; one-hot of its prediction
  when its estimator gives no probabilities).
"""

from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np
from sklearn.model_selection import GroupKFold, LeaveOneGroupOut, StratifiedKFold

from ..core.errors import TouchbenchError
from ..features.base import learns_from_data, make_feature_set, stack_features
from .fitting import FittedEstimator, FittedMethod, feature_specs, fit_on_codes, pipeline_refusal, proba_over

__all__ = ["candidate", "candidate_list", "candidate_refusal", "inner_fits", "inner_splits", "proba_over", "refit",
           "shortest_capture"]

Split = tuple[np.ndarray, np.ndarray]


def candidate(entry: Any, who: str = "nested-select") -> dict[str, Any]:
    """A candidate as ``{"label", "features": [(name, params)...], "estimator", "params"}``.

    ``entry``: a mapping with ``features`` (names, ``{name, params}`` mappings or
    ``[name, params]`` pairs), ``estimator`` and optional ``params`` and
    ``label`` (default: the feature sets joined by ``+``, ``->``, the
    estimator); a registered method's name must have been written out
    before (the run engine does it). ``who`` names the classifier in messages.
    """
    if isinstance(entry, str):
        raise TouchbenchError(f"{who}: candidate {entry!r} is not a feature set -> estimator mapping; "
                              f"a registered method's name is written out by the run engine (protocols), "
                              f"from Python give {{features: [...], estimator: ..., params: {{...}}}}")
    if not isinstance(entry, dict) or "estimator" not in entry:
        raise TouchbenchError(f"{who}: a candidate needs 'estimator' (and 'features'), got {entry!r}")
    sets = feature_specs(entry.get("features"))
    est, params = str(entry["estimator"]), dict(entry.get("params") or {})
    label = entry.get("label") or ("+".join(n for n, _ in sets) + (" -> " if sets else "") + est)
    return {"label": str(label), "features": sets, "estimator": est, "params": params}


def candidate_list(entries: Any, who: str, at_least: int = 1, noun: str = "candidate") -> list[dict[str, Any]]:
    """Every entry read by :func:`candidate`: at least ``at_least`` of them (``noun``: what
    messages call one), each label once."""
    cands = [candidate(c, who) for c in (entries or [])]
    if len(cands) < at_least:
        raise TouchbenchError(f"{who} needs at least {'one' if at_least == 1 else at_least} {noun}"
                              f"{'' if at_least == 1 else 's'}" + (f", got {len(cands)}" if cands else ""))
    labels = [c["label"] for c in cands]
    if len(set(labels)) != len(labels):
        raise TouchbenchError(f"{who}: two {noun}s share a label ({', '.join(labels)}); give each a 'label'")
    return cands


def candidate_refusal(cand: dict[str, Any], sensor: Any, min_frames: int | None) -> str | None:
    """Why ``cand`` cannot serve ``sensor`` (its feature set or estimator), or None."""
    return pipeline_refusal(cand["features"], cand["estimator"], cand["params"], sensor, min_frames)


def shortest_capture(captures: Sequence[Any]) -> int | None:
    """The frame count of the shortest capture (None for rows of a matrix or no captures)."""
    return min(len(c) for c in captures) if len(captures) and np.ndim(captures[0]) == 3 else None


def inner_splits(y: np.ndarray, groups: Any, inner_folds: int | None, seed: int) -> tuple[list[Split], str]:
    """The inner folds over the training rows and how they were made (module docstring)."""
    rows = np.zeros((len(y), 1))
    if groups is not None and len(np.unique(groups)) >= 2:
        g = np.asarray(groups)
        if inner_folds is None:
            return list(LeaveOneGroupOut().split(rows, y, g)), "one training subject left out at a time"
        k = min(int(inner_folds), len(np.unique(g)))
        return list(GroupKFold(n_splits=k).split(rows, y, g)), f"{k} folds of whole training subjects"
    counts = np.unique(y, return_counts=True)[1]
    k = min(int(inner_folds or 5), int(counts.min()))
    if k < 2:
        return [], "no inner folds (a class with a single training capture)"
    return (list(StratifiedKFold(n_splits=k, shuffle=True, random_state=seed).split(rows, y)),
            f"{k} stratified folds (fewer than two training subjects given)")


def _fit_sets(features: Sequence[tuple[str, dict]], sensor: Any, captures: Sequence[np.ndarray], y: Any) -> list:
    """The feature sets ``[(name, params)...]`` built with ``sensor`` and fitted on ``captures``."""
    return [make_feature_set(name, dict(params), sensor).fit(captures, y) for name, params in features]


def _learns_nothing(cand: dict[str, Any]) -> bool:
    """Whether every feature set of ``cand`` is computed without fitting (``fold_dependent = False``)."""
    return not any(learns_from_data(n) for n, _ in cand["features"])


def _fixed_matrix(cand: dict[str, Any], sensor: Any, captures: Sequence[np.ndarray], y: Any,
                  cache: dict) -> np.ndarray | list:
    """The candidate's features over all ``captures`` (sets that learn nothing), each set computed once per ``cache``."""
    if not cand["features"]:
        return list(captures)
    blocks = []
    for name, params in cand["features"]:
        key = (name, repr(sorted(params.items())))
        if key not in cache:
            cache[key] = stack_features(_fit_sets([(name, params)], sensor, captures, y), captures)
        blocks.append(cache[key])
    return np.hstack(blocks)


def _rows(X: np.ndarray | list, idx: np.ndarray) -> np.ndarray | list:
    return X[idx] if isinstance(X, np.ndarray) else [X[i] for i in idx]


def fit_candidate(cand: dict[str, Any], seed: int, X: Any, y: np.ndarray, groups: Any, sensor: Any) -> FittedEstimator:
    """The candidate's estimator fitted on ``X`` and contiguous codes of ``y`` (none for one class)."""
    return fit_on_codes(cand["estimator"], cand["params"], seed, X, y, groups, sensor=sensor)


def inner_fits(cand: dict[str, Any], captures: Sequence[np.ndarray], y: np.ndarray, groups: Any,
               splits: Sequence[Split], seed: int, sensor: Any,
               cache: dict) -> Iterator[tuple[np.ndarray, FittedEstimator, np.ndarray | list]]:
    """For every inner split: its test rows, the candidate fitted on its training part, and the test rows' input."""
    fixed = _learns_nothing(cand)
    X_all = _fixed_matrix(cand, sensor, captures, y, cache) if fixed else None
    for tr, te in splits:
        g_tr = None if groups is None else np.asarray(groups)[tr]
        if fixed:
            X_tr, X_te = _rows(X_all, tr), _rows(X_all, te)
        else:
            caps_tr = [captures[i] for i in tr]
            sets = _fit_sets(cand["features"], sensor, caps_tr, y[tr])
            X_tr, X_te = stack_features(sets, caps_tr), stack_features(sets, [captures[i] for i in te])
        yield te, fit_candidate(cand, seed, X_tr, y[tr], g_tr, sensor), X_te


def refit(cand: dict[str, Any], captures: Sequence[np.ndarray], y: np.ndarray, groups: Any, seed: int, sensor: Any,
          cache: dict) -> FittedMethod:
    """The candidate fitted on all training ``captures`` (its feature sets, then its estimator)."""
    sets = _fit_sets(cand["features"], sensor, captures, y)
    X = _fixed_matrix(cand, sensor, captures, y, cache) if _learns_nothing(cand) else stack_features(sets, captures)
    return FittedMethod(sets, fit_candidate(cand, seed, X, y, groups, sensor))

