"""Declared parameter domains, checked one parameter at a time: scikit-learn's
``_parameter_constraints`` (``Interval``, ``StrOptions``, types...) of any object, with two rules
of touchbench's own: a boolean is never read as a number (Python's ``True`` is an ``int``), and a
string outside a ``StrOptions`` choice is answered with the nearest choice. :class:`ListOf` declares a
list whose every item has a domain (a pair of bounds, a list of counts), which scikit-learn's own
constraints cannot say."""

from __future__ import annotations

import copy
from numbers import Integral, Number, Real
from typing import Any

from sklearn.utils._param_validation import Interval, Options, StrOptions, make_constraint, validate_parameter_constraints

from .suggest import did_you_mean

__all__ = ["ListOf", "declared_failures"]

#: the types whose instances a boolean is (Python's bool is an int): allowed only as a number
_NUMBER_TYPES = (int, float, Integral, Real, Number)


def _number_only(constraints: Any, value: bool) -> bool:
    """Whether the boolean ``value`` meets ``constraints`` only as a number (an ``Interval`` or a
    numeric type), none of them saying a boolean (``"boolean"``, ``"verbose"``)."""
    if not isinstance(constraints, list):
        return False
    return _met_only_as_number([c for c in map(make_constraint, constraints) if c.is_satisfied_by(value)])


def _met_only_as_number(met: list) -> bool:
    """Whether the constraints a boolean ``met`` (made constraints) are all numeric ones: some, and
    none of them saying a boolean."""
    return bool(met) and all(isinstance(c, Interval) or getattr(c, "type", None) in _NUMBER_TYPES for c in met)


class ListOf(Options):
    """A list or tuple whose every item meets one of ``items`` (scikit-learn constraints: an
    ``Interval``, a type, None...; a boolean never read as a number), of exactly ``length`` items
    (None: at least ``min_length``), in non-decreasing order when ``ordered`` (a ``(low, high)``
    pair). Declared in ``_parameter_constraints`` like any constraint: scikit-learn asks it as one of
    its own ``Options`` (the kind it takes), and a refusal says it in words.

    >>> from numbers import Real
    >>> pair = ListOf([Interval(Real, 0, 1, closed="both")], length=2, ordered=True)
    >>> pair.is_satisfied_by((0.2, 0.5)), pair.is_satisfied_by((0.5, 0.2)), pair.is_satisfied_by([True, 1])
    (True, False, False)
    >>> print(pair)
    a list of 2 items, each a float in the range [0.0, 1.0], low <= high
    """

    def __init__(self, items: list, *, length: int | None = None, min_length: int = 0, ordered: bool = False):
        super().__init__(object, set())
        self.items = [make_constraint(c) for c in _in_order(list(items))]
        self.length, self.min_length, self.ordered = length, min_length, ordered

    def _item_ok(self, v: Any) -> bool:
        met = [c for c in self.items if c.is_satisfied_by(v)]
        return bool(met) and not (isinstance(v, bool) and _met_only_as_number(met))

    def is_satisfied_by(self, val: Any) -> bool:
        if not isinstance(val, (list, tuple)):
            return False
        if len(val) != self.length if self.length is not None else len(val) < self.min_length:
            return False
        if not all(self._item_ok(v) for v in val):
            return False
        return not self.ordered or all(a <= b for a, b in zip(val, val[1:]))

    def __str__(self) -> str:
        n = (f"a list of {self.length} items" if self.length is not None else "a non-empty list" if self.min_length == 1
             else f"a list of at least {self.min_length} items" if self.min_length else "a list")
        return (f"{n}, each {' or '.join(map(str, self.items))}"
                + (", low <= high" if self.ordered else ""))


def _choices(constraints: Any) -> list[str]:
    return sorted(o for c in (constraints if isinstance(constraints, list) else []) if isinstance(c, StrOptions)
                  for o in c.options if isinstance(o, str))


def _in_order(constraints: Any) -> Any:
    """``constraints`` with each ``StrOptions``' choices in sorted order, so that a refusal lists them
    the same way in every process (a set of strings iterates in an order that changes with the
    interpreter's hash seed)."""
    if not isinstance(constraints, list):
        return constraints
    out = []
    for c in constraints:
        if isinstance(c, StrOptions) and all(isinstance(o, str) for o in c.options):
            c = copy.copy(c)
            c.options = dict.fromkeys(sorted(c.options))  # ordered, and answers `in` as the set did
        out.append(c)
    return out


def declared_failures(constraints: dict[str, Any], values: dict[str, Any], owner: str) -> dict[str, str]:
    """``parameter -> message`` for each of ``values`` that its entry of ``constraints`` (scikit-learn's
    form) refuses; ``owner`` names the object in the message. A parameter without an entry is not asked."""
    out: dict[str, str] = {}
    for k, c in constraints.items():
        if k not in values:
            continue
        v = values[k]
        try:
            validate_parameter_constraints({k: _in_order(c)}, {k: v}, caller_name=owner)
        except (ValueError, TypeError) as e:
            hint = did_you_mean(v, _choices(c)) if isinstance(v, str) else ""
            out[k] = str(e).rstrip(".") + hint if hint else str(e)
        else:
            if isinstance(v, bool) and _number_only(c, v):
                out[k] = f"The {k!r} parameter of {owner} is a number, got {v!r}: a boolean is not read as a number"
    return out
