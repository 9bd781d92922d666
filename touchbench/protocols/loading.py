"""Reading a protocol: :func:`load_protocol` (a file) and :func:`parse_protocol` (its text),
validated in passes (see :mod:`touchbench.protocols.schema`); every error names the file, line
and field."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from ..core.yamlsafe import MAX_BYTES, load_bounded, node_lines, yaml_problem
from .checks import (
    _classifier_issues,
    _design_issues,
    _duplicate_issues,
    _evaluation_issues,
    _expected_issues,
    _feature_issues,
    _shape_issues,
    _size_issues,
)
from .errors import ProtocolError, _boolean_map, _make_error, _pydantic_issues
from .schema import Protocol

__all__ = ["load_protocol", "parse_protocol"]


def parse_protocol(text: str, path: str | Path | None = None, *, deep: bool = True) -> Protocol:
    """Validate protocol ``text``; ``path`` names it in errors.

    ``deep=False`` skips the checks that build classifiers (for listing).
    """
    p = Path(path) if path is not None else None
    data, root = _load_mapping(text, str(p) if p is not None else "<protocol>")
    lines, booleans = node_lines(root), _boolean_map(root)
    data = copy.deepcopy(data)
    if "name" not in data and p is not None:
        data["name"] = p.stem.replace(".yaml", "")
    try:
        proto = Protocol.model_validate(data)
    except ValidationError as e:
        raise _make_error(p, lines, _pydantic_issues(e, Protocol), booleans) from None
    proto._path = p
    proto._text = text
    proto._lines, proto._booleans = lines, booleans
    issues = _size_issues(proto)  # before anything expands the grids
    if issues:
        raise _make_error(p, lines, issues, booleans)
    names = [ev.name for ev in proto.evaluations]
    issues = [(("evaluations", i, "name"), f"evaluation {n!r} is named twice") for i, n in enumerate(names)
              if n in names[:i]]
    try:
        subs = proto.evaluation_protocols()
    except ValidationError as e:
        raise _make_error(p, lines, _pydantic_issues(e, Protocol), booleans) from None
    issues += _shape_issues(proto)
    issues += _feature_issues(proto)
    if deep:
        issues += _classifier_issues(proto)
    issues += _evaluation_issues(proto, subs, clean_so_far=not issues)
    if not issues:
        issues += _duplicate_issues(proto) + _design_issues(proto)
    if not issues:
        issues += _expected_issues(proto)
    if issues:
        raise _make_error(p, lines, list(dict.fromkeys(issues)), booleans)
    return proto


def _load_mapping(text: str, where: str) -> tuple[dict, Any]:
    """The YAML mapping of protocol ``text`` and its node tree; anything else is a :class:`ProtocolError`."""
    try:
        data, root = load_bounded(text)
    except yaml.YAMLError as e:
        line, problem = yaml_problem(e)
        raise ProtocolError(f"{where}{'' if line is None else f':{line}'}: {problem}") from None
    if data is None:
        raise ProtocolError(f"{where}: the protocol is empty")
    if not isinstance(data, dict):
        raise ProtocolError(f"{where}:1: a protocol is a mapping of fields (name, dataset, scheme, ...), got {type(data).__name__}")
    return data, root


def load_protocol(path: str | Path, *, deep: bool = True) -> Protocol:
    """Read and validate a protocol file (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise ProtocolError(f"{p}: no such protocol file")
    size = p.stat().st_size
    if size > MAX_BYTES:  # refused before reading it
        raise ProtocolError(f"{p}: the file has {size} bytes: a protocol has at most {MAX_BYTES}")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ProtocolError(f"{p}: not a UTF-8 text file") from None
    return parse_protocol(text, p, deep=deep)
