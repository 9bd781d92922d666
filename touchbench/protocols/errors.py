"""Protocol errors and where they point: :class:`ProtocolError` (every line names the file, line
and field), the YAML document's line of each field, and pydantic's errors mapped to them."""

from __future__ import annotations

import typing
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError

from ..core.errors import TouchbenchError
from ..core.suggest import did_you_mean
from ..core.yamlsafe import best_line, number_as_text, yaml_nodes

__all__ = ["ProtocolError", "UnknownEvaluation"]


class UnknownEvaluation(TouchbenchError):
    """An evaluation name the protocol does not have (``--evaluation``)."""


class ProtocolError(TouchbenchError):
    """An invalid protocol: every line names the file, line and field."""

    def __init__(self, message: str, issues: list[tuple[str, int | None, str, str]] | None = None):
        super().__init__(message)
        self.issues = issues or []


class _ErrorAt(ValueError):
    """Raised by a model validator about one of the model's fields (``loc``
    below the model), so that the error names that field's line; ``more``: further
    ``(loc, message)`` problems found with it, each reported at its own line."""

    def __init__(self, loc: tuple, message: str, more: list[tuple[tuple, str]] | None = None):
        super().__init__(message)
        self.loc = loc
        self.more = more or []


# ----------------------------------------------------------------- YAML with lines
# (the walk over a composed document and the line of a field: core.yamlsafe)
def _boolean_map(root: yaml.Node | None) -> dict[tuple, str]:
    """Path -> what was written, for every value YAML read otherwise than it looks: as a boolean
    (``no``, ``on``, ``yes``...), or as a string where a number with an exponent is written
    (``1e-09``: :func:`touchbench.core.yamlsafe.number_as_text`)."""
    return {path: node.value for path, node, _ in yaml_nodes(root)
            if isinstance(node, yaml.ScalarNode) and (
                node.tag == "tag:yaml.org,2002:bool"
                or (node.tag == "tag:yaml.org,2002:str" and node.style is None and number_as_text(node.value)))}


def _boolean_hint(loc: tuple, booleans: dict[tuple, str], msg: str = "") -> str:
    """For an issue at ``loc`` on (or just above) a value YAML read as a boolean: what was written,
    quoted; on (or above, such as a grid's point) a number YAML read as a string and the message
    shows: why, and how to write it."""
    for at, text in booleans.items():
        number = number_as_text(text)
        if number is not None:
            if at[:len(loc)] == loc and repr(text) in msg:
                return f" ({number})"
        elif at == loc or (loc and at[:-1] == loc):
            return (f" ({text!r} was read as a YAML boolean, {text.lower() in _TRUE}: quote it, \"{text}\", "
                    "where a name or text is meant)")
    return ""


_TRUE = {"y", "yes", "true", "on"}


def _loc_str(loc: tuple) -> str:
    s = ""
    for part in loc:
        if isinstance(part, int):
            s += f"[{part}]"
        else:
            s += ("." if s else "") + str(part)
    return s or "(top level)"


# ----------------------------------------------------------------- error mapping
def _make_error(path: Path | None, lines: dict[tuple, int], issues: list[tuple[tuple, str]],
                booleans: dict[tuple, str] | None = None) -> ProtocolError:
    where = str(path) if path is not None else "<protocol>"
    rows, out = [], []
    for loc, msg in issues:
        msg += _boolean_hint(loc, booleans or {}, msg)
        line = best_line(lines, loc) if loc else None
        loc_s = _loc_str(loc)
        rows.append((where, line, loc_s, msg))
        out.append(f"{where}{':' + str(line) if line else ''}: {loc_s}: {msg}")
    return ProtocolError("\n".join(out), rows)


def _model_fields_at(model: type[BaseModel], loc: tuple) -> list[str] | None:
    """Field names of the model reached by walking ``loc`` through annotations."""
    tp: Any = model
    for part in loc:
        tp = _unwrap(tp, part)
        if tp is None:
            return None
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return list(tp.model_fields)
    return None


def _unwrap(tp: Any, part: Any) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return _unwrap(args[0], part) if len(args) == 1 else None
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        f = tp.model_fields.get(str(part))
        return None if f is None else f.annotation
    if origin in (list, tuple) and isinstance(part, int):
        return typing.get_args(tp)[0]
    if origin is dict:
        return typing.get_args(tp)[1]
    return None


def _pydantic_issues(err: ValidationError, model: type[BaseModel], prefix: tuple = ()) -> list[tuple[tuple, str]]:
    issues = []
    for e in err.errors():
        loc = tuple(e["loc"])
        kind = e["type"]
        msg = e["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        at = (e.get("ctx") or {}).get("error")
        more = [(prefix + loc + m_loc, m_msg) for m_loc, m_msg in at.more] if isinstance(at, _ErrorAt) else []
        if isinstance(at, _ErrorAt):
            loc += at.loc
        if kind == "missing":
            msg = "missing required field"
        elif kind == "extra_forbidden":
            fields = _model_fields_at(model, loc[:-1]) or []
            msg = f"unknown field{did_you_mean(str(loc[-1]), fields)}"
            if fields:
                msg += f" (allowed: {', '.join(fields)})"
        elif kind not in ("value_error", "assertion_error"):
            value = e.get("input")
            if isinstance(value, (str, int, float, bool)) or value is None:
                msg = f"{msg}, got {value!r}"
        issues += [(prefix + loc, msg), *more]
    return issues
