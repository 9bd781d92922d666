"""Named methods: a registry of feature sets + an estimator, declared once.

An entry is a factory ``f(**params) -> MethodSpec``; ``params`` go to the
method's estimator (over the method's own estimator parameters), so a
protocol may write ``{name: touch-et, params: {n_estimators: 100}}``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..core.errors import TouchbenchError
from ..core.registry import Registry

__all__ = ["CAPTURES", "METHODS", "MethodSpec", "method_spec", "resolve_entry"]


@dataclass(frozen=True)
class MethodSpec:
    """Feature sets (name, parameters) concatenated in order -> estimator (name, parameters)."""

    name: str
    feature_sets: tuple[tuple[str, dict[str, Any]], ...]
    estimator: str
    estimator_params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.feature_sets:
            raise TouchbenchError(f"method {self.name!r}: a method needs at least one feature set")

    @property
    def feature_names(self) -> list[str]:
        return [n for n, _ in self.feature_sets]


# Filled by every module of touchbench.methods (imported on first use of the registry).
METHODS: Registry = Registry("method", package="touchbench.methods")


def method_spec(name: str, **params: Any) -> MethodSpec:
    """The registered method ``name`` with ``params`` given to its estimator."""
    return METHODS.create(name, **params)


def pipeline_method(name: str, feature_sets: tuple[str, ...], estimator: str,
                    estimator_params: dict[str, Any] | None = None):
    """A factory for :data:`METHODS`: ``feature_sets`` (default parameters) -> ``estimator``."""
    base = dict(estimator_params or {})

    def factory(**params: Any) -> MethodSpec:
        if "random_state" in params:
            raise TouchbenchError(f"method {name!r}: random_state is derived from the protocol's seed")
        return MethodSpec(name=name, feature_sets=tuple((s, {}) for s in feature_sets), estimator=estimator,
                          estimator_params={**base, **params})

    return factory


#: the feature combination that stands for "the captures as recorded" next to a named method
CAPTURES = "raw-window"


def resolve_entry(sets: list[tuple[str, dict[str, Any]]] | tuple, classifier: str,
                  params: dict[str, Any]) -> MethodSpec:
    """The method a protocol's (feature combination, classifier) entry stands for.

    A classifier of the registry with the combination's sets in front of it;
    or, when ``classifier`` names a registered method (``touch-et``...),
    that method, whose own feature sets replace the combination: the
    combination must then be ``[raw-window]`` alone (the captures as
    recorded, which is what the method takes).
    """
    if classifier in METHODS:
        names = [n for n, _ in sets]
        if names != [CAPTURES]:
            raise TouchbenchError(
                f"method {classifier!r} computes its own feature sets "
                f"({', '.join(METHODS.entry(classifier).tags.get('feature_sets', ()))}): pair it with the "
                f"feature combination [{CAPTURES}] (the captures as recorded), not [{', '.join(names)}]")
        return method_spec(classifier, **params)
    return MethodSpec(name=classifier, feature_sets=tuple((n, dict(p)) for n, p in sets), estimator=classifier,
                      estimator_params=dict(params))
