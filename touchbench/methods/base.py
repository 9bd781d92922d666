"""Named methods: a registry of feature sets + an estimator, declared once.

An entry is a factory ``f(**params) -> MethodSpec``; ``params`` go to the
method's estimator (over the method's own estimator parameters), so a
protocol may write ``{name: touch-et, params: {n_estimators: 100}}``.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

from ..classifiers import CLASSIFIERS
from ..classifiers.adapt import uses_unlabelled_test
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.paramdoc import Param, defaults_params, of_defaults
from ..core.registry import Registry
from ..core.suggest import did_you_mean

__all__ = ["ADAPTED", "CAPTURES", "METHODS", "Method", "MethodSpec", "STOPPED_ON_TEST_LEAK", "SUBJECT_ID_LEAK",
           "TUNED_ON_TEST_LEAK", "expand_candidates", "method_name", "method_spec", "named_methods", "resolve_entry",
           "stops_on_test"]

SUBJECT_ID_LEAK = "the subject's id is a feature"
TUNED_ON_TEST_LEAK = "a parameter chosen by its test accuracy"
STOPPED_ON_TEST_LEAK = "the training epoch chosen by its test accuracy"
#: what a method whose estimator adapts to the test session uses (the results' ``adaptation`` column)
ADAPTED = "unlabelled test captures, per subject"


@dataclass(frozen=True)
class MethodSpec:
    """Feature sets (name, parameters) concatenated in order -> estimator (name, parameters)."""

    name: str
    feature_sets: tuple[tuple[str, dict[str, Any]], ...]
    estimator: str
    estimator_params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.feature_sets and not takes_captures(self.estimator):
            raise TouchbenchError(f"method {self.name!r}: a method needs at least one feature set "
                                  f"(or an estimator that takes the captures themselves)")

    @property
    def takes_captures(self) -> bool:
        """The estimator gets the captures as recorded (native dtype, their own lengths): no feature sets."""
        return not self.feature_sets

    @property
    def feature_names(self) -> list[str]:
        return [n for n, _ in self.feature_sets]


@dataclass(frozen=True)
class Method:
    """One method a protocol evaluates: the unit of a task, a results row and a model file.

    Every spelling of a protocol (``features`` x ``classifiers``, a registered
    method, an inline pipeline, a classifier on captures) is read into one of
    these, so nothing downstream knows which spelling it came from.

    - ``spec``: what is fitted (feature sets -> estimator, with parameters);
    - ``name`` and ``params``: the registered method or classifier the
      protocol named, with the parameters it gave (grids expanded);
    - ``label``: how reports name the method (the protocol's ``label``, or
      ``name`` with the grid values); ``features_label``: how reports name its
      input (the protocol's feature combination, the method's own feature
      sets, or ``captures`` for an estimator that takes the captures);
    - the leaky variants: ``subject_id_feature`` (the subject one-hot
      appended to the features), ``tuned_on_test`` (the label of the
      entry whose grid value is chosen by its test accuracy, "" otherwise)
      and ``stopped_on_test`` (the estimator stops training at the epoch
      of its best accuracy on the test fold, which its ``fit`` is given).

    :attr:`key` is the method's content (never a display label): its
    :attr:`method_id` and, with the evaluation and the fold, its tasks'
    identities and seeds come from it, so renaming a label changes neither.
    """

    label: str
    spec: MethodSpec
    name: str
    params: dict[str, Any] = field(default_factory=dict)
    features_label: str = ""
    subject_id_feature: bool = False
    tuned_on_test: str = ""
    stopped_on_test: bool = False
    #: the frame count the protocol stated for the captures a registered method takes as recorded
    input_frames: int | None = None

    @property
    def key(self) -> dict[str, Any]:
        """What determines the method's results: feature sets, estimator, parameters, variant."""
        key: dict[str, Any] = {"features": [[n, dict(p)] for n, p in self.spec.feature_sets],
                               "estimator": [self.spec.estimator, dict(self.spec.estimator_params)]}
        if self.subject_id_feature:
            key["subject_id_feature"] = True
        if self.stopped_on_test:
            key["stopped_on_test"] = True
        return key

    @property
    def method_id(self) -> str:
        """A short hash of :attr:`key`."""
        return hashlib.sha256(canonical_json(self.key).encode()).hexdigest()[:12]

    @property
    def adaptation(self) -> str:
        """What the method adapts to at test time (:data:`ADAPTED`: its estimator is tagged
        ``unlabelled_test``, it sees each test subject's captures without their labels); "" otherwise."""
        return ADAPTED if uses_unlabelled_test(self.spec.estimator) else ""

    @property
    def leakage(self) -> list[str]:
        """What this method lets the test data inform (empty for an honest method)."""
        return [why for why, on in ((SUBJECT_ID_LEAK, self.subject_id_feature),
                                    (TUNED_ON_TEST_LEAK, bool(self.tuned_on_test)),
                                    (STOPPED_ON_TEST_LEAK, self.stopped_on_test)) if on]


def method_name(method: Method) -> str:
    """The full name of a method, ``FEATURES/LABEL`` as the results name it (``msd+sd/gaus-rf``)."""
    return f"{method.features_label}/{method.label}"


def named_methods(methods: Sequence[Method], text: str, where: str) -> list[Method]:
    """The methods of ``methods`` that ``text`` names: ``FEATURES/LABEL`` (:func:`method_name`, spaces
    around the ``/`` allowed) names one; a label alone names every method with that label (one when it
    is unique). The one reading of a method's name (``run --method``, ``train -m``); nothing named is a
    :class:`TouchbenchError` naming ``where`` (the protocol) with the nearest names."""
    full = "/".join(part.strip() for part in str(text).rsplit("/", 1)) if "/" in str(text) else str(text).strip()
    hit = [m for m in methods if method_name(m) == full] or [m for m in methods if m.label == full]
    if hit:
        return hit
    names = list(dict.fromkeys(method_name(m) for m in methods))
    hint = did_you_mean(full, [*names, *dict.fromkeys(m.label for m in methods)], cutoff=0.4)
    raise TouchbenchError(f"{where} has no method {text!r}{hint} (methods: {', '.join(names)})")


def features_label(spec: MethodSpec, combination_label: str) -> str:
    """How reports name a method's input: the protocol's combination for a pipeline of its
    own, the method's own feature sets for a registered method, ``captures`` for an
    estimator that takes the captures (with the length it takes when one is set)."""
    if spec.takes_captures:
        length = spec.estimator_params.get("length")
        return "captures" + (f"(frames={length})" if length is not None else "")
    if spec.name in METHODS:
        return "+".join(spec.feature_names)
    return combination_label


def _method_params(obj: Any, tags: dict[str, Any]) -> list[Param] | None:
    """A named method's "Parameters": those of the classifier it builds (its ``estimator`` tag, as
    that classifier documents them), each default the method sets in place of the classifier's."""
    est, own = tags.get("estimator"), dict(tags.get("defaults") or {})
    if est not in CLASSIFIERS:
        return None
    entry = CLASSIFIERS.entry(est)
    theirs = of_defaults(entry.obj, entry.tags) or []
    mine = {q.name: q for q in defaults_params(own)}
    out = [replace(p, default=mine[p.name].default, description=f"{p.description} (this method's value; {est}'s "
                   f"is {p.default})".strip()) if p.name in mine and mine[p.name].default != p.default else p
           for p in theirs]
    return out + [replace(q, description=f"given to {est} by this method") for n, q in mine.items()
                  if n not in {p.name for p in theirs}]


# Filled by every module of touchbench.methods (imported on first use of the registry).
METHODS: Registry = Registry("method", package="touchbench.methods", params_of=_method_params)


def method_spec(name: str, **params: Any) -> MethodSpec:
    """The registered method ``name`` with ``params`` given to its estimator."""
    return METHODS.create(name, **params)


def pipeline_method(name: str, feature_sets: tuple[str, ...], estimator: str,
                    estimator_params: dict[str, Any] | None = None):
    """A factory for :data:`METHODS`: ``feature_sets`` (default parameters) -> ``estimator``."""
    base = dict(estimator_params or {})

    def factory(**params: Any) -> MethodSpec:
        """The method's feature sets, then its classifier: a protocol's ``params`` go to the classifier
        (the parameters below, with the values this method sets)."""
        if "random_state" in params:
            raise TouchbenchError(f"method {name!r}: random_state is derived from the protocol's seed")
        return MethodSpec(name=name, feature_sets=tuple((s, {}) for s in feature_sets), estimator=estimator,
                          estimator_params={**base, **params})

    return factory


#: the feature combination that stands for "the captures as recorded" next to a named method
CAPTURES = "raw-window"


def takes_captures(estimator: str) -> bool:
    """Whether the registered classifier ``estimator`` takes captures (tag ``input="captures"``)."""
    return estimator in CLASSIFIERS and CLASSIFIERS.entry(estimator).tags.get("input") == "captures"


def stops_on_test(estimator: str) -> bool:
    """Whether the registered classifier ``estimator`` can stop training on the test data's accuracy
    (tag ``stops_on_test``: its ``fit`` takes a ``test_set``; the audit's stopped-on-test variant)."""
    return estimator in CLASSIFIERS and bool(CLASSIFIERS.entry(estimator).tags.get("stops_on_test"))


def expand_candidates(classifier: str, params: dict[str, Any]) -> dict[str, Any]:
    """``params`` with the candidates of a classifier that fits other methods inside it written out.

    Such a classifier (``nested-select``, ``fusion``) is tagged ``candidates=`` with the name
    of the parameter holding them (``candidates``, ``parts``). A registered method's name, or
    ``{name, params}``, becomes its feature sets and estimator (``{label, features, estimator,
    params}``); so does the name of a classifier that takes the captures themselves
    (``minirocket``: no feature sets). The classifier never needs the method registry and the
    task's identity covers every candidate's code."""
    key = CLASSIFIERS.entry(classifier).tags.get("candidates") if classifier in CLASSIFIERS else None
    if not key:
        return params
    key = key if isinstance(key, str) else "candidates"
    return {**params, key: [_written_out(classifier, c) for c in params.get(key) or []]}


def _written_out(classifier: str, c: Any) -> Any:
    """One candidate of ``classifier`` written out (see :func:`expand_candidates`); a mapping
    without ``name`` is already written out."""
    name, p = (c, {}) if isinstance(c, str) else (c.get("name"), dict(c.get("params") or {})) if isinstance(c, dict) else (None, {})
    if name is None:
        return c
    label = c.get("label", name) if isinstance(c, dict) else name
    if name in METHODS:
        m = method_spec(name, **p)
        return {"label": label, "features": [[n, dict(sp)] for n, sp in m.feature_sets], "estimator": m.estimator,
                "params": dict(m.estimator_params)}
    if takes_captures(name):
        return {"label": label, "features": [], "estimator": name, "params": p}
    raise TouchbenchError(f"classifier {classifier!r}: candidate {name!r} is not a registered method "
                          f"(nor a classifier that takes the captures); "
                          f"write it as {{features: [...], estimator: ..., params: {{...}}}}")


def resolve_entry(sets: list[tuple[str, dict[str, Any]]] | tuple, classifier: str,
                  params: dict[str, Any]) -> MethodSpec:
    """The method a protocol's (feature combination, classifier) entry stands for.

    A classifier of the registry with the combination's sets in front of it;
    or, when ``classifier`` names a registered method (``touch-et``...),
    that method, whose own feature sets replace the combination: the
    combination must then be ``[raw-window]`` alone (the captures as
    recorded, which is what the method takes). A classifier that takes the
    captures themselves (the CNN, the aeon peers: tag ``input="captures"``)
    beside ``[raw-window]`` gets them as recorded, in their native dtype,
    with raw-window's ``frames`` as its stated ``length`` (how many frames
    it takes; a shorter capture padded by repeating its last frame).
    """
    if classifier in METHODS:
        names = [n for n, _ in sets]
        if names != [CAPTURES]:
            raise TouchbenchError(
                f"method {classifier!r} computes its own feature sets "
                f"({', '.join(METHODS.entry(classifier).tags.get('feature_sets', ()))}): pair it with the "
                f"feature combination [{CAPTURES}] (the captures as recorded), not [{', '.join(names)}]")
        return method_spec(classifier, **params)
    names = [n for n, _ in sets]
    if names == [CAPTURES] and takes_captures(classifier):
        window = dict(sets[0][1])
        if int(window.get("offset", 0) or 0) != 0:
            raise TouchbenchError(f"classifier {classifier!r} takes the captures from their first frame: "
                                  f"raw-window's offset={window['offset']} beside it is not supported")
        est_params = expand_candidates(classifier, dict(params))
        if "frames" in window and "length" not in est_params and "length" in (CLASSIFIERS.entry(classifier).tags.get("defaults") or {}):
            est_params["length"] = int(window["frames"])
        return MethodSpec(name=classifier, feature_sets=(), estimator=classifier, estimator_params=est_params)
    return MethodSpec(name=classifier, feature_sets=tuple((n, dict(p)) for n, p in sets), estimator=classifier,
                      estimator_params=dict(params))
