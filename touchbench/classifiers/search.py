"""Nested design as a method: choose among candidate methods inside the training subjects only.

``nested-select`` takes the captures as recorded and a list of
``candidates``, each feature sets -> an estimator with its parameters
(in a protocol a candidate may also name a registered method such as
``touch-et``: the run engine writes out its feature sets and estimator
before the search is built, so their code and versions enter the task's
identity). ``fit`` scores every candidate by an inner cross-validation
over the training captures it is given, grouped by their subjects
(``groups``, which the run engine passes: the training fold's subjects),
keeps the candidate with the highest mean inner accuracy (ties: the one
listed first; a candidate that raises in an inner part is not chosen,
and the note says why) and refits it on all training captures. The test captures
are never seen: ``predict`` only applies the refitted candidate.

This is what a researcher does by hand when designing a method on
training subjects (docs/research/touch-methods.md), written as a method
any protocol can rerun, inside every outer fold.

Inner folds: ``inner_folds=None`` leaves one training subject out at a
time; an integer k gives k folds of whole subjects (scikit-learn's
``GroupKFold``). With fewer than two training subjects (or no ``groups``)
the folds are stratified by label instead (``StratifiedKFold``, at most k
or 5 folds, at most the rarest class's count), which the selection note
says. A feature set that learns nothing from data (``fold_dependent =
False``) is computed once per ``fit`` over the training captures (once
for all the candidates that share it); one that learns is refitted on
every inner training part. An estimator is fitted on the
contiguous codes of the classes its inner training part holds.

After ``fit``: ``chosen_`` (the label of the chosen candidate),
``cv_results_`` (label -> inner accuracies), ``selection_note_`` (one
line the run engine adds to the task's notes) and the refitted
candidate, ``method_`` (a :class:`touchbench.classifiers.fitting.FittedMethod`: its
``sets_`` and ``estimator_``).

A candidate that cannot serve the data's sensor (a window longer than the
shortest training capture...) is left out of the search, and the note
says why; the search is refused only when no candidate serves.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.model_selection import GroupKFold, LeaveOneGroupOut, StratifiedKFold
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted

from ..core.errors import TouchbenchError
from ..features.base import learns_from_data, make_feature_set, stack_features
from ._util import build, seed_int
from .base import CLASSIFIERS
from .fitting import FittedEstimator, FittedMethod, feature_specs, fit_on_codes, pipeline_refusal, proba_matrix

SOURCE = "touchbench: nested selection over candidate methods by inner cross-validation over training subjects"


def candidate(entry: Any) -> dict[str, Any]:
    """A candidate as ``{"label", "features": [(name, params)...], "estimator", "params"}``.

    ``entry``: a mapping with ``features`` (names, ``{name, params}`` mappings or
    ``[name, params]`` pairs), ``estimator`` and optional ``params`` and
    ``label``; a registered method's name must have been written out before
    (the run engine does it).
    """
    if isinstance(entry, str):
        raise TouchbenchError(f"nested-select: candidate {entry!r} is not a feature set -> estimator mapping; "
                              f"a registered method's name is written out by the run engine (protocols), "
                              f"from Python give {{features: [...], estimator: ..., params: {{...}}}}")
    if not isinstance(entry, dict) or "estimator" not in entry:
        raise TouchbenchError(f"nested-select: a candidate needs 'estimator' (and 'features'), got {entry!r}")
    sets = feature_specs(entry.get("features"))
    est, params = str(entry["estimator"]), dict(entry.get("params") or {})
    label = entry.get("label") or ("+".join(n for n, _ in sets) + (" -> " if sets else "") + est)
    return {"label": str(label), "features": sets, "estimator": est, "params": params}


class NestedSelection(ClassifierMixin, BaseEstimator):
    """Choose a candidate method by inner cross-validation over the training subjects (module docstring).

    Parameters
    ----------
    candidates : list of candidate mappings (:func:`candidate`).
    inner_folds : None (one per training subject) or k folds of whole subjects.
    sensor : the data's SensorSpec (the run engine passes it); given to every
        feature set and to estimators that take one.
    random_state : seed of every candidate's estimator (the same for all, so
        the choice compares methods, not seeds).
    """

    def __init__(self, candidates=(), inner_folds=None, sensor=None, random_state=None):
        self.candidates = candidates
        self.inner_folds = inner_folds
        self.sensor = sensor
        self.random_state = random_state

    def _candidates(self) -> list[dict[str, Any]]:
        cands = [candidate(c) for c in (self.candidates or [])]
        if not cands:
            raise TouchbenchError("nested-select needs at least one candidate")
        labels = [c["label"] for c in cands]
        if len(set(labels)) != len(labels):
            raise TouchbenchError(f"nested-select: two candidates share a label ({', '.join(labels)}); give each a 'label'")
        return cands

    @staticmethod
    def _refusal(cand, sensor, min_frames) -> str | None:
        """Why ``cand`` cannot serve ``sensor`` (its feature set or estimator), or None."""
        return pipeline_refusal(cand["features"], cand["estimator"], cand["params"], sensor, min_frames)

    def check_sensor(self, sensor, min_frames=None):
        """Why no candidate can serve ``sensor``, or None (a candidate that cannot is left out by ``fit``)."""
        cands = self._candidates()
        problems = [self._refusal(c, sensor, min_frames) for c in cands]
        if all(problems):
            return "no candidate serves this sensor: " + "; ".join(f"{c['label']}: {p}" for c, p in zip(cands, problems))
        return None

    # -- pieces ---------------------------------------------------------------
    def _splits(self, y: np.ndarray, groups) -> tuple[list[tuple[np.ndarray, np.ndarray]], str]:
        rows = np.zeros((len(y), 1))
        if groups is not None and len(np.unique(groups)) >= 2:
            g = np.asarray(groups)
            if self.inner_folds is None:
                return list(LeaveOneGroupOut().split(rows, y, g)), "one training subject left out at a time"
            k = min(int(self.inner_folds), len(np.unique(g)))
            return list(GroupKFold(n_splits=k).split(rows, y, g)), f"{k} folds of whole training subjects"
        counts = np.unique(y, return_counts=True)[1]
        k = min(int(self.inner_folds or 5), int(counts.min()))
        if k < 2:
            return [], "no inner folds (a class with a single training capture)"
        seed = seed_int(self.random_state)
        return (list(StratifiedKFold(n_splits=k, shuffle=True, random_state=seed).split(rows, y)),
                f"{k} stratified folds (fewer than two training subjects given)")

    def _fit_sets(self, cand, captures, y) -> list:
        sets = []
        for name, params in cand["features"]:
            fs = make_feature_set(name, dict(params), self.sensor)
            fs.fit(captures, y)
            sets.append(fs)
        return sets

    def _fit_estimator(self, cand, X, y, groups) -> FittedEstimator:
        """The candidate's estimator fitted on contiguous codes of ``y`` (none for one class)."""
        return fit_on_codes(cand["estimator"], cand["params"], seed_int(self.random_state), X, y, groups,
                            sensor=self.sensor)

    @staticmethod
    def _learns_nothing(cand) -> bool:
        """Whether every feature set of ``cand`` is computed without fitting (``fold_dependent = False``)."""
        return not any(learns_from_data(n) for n, _ in cand["features"])

    def _fixed_matrix(self, cand, captures, y, cache: dict) -> np.ndarray | list:
        """The candidate's features over all ``captures`` (sets that learn nothing), each set computed once per fit."""
        if not cand["features"]:
            return list(captures)
        blocks = []
        for name, params in cand["features"]:
            key = (name, repr(sorted(params.items())))
            if key not in cache:
                cache[key] = stack_features(self._fit_sets({"features": [(name, params)]}, captures, y), captures)
            blocks.append(cache[key])
        return np.hstack(blocks)

    def _inner_scores(self, cand, captures, y, groups, splits, cache: dict) -> list[float]:
        fixed = self._learns_nothing(cand)
        X_all = self._fixed_matrix(cand, captures, y, cache) if fixed else None
        scores = []
        for tr, te in splits:
            g_tr = None if groups is None else np.asarray(groups)[tr]
            if fixed:
                X_tr = X_all[tr] if isinstance(X_all, np.ndarray) else [X_all[i] for i in tr]
                X_te = X_all[te] if isinstance(X_all, np.ndarray) else [X_all[i] for i in te]
            else:
                caps_tr = [captures[i] for i in tr]
                sets = self._fit_sets(cand, caps_tr, y[tr])
                X_tr, X_te = stack_features(sets, caps_tr), stack_features(sets, [captures[i] for i in te])
            fitted = self._fit_estimator(cand, X_tr, y[tr], g_tr)
            scores.append(float(np.mean(fitted.predict(X_te) == y[te])))
        return scores

    # -- API ------------------------------------------------------------------
    def fit(self, X: Sequence[np.ndarray], y, groups=None):
        """Score every candidate by inner CV over ``groups`` (the training subjects), refit the best."""
        captures = list(X)
        y = np.asarray(y)
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        cands, left_out = [], []
        shortest = min(len(c) for c in captures) if captures and np.ndim(captures[0]) == 3 else None
        for c in self._candidates():
            problem = self._refusal(c, self.sensor, shortest) if self.sensor is not None else None
            (left_out.append(f"{c['label']} ({problem})") if problem else cands.append(c))
        if not cands:
            raise TouchbenchError("nested-select: no candidate serves this data: " + "; ".join(left_out))
        splits, how = self._splits(y, groups)
        self.cv_results_ = {}
        failed, cache = [], {}
        if len(cands) > 1 and splits:
            means = []
            for c in cands:
                try:
                    self.cv_results_[c["label"]] = self._inner_scores(c, captures, y, groups, splits, cache)
                    means.append(float(np.mean(self.cv_results_[c["label"]])))
                except Exception as e:  # a candidate that cannot fit an inner part is not chosen
                    failed.append(f"{c['label']} ({type(e).__name__}: {e})")
                    means.append(-np.inf)
            if len(failed) == len(cands):
                raise TouchbenchError("nested-select: every candidate failed in the inner folds: " + "; ".join(failed))
            best = int(np.argmax(means))  # the first of equal means
        else:
            best = 0
        chosen = cands[best]
        self.chosen_ = chosen["label"]
        scored = ", ".join(f"{lab} {100 * np.mean(s):.1f} %" for lab, s in self.cv_results_.items())
        self.selection_note_ = (f"nested-select chose {self.chosen_} by inner CV ({how}): {scored}" if scored
                                else f"nested-select took {self.chosen_} ({how if len(cands) > 1 else 'one candidate'})")
        if failed:
            self.selection_note_ += "; failed in the inner folds: " + ", ".join(failed)
        if left_out:
            self.selection_note_ += "; left out for this sensor: " + ", ".join(left_out)
        self.sets_ = self._fit_sets(chosen, captures, y)
        X = (self._fixed_matrix(chosen, captures, y, cache) if self._learns_nothing(chosen)
             else stack_features(self.sets_, captures))
        self.method_ = FittedMethod(self.sets_, self._fit_estimator(chosen, X, y, groups))
        self.estimator_, self.est_classes_ = self.method_.estimator, self.method_.classes
        return self

    def predict(self, X):
        check_is_fitted(self)
        return self.method_.predict(list(X))

    def predict_proba(self, X):
        """The chosen candidate's probabilities over ``classes_`` (zeros for a class it never saw)."""
        check_is_fitted(self)
        return proba_matrix(self.method_, list(X), self.classes_)


DEFAULTS = {"candidates": (), "inner_folds": None}


@CLASSIFIERS.register(
    "nested-select",
    description="nested design: the candidate method (feature sets -> estimator) with the best inner-CV accuracy over the training subjects, refitted",
    source=SOURCE, defaults=DEFAULTS, extra=None, input="captures", candidates=True,
    cheap_params=dict(candidates=[{"features": ["flagg-stats"], "estimator": "zhou-lda"},
                                  {"features": ["flagg-stats"], "estimator": "zhou-tree"}]),
)
def nested_select(random_state=None, sensor=None, **params):
    return build(NestedSelection, DEFAULTS, random_state, {**params, "sensor": sensor}, name="nested-select")
