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
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted

from ..core.constraints import ListOf
from ..core.errors import TouchbenchError
from ._util import build, seed_int
from .base import CLASSIFIERS, check_declared, count_constraint
from .inner import (
    candidate,
    candidate_list,
    candidate_refusal,
    inner_fits,
    inner_splits,
    proba_over,
    refit,
    shortest_capture,
)

__all__ = ["NestedSelection", "candidate"]

SOURCE = "touchbench: nested selection over candidate methods by inner cross-validation over training subjects"


class NestedSelection(ClassifierMixin, BaseEstimator):
    """Choose a candidate method by inner cross-validation over the training subjects (module docstring).

    Parameters
    ----------
    candidates : list of candidate mappings (:func:`touchbench.classifiers.inner.candidate`).
    inner_folds : None (one per training subject) or k folds of whole subjects.
    sensor : the data's SensorSpec (the run engine passes it); given to every
        feature set and to estimators that take one.
    random_state : seed of every candidate's estimator (the same for all, so
        the choice compares methods, not seeds).
    """

    #: candidates: mappings (or registered methods' names, written out before the search is built);
    #: inner_folds: None or the shared bound, 2..1000 (every candidate is fitted once per inner fold)
    _parameter_constraints = {"candidates": [ListOf([dict, str])], "inner_folds": [None, *count_constraint("inner_folds")],
                              "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, candidates=(), inner_folds=None, sensor=None, random_state=None):
        self.candidates = candidates
        self.inner_folds = inner_folds
        self.sensor = sensor
        self.random_state = random_state

    def _candidates(self) -> list[dict[str, Any]]:
        return candidate_list(self.candidates, "nested-select")

    def check_sensor(self, sensor, min_frames=None):
        """Why no candidate can serve ``sensor``, or None (a candidate that cannot is left out by ``fit``)."""
        cands = self._candidates()
        problems = [candidate_refusal(c, sensor, min_frames) for c in cands]
        if all(problems):
            return "no candidate serves this sensor: " + "; ".join(f"{c['label']}: {p}" for c, p in zip(cands, problems))
        return None

    # -- pieces ---------------------------------------------------------------
    def _serving(self, captures) -> tuple[list[dict[str, Any]], list[str]]:
        """The candidates that serve the sensor, and the others as ``"label (reason)"``."""
        cands, left_out = [], []
        shortest = shortest_capture(captures)
        for c in self._candidates():
            problem = candidate_refusal(c, self.sensor, shortest) if self.sensor is not None else None
            (left_out.append(f"{c['label']} ({problem})") if problem else cands.append(c))
        if not cands:
            raise TouchbenchError("nested-select: no candidate serves this data: " + "; ".join(left_out))
        return cands, left_out

    def _inner_scores(self, cand, captures, y, groups, splits, seed, cache: dict) -> list[float]:
        return [float(np.mean(fitted.predict(X_te) == y[te]))
                for te, fitted, X_te in inner_fits(cand, captures, y, groups, splits, seed, self.sensor, cache)]

    def _choose(self, cands, captures, y, groups, splits, seed, cache: dict) -> tuple[int, list[str]]:
        """The index of the candidate with the best mean inner accuracy (the first of ties), and the failed ones."""
        self.cv_results_ = {}
        if len(cands) < 2 or not splits:
            return 0, []
        means, failed = [], []
        for c in cands:
            try:
                self.cv_results_[c["label"]] = self._inner_scores(c, captures, y, groups, splits, seed, cache)
                means.append(float(np.mean(self.cv_results_[c["label"]])))
            except Exception as e:  # a candidate that cannot fit an inner part is not chosen
                failed.append(f"{c['label']} ({type(e).__name__}: {e})")
                means.append(-np.inf)
        if len(failed) == len(cands):
            raise TouchbenchError("nested-select: every candidate failed in the inner folds: " + "; ".join(failed))
        return int(np.argmax(means)), failed  # the first of equal means

    def _note(self, n_cands: int, how: str, failed: list[str], left_out: list[str]) -> str:
        scored = ", ".join(f"{lab} {100 * np.mean(s):.1f} %" for lab, s in self.cv_results_.items())
        note = (f"nested-select chose {self.chosen_} by inner CV ({how}): {scored}" if scored
                else f"nested-select took {self.chosen_} ({how if n_cands > 1 else 'one candidate'})")
        if failed:
            note += "; failed in the inner folds: " + ", ".join(failed)
        if left_out:
            note += "; left out for this sensor: " + ", ".join(left_out)
        return note

    # -- API ------------------------------------------------------------------
    def fit(self, X: Sequence[np.ndarray], y, groups=None):
        """Score every candidate by inner CV over ``groups`` (the training subjects), refit the best."""
        captures = list(X)
        y = np.asarray(y)
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        check_declared(self)
        cands, left_out = self._serving(captures)
        seed = seed_int(self.random_state)
        splits, how = inner_splits(y, groups, self.inner_folds, seed)
        cache: dict = {}
        best, failed = self._choose(cands, captures, y, groups, splits, seed, cache)
        chosen = cands[best]
        self.chosen_ = chosen["label"]
        self.selection_note_ = self._note(len(cands), how, failed, left_out)
        self.method_ = refit(chosen, captures, y, groups, seed, self.sensor, cache)
        self.sets_ = self.method_.sets
        self.estimator_, self.est_classes_ = self.method_.estimator, self.method_.classes
        return self

    def predict(self, X):
        check_is_fitted(self)
        return self.method_.predict(list(X))

    def predict_proba(self, X):
        """The chosen candidate's probabilities over ``classes_`` (zeros for a class it never saw)."""
        check_is_fitted(self)
        return proba_over(self.method_.fitted, self.method_.transform(list(X)), self.classes_)


DEFAULTS = {"candidates": (), "inner_folds": None}


@CLASSIFIERS.register(
    "nested-select",
    description="nested design: the candidate method (feature sets -> estimator) with the best inner-CV accuracy over the training subjects, refitted",
    source=SOURCE, defaults=DEFAULTS, extra=None, input="captures", candidates="candidates",
    cheap_params=dict(candidates=[{"features": ["flagg-stats"], "estimator": "zhou-lda"},
                                  {"features": ["flagg-stats"], "estimator": "zhou-tree"}]),
)
def nested_select(random_state=None, sensor=None, **params):
    return build(NestedSelection, DEFAULTS, random_state, {**params, "sensor": sensor}, name="nested-select")
