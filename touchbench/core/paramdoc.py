"""A registered component's "Parameters" section, generated from what it declares, so that it
cannot drift from the parameters it takes.

Three kinds of declaration are read:

- a pydantic model (a scheme's or a decision rule's ``Params``): each field's name, type, default,
  bounds (``ge``/``gt``/``le``/``lt``, ``min_length``, ``Literal`` choices) and its
  ``Field(description=...)``;
- scikit-learn's ``_parameter_constraints`` (a feature set): each ``__init__`` parameter, its
  constraints in words (``Interval`` -> "an integer in [1, inf)", ``StrOptions`` -> "one of 'a',
  'b'"), its ``__init__`` default and its line in the class's ``_parameter_docs`` dict;
- a registered factory's ``defaults`` (a classifier): each parameter with the paper's value.

:func:`with_parameters` puts the section in a docstring, in place of a hand-written one; the
registries call :func:`document` on each entry they register.

>>> from pydantic import BaseModel, Field
>>> class P(BaseModel):
...     n: int = Field(default=5, ge=1, description="how many vote.")
>>> print(render(model_params(P)), end="")
Parameters
----------
n : int in [1, inf), default 5
    how many vote.
"""

from __future__ import annotations

import inspect
import re
import textwrap
import types
import typing
from dataclasses import dataclass
from typing import Any, Literal

__all__ = ["Param", "constraint_params", "constraint_words", "defaults_params", "document", "model_params",
           "of_constraints", "of_defaults", "of_model", "render", "with_parameters"]

#: the headings of numpydoc sections that follow "Parameters"
_AFTER = ("Returns", "Yields", "Raises", "See Also", "Notes", "References", "Examples", "Attributes", "Methods")


@dataclass(frozen=True)
class Param:
    """One parameter as documented: ``kind`` its type and domain in words, ``default`` as written
    (None: required), ``description`` one or more sentences ("" when none is declared)."""

    name: str
    kind: str
    default: str | None
    description: str = ""


# ----------------------------------------------------------------- pydantic models
def _type_words(tp: Any) -> str:
    """A type annotation in words: ``int``, ``list of float``, ``float or None``, ``one of 'a', 'b'``."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if tp is type(None):
        return "None"
    if origin is typing.Annotated:
        return _type_words(args[0]) + _bounds(args[1:], args[0] is str)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_words(a) for a in args)
    if origin is tuple and args and Ellipsis not in args:
        return "(" + ", ".join(_type_words(a) for a in args) + ")"
    if origin in (list, tuple, set, dict):
        name = {list: "list", tuple: "tuple", set: "set", dict: "mapping"}[origin]
        inner = [a for a in args if a is not Ellipsis]
        if origin is dict or not inner:
            return name
        return f"{name} of " + ", ".join(_type_words(a) for a in inner)
    if tp is Any:
        return "any value"
    return getattr(tp, "__name__", str(tp))


def _bounds(metadata: Any, text: bool = False) -> str:
    """The bounds in ``metadata`` (annotated-types' ``Ge``, ``Gt``, ``Le``, ``Lt``, ``MinLen``, or
    pydantic's ``FieldInfo``) as `` in [lo, hi)`` and ``, at least n items`` (``not empty`` for a
    ``text`` of at least one character)."""
    lo = hi = None
    closed_lo = closed_hi = True
    min_len = None
    for m in metadata:
        for inner in getattr(m, "metadata", None) or [m]:
            name = type(inner).__name__
            if name in ("Ge", "Gt"):
                lo, closed_lo = getattr(inner, name.lower()), name == "Ge"
            elif name in ("Le", "Lt"):
                hi, closed_hi = getattr(inner, name.lower()), name == "Le"
            elif name == "MinLen":
                min_len = inner.min_length
    out = ""
    if lo is not None or hi is not None:
        out += f" in {'[' if closed_lo and lo is not None else '('}{_num(lo, '-inf')}, " \
               f"{_num(hi, 'inf')}{']' if closed_hi and hi is not None else ')'}"
    if min_len is not None and min_len > 0:
        out += ", not empty" if min_len == 1 else f", at least {min_len} {'characters' if text else 'items'}"
    return out


def _num(v: Any, missing: str) -> str:
    return missing if v is None else f"{v:g}" if isinstance(v, float) else str(v)


def _default(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return repr(v)


def _field_words(tp: Any, metadata: list[Any]) -> str:
    """A field's type with its bounds; an optional field's as ``int in [1, inf) or None``."""
    args = typing.get_args(tp)
    if typing.get_origin(tp) in (typing.Union, types.UnionType) and type(None) in args and metadata:
        rest = [a for a in args if a is not type(None)]
        return " or ".join(_type_words(a) for a in rest) + _bounds(metadata, rest == [str]) + " or None"
    return _type_words(tp) + _bounds(metadata, tp is str)


def model_params(model: Any) -> list[Param]:
    """The fields of the pydantic ``model``, in order."""
    out = []
    for name, f in model.model_fields.items():
        kind = _field_words(f.annotation, f.metadata)
        default = None if f.is_required() else _default(f.get_default(call_default_factory=True))
        out.append(Param(name, kind, default, (f.description or "").strip()))
    return out


# ----------------------------------------------------------------- scikit-learn constraints
def constraint_words(constraints: Any) -> str:
    """scikit-learn's constraints of one parameter in words, each alternative joined by "or"."""
    from sklearn.utils._param_validation import Interval, Options, StrOptions  # scikit-learn only when asked

    words = []
    for c in constraints if isinstance(constraints, list) else [constraints]:
        if c is None:
            words.append("None")
        elif isinstance(c, Interval):
            what = "an integer" if c.type.__name__ == "Integral" else "a number"
            left = "[" if c.closed in ("left", "both") and c.left is not None else "("
            right = "]" if c.closed in ("right", "both") and c.right is not None else ")"
            words.append(f"{what} in {left}{_num(c.left, '-inf')}, {_num(c.right, 'inf')}{right}")
        elif isinstance(c, (StrOptions, Options)):
            words.append("one of " + ", ".join(repr(o) for o in sorted(c.options, key=str)))
        elif isinstance(c, type):
            words.append({"Integral": "an integer", "Real": "a number", "Number": "a number"}.get(c.__name__, c.__name__))
        elif isinstance(c, str):
            words.append({"array-like": "a list or array", "boolean": "a boolean", "random_state": "a seed"}.get(c, c))
        else:
            words.append(str(c))
    return " or ".join(words)


def constraint_params(cls: type) -> list[Param]:
    """The ``__init__`` parameters of the scikit-learn-style ``cls``, with its
    ``_parameter_constraints`` in words and its ``_parameter_docs`` lines (a base class's lines
    hold for its subclasses, unless they give their own)."""
    constraints = getattr(cls, "_parameter_constraints", {})
    docs = {k: v for c in reversed(cls.__mro__) for k, v in vars(c).get("_parameter_docs", {}).items()}
    out = []
    for p in inspect.signature(cls.__init__).parameters.values():
        if p.name == "self" or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        kind = constraint_words(constraints[p.name]) if p.name in constraints else "any value"
        default = None if p.default is p.empty else _default(p.default)
        out.append(Param(p.name, kind, default, docs.get(p.name, "").strip()))
    return out


def defaults_params(defaults: dict[str, Any], docs: dict[str, str] | None = None) -> list[Param]:
    """A factory's ``defaults`` (the paper's settings), each with its ``docs`` line where one is given."""
    docs = docs or {}
    return [Param(k, "any value" if v is None else type(v).__name__, _default(v), docs.get(k, "").strip())
            for k, v in defaults.items()]


# ----------------------------------------------------------------- the section
def render(params: list[Param]) -> str:
    """The numpydoc "Parameters" section of ``params``."""
    lines = ["Parameters", "----------"]
    if not params:
        lines.append("None.")
    for p in params:
        lines.append(f"{p.name} : {p.kind}, " + ("required" if p.default is None else f"default {p.default}"))
        if p.description:
            lines.extend(textwrap.wrap(" ".join(p.description.split()), 100, initial_indent="    ",
                                       subsequent_indent="    ", break_long_words=False, break_on_hyphens=False))
    return "\n".join(lines) + "\n"


def with_parameters(doc: str | None, section: str) -> str:
    """``doc`` (dedented) with ``section`` in place of its "Parameters" section, or else before the
    first section that follows one in numpydoc's order, or else at its end."""
    text = inspect.cleandoc(doc or "")
    heading = re.compile(r"^(\w[\w ]*)\n-{3,}$", re.M)
    found = [(m.start(), m.group(1)) for m in heading.finditer(text)]
    params = [i for i, (_, h) in enumerate(found) if h == "Parameters"]
    if params:
        i = params[0]
        end = found[i + 1][0] if i + 1 < len(found) else len(text)
        return (text[:found[i][0]] + section + ("\n" + text[end:] if end < len(text) else "")).rstrip() + "\n"
    after = [start for start, h in found if h in _AFTER]
    if after:
        return text[:after[0]] + section + "\n" + text[after[0]:].rstrip() + "\n"
    return (text.rstrip() + "\n\n" if text.strip() else "") + section


def document(obj: Any, params: list[Param] | None) -> None:
    """Put the section of ``params`` in ``obj``'s docstring (nothing when ``params`` is None)."""
    if params is not None:
        obj.__doc__ = with_parameters(obj.__doc__, render(params))


# ----------------------------------------------------------------- what a registry reads (``params_of``)
def of_model(obj: Any, tags: dict[str, Any]) -> list[Param] | None:
    """A registered class's parameters from its pydantic ``Params`` model (schemes, decision rules)."""
    model = getattr(obj, "Params", None)
    return model_params(model) if isinstance(obj, type) and hasattr(model, "model_fields") else None


def of_constraints(obj: Any, tags: dict[str, Any]) -> list[Param] | None:
    """A registered scikit-learn-style class's ``__init__`` parameters (feature sets)."""
    return constraint_params(obj) if isinstance(obj, type) else None


def of_defaults(obj: Any, tags: dict[str, Any]) -> list[Param] | None:
    """A registered factory's parameters from its ``defaults`` tag (classifiers)."""
    defaults = tags.get("defaults")
    return defaults_params(defaults, tags.get("parameter_docs")) if isinstance(defaults, dict) else None
