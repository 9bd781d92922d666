"""The classifier registry.

Each entry is a factory ``f(random_state=None, **params) -> estimator``
(``f(random_state=None, sensor=None, **params)`` for a classifier that
needs the sensor: the run engine passes the dataset's)
registered with ``description`` (one line), ``source`` (paper and section),
``defaults`` (the paper's settings, as a dict), ``extra`` (the optional
install it needs: None, ``"deep"``, ``"peers"``, ``"xgboost"``, or several
joined by commas, ``"peers,deep"``) and, where the defaults
are slow, ``cheap_params`` (smaller settings that run the same code paths in
seconds: the tests' estimator checks use them). The estimators are plain
scikit-learn estimators (or follow that API), so users can use them in their
own pipelines.

Every estimator declares the domain of each of its parameters as
scikit-learn's ``_parameter_constraints`` (types, ``Interval`` bounds,
``StrOptions`` choices, :class:`touchbench.core.constraints.ListOf` for a
list whose items have a domain); a protocol's validation asks them of every
entry, and a wrapper calls :func:`check_declared` when it is fitted. A rule
that ties parameters together (a weight vector per part, an inner
estimator's own parameters) is the classifier's check in the tag
``check_params``: a function of its parameters over its defaults that
raises :class:`ParamError` naming the parameter. :func:`check_classifier_params`
calls it, and that of every classifier nested in the parameters (the
candidates a ``candidates=`` tag names, written out; an inner estimator that
the check itself hands to :func:`check_nested_params`; each asked its
declared domains first), so a protocol's validation refuses the
value with its file, line and field, before anything runs; the classifier
calls the same function when it is fitted.

Counts every classifier shares are bounded here, whatever the classifier
(:data:`COUNT_BOUNDS`): ``n_estimators`` a whole number 1..100000 and
``inner_folds`` None or 2..1000 (the inner splits never use more folds than
training subjects), so ``n_estimators: 1e12`` is refused at validation rather
than running for ever, even by a classifier that declares no bound of its own
(scikit-learn's forests); touchbench's estimators declare the same bounds
(:func:`count_constraint`).
"""

from __future__ import annotations

from numbers import Integral
from typing import Any

from sklearn.utils._param_validation import Interval

from ..core.constraints import declared_failures
from ..core.errors import TouchbenchError
from ..core.introspect import with_accepted
from ..core.paramdoc import of_defaults
from ..core.registry import Registry

# Filled by every module of touchbench.classifiers (imported on first use of the registry).
CLASSIFIERS: Registry = Registry("classifier", package="touchbench.classifiers", params_of=of_defaults)


def make_classifier(name: str, random_state: int | None = None, sensor: Any = None, **params: Any):
    """Build the registered classifier ``name`` with ``params`` over its defaults.

    ``sensor`` (the dataset's :class:`touchbench.datasets.model.SensorSpec`)
    is passed when the factory takes it (the raw-frame classifiers take
    their grid and frame rate from it), by the same rule as
    :func:`touchbench.features.base.make_feature_set`.
    """
    factory = CLASSIFIERS.get(name)
    return CLASSIFIERS.create(name, random_state=random_state, **with_accepted(factory, params, sensor=sensor))


class ParamError(TouchbenchError, ValueError):
    """A parameter value a classifier refuses: ``field`` is its path below the classifier's
    parameters (``("weights", 0)``: the first weight vector)."""

    def __init__(self, field: str | tuple, message: str):
        self.field = field if isinstance(field, tuple) else (field,)
        super().__init__(message)


#: parameter -> (smallest, largest, what it counts): bounds every classifier that takes it shares
COUNT_BOUNDS = {"n_estimators": (1, 100_000, "trees or boosting rounds"),
                "inner_folds": (2, 1000, "inner folds of whole subjects, or None for one per training subject")}


def count_constraint(key: str) -> list:
    """The declared domain (``_parameter_constraints``) of the shared count ``key`` of
    :data:`COUNT_BOUNDS`: a whole number within its bounds."""
    low, high, _ = COUNT_BOUNDS[key]
    return [Interval(Integral, low, high, closed="both")]


def _check_counts(name: str, params: dict[str, Any]) -> None:
    for key, (low, high, what) in COUNT_BOUNDS.items():
        value = params.get(key)
        if key not in params or (value is None and key == "inner_folds"):
            continue
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise ParamError(key, f"{name}: {key} must be a whole number from {low} to {high:,} ({what}), "
                                  f"got {value!r}")


def check_declared(estimator: Any) -> None:
    """Refuse the first parameter of ``estimator`` outside its declared domain
    (``_parameter_constraints``, :func:`touchbench.core.constraints.declared_failures`: a boolean
    never read as a number), as a :class:`ParamError` naming it: what a protocol's validation
    says, said again when the estimator is fitted from Python."""
    found = _declared_failures(estimator)
    if found:
        key, message = next(iter(found.items()))
        raise ParamError(key, message)


def _declared_failures(estimator: Any) -> dict[str, str]:
    return declared_failures(getattr(estimator, "_parameter_constraints", {}), estimator.get_params(deep=False),
                             type(estimator).__name__)


def _check_declared_params(name: str, params: dict[str, Any]) -> None:
    """The declared domains of the classifier ``name`` built with ``params``: the first refused value
    as a :class:`ParamError`, beyond what its own defaults break (a subclass widening its parent's
    domain); nothing when it cannot be built here (a missing extra, a value its constructor
    refuses: refused when it is built)."""
    try:
        built, default = make_classifier(name, random_state=0, **params), make_classifier(name, random_state=0)
    except Exception:
        return
    if not callable(getattr(built, "get_params", None)):
        return
    own = set(_declared_failures(default))
    found = {k: m for k, m in _declared_failures(built).items() if k not in own}
    if found:
        key, message = next(iter(found.items()))
        raise ParamError(key, message)


def check_classifier_params(name: str, params: dict[str, Any], declared: bool = True) -> None:
    """Refuse a value of ``params`` the registered classifier ``name`` cannot run with (module
    docstring): its declared domains (unless ``declared`` is False: a caller that has just checked
    them on the built estimator), the shared counts, its ``check_params`` over its defaults,
    then each candidate of its ``candidates=``
    parameter that is written out (``{features, estimator, params}``), as a nested classifier."""
    entry = CLASSIFIERS.entry(name)
    full = {**(entry.tags.get("defaults") or {}), **params}
    if declared:
        _check_declared_params(name, params)
    _check_counts(name, full)
    check = entry.tags.get("check_params")
    if check is not None:
        check(full)
    key = entry.tags.get("candidates")
    if key:
        key = key if isinstance(key, str) else "candidates"
        entries = full.get(key) or ()
        for i, c in enumerate(entries if isinstance(entries, (list, tuple)) else ()):
            if isinstance(c, dict) and isinstance(c.get("params") or {}, dict):
                check_nested_params(c.get("estimator"), dict(c.get("params") or {}), (key, i, "params"))


def check_nested_params(name: Any, params: Any, at: tuple) -> None:
    """:func:`check_classifier_params` of a registered classifier ``name`` nested at ``at`` in
    another's parameters (its refusal's field prefixed with ``at``); nothing for a name that is not
    registered or parameters that are not a mapping (the classifier refuses those when it is built)."""
    if not isinstance(name, str) or name not in CLASSIFIERS or not isinstance(params, dict):
        return
    try:
        check_classifier_params(name, params)
    except ParamError as e:
        raise ParamError(at + e.field, str(e)) from None
