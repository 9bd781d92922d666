"""Fusion as a method: candidate methods' probabilities summed with weights chosen inside the training subjects.

``fusion`` takes the captures as recorded and two or more ``parts``, each
feature sets -> an estimator with its parameters, spelled as
``nested-select``'s candidates (in a protocol a part may also name a
registered method such as ``touch-et-contact``, or a classifier that takes
the captures such as ``minirocket``: the run engine writes it out before
the fusion is built, so its code enters the task's identity). Its output
is the weighted sum of the parts' class probabilities; the weights are
chosen by an inner cross-validation over the training captures it is
given, grouped by their subjects (``groups``: the training fold's
subjects), so the test captures never inform them.

The idea is late fusion (a weighted average of classifiers' posteriors,
Kittler et al., "On combining classifiers", IEEE TPAMI 1998, the sum
rule), with the weight chosen by nested cross-validation as in stacking
(Wolpert, "Stacked generalization", 1992) but restricted to a grid of
weight vectors instead of a learnt combiner: on HAART's held-out subjects
touchbench's feature methods and the Rocket family make different errors.

``fit``:

1. inner folds over the training subjects, as ``nested-select``
   (:func:`touchbench.classifiers.inner.inner_splits`: one training subject
   left out at a time, ``inner_folds`` = k folds of whole subjects, or
   stratified folds with fewer than two subjects);
2. every part fitted once per inner fold (a feature set that learns
   nothing computed once per ``fit``); its probabilities for the fold's
   inner test captures kept as columns of all the training classes
   (``classes_``: a class the inner training part lacks gets 0);
3. every weight vector scored on the pooled inner predictions: the
   accuracy over all inner test captures together (not a mean of the
   folds' accuracies) of the argmax of the weighted sum of the parts'
   probabilities (equal sums: the first class in sorted order);
4. the best weight vector kept (ties: the first listed), and every part
   refitted on all training captures.

``weights``: a list of weight vectors, one weight per part in the order of
``parts``, each non-negative with a positive sum; a vector is scaled to sum
1 (the argmax is unchanged, and ``predict_proba`` stays a distribution). A
protocol's validation refuses any other: a non-empty list of vectors is
declared (``_parameter_constraints``), each vector's weights (one per part,
non-negative, a positive sum) are the registry tag ``check_params`` (they
depend on ``parts``), which names the vector at fault.
None gives a default grid: for two parts ``(w, 1 - w)`` for w in 0, 0.25,
0.5, 0.75, 1 (the second part alone first); for k parts the equal weights,
then each part alone.

``predict_proba`` is the chosen weighted sum over ``classes_`` (a part that
never saw a class contributes 0 for it; a part whose estimator gives no
probabilities contributes a one-hot of its prediction), ``predict`` its
argmax. A part's probabilities are taken as its estimator gives them: a
ridge classifier (aeon's MiniRocket) gives a one-hot of its prediction, so
against such a part a weight below 0.5 on the other parts never overturns
it; at 0.5 only a class the others give probability 1 ties with it (the
first class in sorted order wins), and only heavier weights mix the two.

After ``fit``: ``weights_`` (the chosen vector), ``cv_results_``
(``{"weights": every vector as scaled, "accuracy": its pooled inner
accuracy}``, NaN without inner folds), ``parts_`` (each part refitted: a
:class:`touchbench.classifiers.fitting.FittedMethod`) and
``selection_note_`` (one line the run engine adds to the task's notes: the
weights chosen and every vector's inner accuracy).

Degenerate input: without inner folds (a class with a single training
capture and no subjects) the first weight vector listed is taken, and the
note says so. A fusion needs every part: unlike ``nested-select``, a part
the sensor refuses refuses the whole fusion, naming the part and its
reason, and a part that raises in an inner fold fails the fit with its name.
Every part gets the same seed (``random_state``), in the inner folds and
in the refit.
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
from .base import CLASSIFIERS, ParamError, check_declared, count_constraint
from .inner import candidate_list, candidate_refusal, inner_fits, inner_splits, proba_over, refit, shortest_capture

__all__ = ["Fusion", "default_weights", "weight_grid"]

SOURCE = ("touchbench: weighted sum of candidate methods' probabilities (sum rule, Kittler et al. 1998), "
          "weights chosen by inner cross-validation over training subjects")
TWO_PART_GRID = (0.0, 0.25, 0.5, 0.75, 1.0)


def default_weights(k: int) -> list[tuple[float, ...]]:
    """The default weight vectors for ``k`` parts (module docstring)."""
    if k == 2:
        return [(w, 1.0 - w) for w in TWO_PART_GRID]
    return [tuple([1.0 / k] * k)] + [tuple(float(i == j) for j in range(k)) for i in range(k)]


def weight_grid(weights: Any, k: int) -> np.ndarray:
    """The weight vectors ``(m, k)`` as float64, each scaled to sum 1 (``weights`` None: :func:`default_weights`);
    a :class:`ParamError` naming the vector at fault (the list itself: its declared domain,
    :attr:`Fusion._parameter_constraints`)."""
    vectors = default_weights(k) if weights is None else list(weights)
    W = []
    for i, v in enumerate(vectors):
        try:
            w = np.asarray(v, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            w = np.array([np.nan])
        if len(w) != k or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
            raise ParamError(("weights", i), f"fusion: weight vector {list(v) if np.ndim(v) else v!r} is not {k} "
                                             f"non-negative weights with a positive sum (one per part, in the order "
                                             f"of 'parts')")
        W.append(w / w.sum())
    return np.vstack(W)


def check_params(params: dict[str, Any]) -> None:
    """Two parts or more (the default, no parts, is what a method fills in), and the weights against
    their number (the parts' own values: their classifiers' checks)."""
    parts = params.get("parts")
    if isinstance(parts, (list, tuple)) and len(parts) < 2:
        raise ParamError("parts", f"fusion needs at least 2 parts (the methods whose probabilities it sums), got "
                                  f"{len(parts)}")
    if isinstance(parts, (list, tuple)):
        weight_grid(params.get("weights"), len(parts))


def pooled_accuracies(probas: Sequence[np.ndarray], codes: np.ndarray, rows: np.ndarray, W: np.ndarray) -> np.ndarray:
    """For every weight vector (rows of ``W``): the accuracy over ``rows`` of the argmax of the weighted sum
    of the parts' probabilities ``probas`` (each ``(n, C)``) against the class indices ``codes``."""
    P = np.stack([p[rows] for p in probas])  # (k, r, C)
    fused = np.einsum("mk,krc->mrc", W, P)
    return np.mean(np.argmax(fused, axis=2) == codes[rows][None, :], axis=1)


def _fmt(w: np.ndarray) -> str:
    return "/".join(f"{x:.3g}" for x in w)


class Fusion(ClassifierMixin, BaseEstimator):
    """Weighted sum of candidate methods' probabilities, the weights chosen by inner CV (module docstring).

    Parameters
    ----------
    parts : two or more candidate mappings (:func:`touchbench.classifiers.inner.candidate`).
    weights : a list of weight vectors (one weight per part), or None for the default grid.
    inner_folds : None (one per training subject) or k folds of whole subjects.
    sensor : the data's SensorSpec (the run engine passes it); given to every
        feature set and to estimators that take one.
    random_state : seed of every part's estimator (the same for all).
    """

    #: ``predict`` is ``classes_`` at the argmax of ``predict_proba``: the run engine asks once for both
    labels_are_argmax_proba = True

    #: parts: candidate mappings (or registered methods' names, written out before the fusion is
    #: built); weights: None or at least one vector (its numbers, one per part, non-negative with a
    #: positive sum: ``check_params``, which names the vector); inner_folds: None or the shared
    #: bound, 2..1000
    _parameter_constraints = {
        "parts": [ListOf([dict, str])],
        "weights": [None, ListOf([list, tuple], min_length=1)],
        "inner_folds": [None, *count_constraint("inner_folds")],
        "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, parts=(), weights=None, inner_folds=None, sensor=None, random_state=None):
        self.parts = parts
        self.weights = weights
        self.inner_folds = inner_folds
        self.sensor = sensor
        self.random_state = random_state

    def _parts(self) -> list[dict[str, Any]]:
        return candidate_list(self.parts, "fusion", at_least=2, noun="part")

    def check_sensor(self, sensor, min_frames=None):
        """Why a part cannot serve ``sensor`` (the first that cannot, named), or None."""
        for part in self._parts():
            problem = candidate_refusal(part, sensor, min_frames)
            if problem:
                return f"part {part['label']}: {problem}"
        return None

    # -- pieces ---------------------------------------------------------------
    def _pooled(self, parts, captures, y, groups, splits, seed, cache: dict) -> tuple[list[np.ndarray], np.ndarray]:
        """Each part's inner-test probabilities over ``classes_`` (rows of every inner test part), and those rows."""
        probas, rows = [], np.zeros(len(y), dtype=bool)
        for part in parts:
            P = np.zeros((len(y), len(self.classes_)), dtype=np.float64)
            try:
                for te, fitted, X_te in inner_fits(part, captures, y, groups, splits, seed, self.sensor, cache):
                    P[te] = proba_over(fitted, X_te, self.classes_)
                    rows[te] = True
            except TouchbenchError:
                raise
            except Exception as e:  # a fusion needs every part
                raise TouchbenchError(f"fusion: part {part['label']} failed in the inner folds: "
                                      f"{type(e).__name__}: {e}") from e
            probas.append(P)
        return probas, rows

    def _note(self, parts, how: str) -> str:
        order = " / ".join(p["label"] for p in parts)
        acc = self.cv_results_["accuracy"]
        if np.all(np.isnan(acc)):
            return f"fusion took the first weights listed, {_fmt(self.weights_)} ({order}): {how}"
        scored = ", ".join(f"{_fmt(w)} {100 * a:.1f} %" for w, a in zip(self.cv_results_["weights"], acc))
        return f"fusion chose weights {_fmt(self.weights_)} ({order}) by pooled inner CV ({how}): {scored}"

    # -- API ------------------------------------------------------------------
    def fit(self, X: Sequence[np.ndarray], y, groups=None):
        """Score every weight vector on the parts' pooled inner predictions over ``groups``; refit every part."""
        captures = list(X)
        y = np.asarray(y)
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        check_declared(self)
        parts = self._parts()
        W = weight_grid(self.weights, len(parts))
        problem = self.check_sensor(self.sensor, shortest_capture(captures)) if self.sensor is not None else None
        if problem:
            raise TouchbenchError(f"fusion cannot serve this data: {problem}")
        seed = seed_int(self.random_state)
        splits, how = inner_splits(y, groups, self.inner_folds, seed)
        cache: dict = {}
        acc = np.full(len(W), np.nan)
        if splits:
            probas, rows = self._pooled(parts, captures, y, groups, splits, seed, cache)
            acc = pooled_accuracies(probas, np.searchsorted(self.classes_, y), rows, W)
        best = int(np.argmax(acc)) if splits else 0  # the first of equal accuracies
        self.weights_ = W[best]
        self.cv_results_ = {"weights": W, "accuracy": acc}
        self.selection_note_ = self._note(parts, how)
        self.parts_ = [refit(p, captures, y, groups, seed, self.sensor, cache) for p in parts]
        return self

    def predict_proba(self, X):
        """The chosen weighted sum of the parts' probabilities over ``classes_`` (float64)."""
        check_is_fitted(self)
        captures = list(X)
        out = np.zeros((len(captures), len(self.classes_)), dtype=np.float64)
        for w, part in zip(self.weights_, self.parts_):
            out += w * proba_over(part.fitted, part.transform(captures), self.classes_)
        return out

    def predict(self, X):
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]


DEFAULTS = {"parts": (), "weights": None, "inner_folds": None}


@CLASSIFIERS.register(
    "fusion",
    description="late fusion: the weighted sum of candidate methods' probabilities, the weights chosen by "
                "inner-CV accuracy over the training subjects, every part refitted",
    source=SOURCE, defaults=DEFAULTS, extra="peers", input="captures", candidates="parts",
    needs_every_candidate=True, check_params=check_params,
    cheap_params=dict(parts=[{"features": ["flagg-stats"], "estimator": "zhou-lda"},
                             {"features": [], "estimator": "minirocket", "params": {"n_kernels": 84}}]),
)
def fusion(random_state=None, sensor=None, **params):
    return build(Fusion, DEFAULTS, random_state, {**params, "sensor": sensor}, name="fusion")
