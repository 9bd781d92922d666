"""The method entries of a protocol: feature sets, classifiers and ``methods:`` as written
(:class:`FeatureRef`, :class:`ClassifierSpec`, :class:`MethodRef`), as expanded
(:class:`FeatureCombination`, :class:`ClassifierEntry`), and the parameter grids
(:func:`expand_grid`) and labels of the expansion."""

from __future__ import annotations

import itertools
import json
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..classifiers import CLASSIFIERS
from ..core.suggest import did_you_mean
from ..features import FEATURES
from ..methods import METHODS
from ..methods.base import takes_captures
from .errors import _ErrorAt

__all__ = ["ClassifierEntry", "FeatureCombination", "expand_grid"]


# ----------------------------------------------------------------- helpers
def _is_grid(v: Any) -> bool:
    return isinstance(v, dict) and set(v) == {"grid"}


def expand_grid(params: dict[str, Any]) -> list[dict[str, Any]]:
    """Expand ``{p: {grid: [a, b]}}`` values into one parameter dict per combination.

    >>> expand_grid({"a": 1, "b": {"grid": [2, 3]}})
    [{'a': 1, 'b': 2}, {'a': 1, 'b': 3}]
    """
    keys = [k for k, v in params.items() if _is_grid(v)]
    if not keys:
        return [dict(params)]
    out = []
    for combo in itertools.product(*(params[k]["grid"] for k in keys)):
        d = dict(params)
        d.update(zip(keys, combo))
        out.append(d)
    return out


def _fmt_value(v: Any) -> str:
    return json.dumps(v, default=str) if not isinstance(v, str) else v


def _label(name: str, params: dict[str, Any], keys: list[str] | None = None) -> str:
    keys = sorted(params) if keys is None else keys
    if not keys:
        return name
    return f"{name}(" + ",".join(f"{k}={_fmt_value(params[k])}" for k in keys) + ")"


# ----------------------------------------------------------------- models
class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid")


def _registry_check(reg, name: str) -> str:
    if name not in reg:
        raise ValueError(reg.suggest(name))
    return name


class FeatureRef(_Model):
    """One feature set of a combination: a registered name and its parameters."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)

    @field_validator("name")
    @classmethod
    def _known(cls, v: str) -> str:

        return _registry_check(FEATURES, v)


class ClassifierSpec(_Model):
    """A classifier entry: registered name, parameters (may hold grids), label.

    The name is a registered classifier, or a registered method
    (:data:`touchbench.methods.METHODS`, e.g. ``touch-et``): a method brings
    its own feature sets and takes the captures as recorded, so it is paired
    with the ``[raw-window]`` combination, and its parameters go to its
    estimator."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)
    label: str | None = None
    #: leaky variant: of the grid in ``params``, only the value with the best mean test accuracy
    #: is reported (see :class:`MethodRef`)
    tuned_on_test: bool = False
    #: leaky variant: training stopped at the epoch of the best test accuracy (see :class:`MethodRef`)
    stopped_on_test: bool = False

    @field_validator("name")
    @classmethod
    def _known(cls, v: str) -> str:

        return v if v in METHODS else _registry_check(CLASSIFIERS, v)

    @model_validator(mode="after")
    def _grid_to_tune(self) -> "ClassifierSpec":
        if self.tuned_on_test and not any(_is_grid(v) for v in self.params.values()):
            raise _ErrorAt(("tuned_on_test",), "tuned_on_test chooses among a grid: give a parameter {grid: [values]}")
        return self


class MethodRef(_Model):
    """An entry of ``methods:``: a registered method, or an inline pipeline.

    ``name``: a registered method (``touch-et``...), which brings its own
    feature sets and takes the captures as recorded, or a classifier that
    takes captures itself (``minirocket``, ``cnn``...); ``params`` go to its
    estimator. Or ``features`` (a combination, concatenated) and
    ``estimator`` (a registered classifier) with its ``params``. ``params``
    may hold grids; ``label`` names the entry in results.
    """

    name: str | None = None
    features: list[FeatureRef] | None = Field(default=None, min_length=1)
    estimator: str | None = None
    params: dict[str, Any] = Field(default_factory=dict)
    label: str | None = None
    #: leaky variant: each capture's subject (one-hot over the dataset's subjects) appended to the
    #: feature matrix, as Cang et al. 2015 did with the participant id
    subject_id_feature: bool = False
    #: leaky variant: of the grid in ``params``, only the value with the best mean test accuracy is
    #: reported (a parameter chosen on the test folds, as Al-mashhadani et al. chose the frame length)
    tuned_on_test: bool = False
    #: leaky variant: the estimator is given the test fold with its labels and keeps the training epoch
    #: of its best test accuracy (early stopping on the held-out subject); the ``cnn`` can
    stopped_on_test: bool = False

    @model_validator(mode="after")
    def _variants(self) -> "MethodRef":
        if self.tuned_on_test and not any(_is_grid(v) for v in self.params.values()):
            raise _ErrorAt(("tuned_on_test",), "tuned_on_test chooses among a grid: give a parameter {grid: [values]}")
        if self.subject_id_feature and self.features is None and self.name is not None and self.name not in METHODS:
            raise _ErrorAt(("subject_id_feature",), f"{self.name!r} takes the captures themselves: no feature "
                                                    "matrix to append the subject id to")
        return self

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, d: Any) -> Any:
        if isinstance(d, str):
            return {"name": d}
        if isinstance(d, dict) and isinstance(d.get("features"), list):
            d = {**d, "features": [{"name": f} if isinstance(f, str) else f for f in d["features"]]}
        return d

    @field_validator("name")
    @classmethod
    def _known_method(cls, v: str | None) -> str | None:
        if v is None or v in METHODS or takes_captures(v):
            return v
        capture_estimators = [n for n in CLASSIFIERS.names() if takes_captures(n)]
        names = sorted([*METHODS.names(), *capture_estimators])
        raise ValueError(f"unknown method {v!r}{did_you_mean(v, names)} (registered methods: "
                         f"{', '.join(METHODS.names())}; estimators that take captures: {', '.join(capture_estimators)})")

    @field_validator("estimator")
    @classmethod
    def _known_estimator(cls, v: str | None) -> str | None:
        return None if v is None else _registry_check(CLASSIFIERS, v)

    @model_validator(mode="after")
    def _one_form(self) -> "MethodRef":
        if (self.name is None) == (self.estimator is None) or (self.estimator is None) != (self.features is None):
            raise ValueError("a method entry is either a registered method (name) or an inline pipeline "
                             "(features and estimator)")
        return self


class FeatureCombination(BaseModel):
    """An expanded feature combination: concatenation of (name, params) sets."""

    label: str
    sets: list[tuple[str, dict[str, Any]]]

    @property
    def names(self) -> list[str]:
        return [n for n, _ in self.sets]


class ClassifierEntry(BaseModel):
    """An expanded classifier entry (one value of every grid)."""

    label: str
    name: str
    params: dict[str, Any]
    #: the leaky variants of a ``methods:`` entry (see :class:`MethodRef`)
    subject_id_feature: bool = False
    #: the entry whose grid is chosen on test accuracy (its label without the grid), "" otherwise
    tuned_on_test: str = ""
    #: training stopped at the epoch of the best test accuracy (see :class:`MethodRef`)
    stopped_on_test: bool = False
