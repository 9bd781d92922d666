"""Reading a scene file: :func:`load_spec` (a file, with overrides) and :func:`parse_spec` (its
mapping, validated by :class:`touchbench.scenes.spec.SceneSpec`, then its size checked by
:func:`touchbench.scenes.size.size_problem` before anything is made). Every error is one
:class:`DataError` naming the file, the field and that field's line (a value that an override
gave, not the file, is said to be so)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from ..core.errors import DataError
from ..core.yamlsafe import best_line, load_bounded, node_lines, safe_load
from .size import size_problem
from .spec import SceneSpec

__all__ = ["deep_merge", "load_spec", "parse_spec", "read_yaml"]


def _format_error(e: ValidationError) -> str:
    parts = []
    for err in e.errors():
        loc = ".".join(str(x) for x in err["loc"] if not str(x).startswith("function-after"))
        msg = err["msg"].removeprefix("Value error, ")
        if err.get("type") in ("literal_error", "enum") and isinstance(err.get("input"), (str, int, float)):
            msg += f", got {err['input']!r}"
        parts.append(f"{loc}: {msg}" if loc else msg)
    return "; ".join(parts)


def _error_path(err: dict[str, Any]) -> tuple:
    """The field a pydantic error is about: its location, or (a model's own check) the dotted
    path its message starts with, below that location or from the top."""
    loc = tuple(x for x in err["loc"] if not str(x).startswith("function-after"))
    m = re.match(r"([A-Za-z_][\w-]*(?:\.[\w-]+)*): ", err["msg"].removeprefix("Value error, "))
    named = tuple(m.group(1).split(".")) if m else ()
    return loc + named, named


def _line_in(text: str | None, paths: tuple[tuple, ...]) -> int | None:
    """The line of the first of ``paths`` the YAML ``text`` writes, else of the field nearest above
    the first."""
    if not text or not paths or not paths[0]:
        return None
    try:
        lines = node_lines(load_bounded(text)[1])
    except yaml.YAMLError:
        return None
    for path in paths:
        if path and path in lines:
            return lines[path]
    return best_line(lines, paths[0])


def _overridden(path: tuple, overrides: dict[str, Any] | None) -> bool:
    """Whether ``overrides`` (nested like the scene) set the field at ``path`` or one above it."""
    node: Any = overrides
    for key in path:
        if not isinstance(node, dict) or key not in node:
            return False
        node = node[key]
    return bool(path)


def _refusal(message: str, source: str | Path, text: str | None, paths: tuple[tuple, ...],
             overrides: dict[str, Any] | None) -> DataError:
    """A :class:`DataError` about the field at ``paths[0]``: at its line of the file, or said to be
    an override's value."""
    if overrides and any(_overridden(p[:i], overrides) for p in paths for i in range(1, len(p) + 1)):
        return DataError(f"{message} (the value given as an override)", source)
    return DataError(message, source, _line_in(text, paths))


def deep_merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in over.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = v
    return out


def parse_spec(raw: dict[str, Any], source: str | Path = "<scene>", text: str | None = None,
               overrides: dict[str, Any] | None = None) -> SceneSpec:
    """Validate a scene dict; errors become a :class:`DataError` naming the file, the field and
    its line in ``text`` (or that ``overrides``, merged into ``raw``, gave its value). A scene
    whose captures would not fit in memory (:func:`touchbench.scenes.size.size_problem`) is
    refused here, before anything is made."""
    if not isinstance(raw, dict):
        raise DataError("a scene file holds a mapping (name, description, effects, sensor, ...)", source)
    try:
        spec = SceneSpec.model_validate(raw)
    except ValidationError as e:
        full, named = _error_path(e.errors()[0])
        raise _refusal(f"invalid scene: {_format_error(e)}", source, text, (full, named), overrides) from None
    problem = size_problem(spec)
    if problem is not None:
        field, message = problem
        raise _refusal(f"invalid scene: {field}: {message}", source, text, (tuple(field.split(".")),), overrides)
    return spec


def read_yaml(path: str | Path) -> tuple[dict[str, Any], str]:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise DataError(f"cannot read scene file ({e.strerror})", path) from None
    try:
        raw = safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        raise DataError(f"invalid YAML ({getattr(e, 'problem', e)})", path, None if mark is None else mark.line + 1) from None
    return raw, text


def load_spec(path: str | Path, overrides: dict[str, Any] | None = None) -> SceneSpec:
    raw, text = read_yaml(path)
    if overrides:
        if not isinstance(raw, dict):
            raise DataError("a scene file holds a mapping", path)
        raw = deep_merge(raw, overrides)
    return parse_spec(raw, path, text, overrides)
