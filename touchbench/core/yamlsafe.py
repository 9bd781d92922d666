"""Bounded YAML: user files read with limits, duplicate keys refused.

A YAML file of a few hundred bytes can stand for billions of nodes through
nested aliases ("billion laughs"): PyYAML builds them as shared objects,
but anything that walks the document (line maps, validation, copies)
follows every alias. :class:`BoundedLoader` is PyYAML's ``SafeLoader``
with its own hooks:

- the composer counts aliases (at most :data:`MAX_ALIASES`), the nodes the
  document stands for with every alias expanded (at most
  :data:`MAX_NODES`, counted once per node with a memo, so counting is
  linear in the file) and the nesting depth (at most :data:`MAX_DEPTH`);
  an alias inside the node it names (a recursive document) is refused;
- the constructor refuses a key given twice in one mapping (YAML merge
  keys ``<<`` still fill the keys a mapping does not give);
- :func:`load_bounded` refuses text longer than :data:`MAX_BYTES` before
  parsing.

Every refusal is a :class:`yaml.MarkedYAMLError` whose ``problem_mark`` is
the line it is about; :func:`yaml_problem` turns one into ``line, message``.
:func:`node_lines` maps every field of a composed document to its line, and
:func:`best_line` finds the line of a field (or of the nearest field above it
that the file writes). :func:`number_as_text` says why a number written with an exponent
but no dot or no sign (``1e-09``, ``1.0e300``) is a string: YAML 1.1 reads it so.
"""

from __future__ import annotations

import re
from typing import Any, Iterator

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

__all__ = ["MAX_ALIASES", "MAX_BYTES", "MAX_DEPTH", "MAX_NODES", "BoundedLoader", "YamlLimitError", "best_line", "load_bounded",
           "node_lines", "number_as_text", "safe_load", "yaml_nodes", "yaml_problem"]

MAX_BYTES = 256 * 1024  # the longest shipped protocol is under 10 kB
MAX_ALIASES = 100
MAX_NODES = 50_000  # with every alias expanded; a paper protocol has about 1,000
MAX_DEPTH = 32

_MERGE = "tag:yaml.org,2002:merge"


class YamlLimitError(yaml.MarkedYAMLError):
    """A document refused by a limit or a duplicate key (not a syntax error)."""

    def __init__(self, message: str, mark: Any = None):
        super().__init__(problem=message, problem_mark=mark)


class BoundedLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` with bounded composition and duplicate keys refused (see the module)."""

    def __init__(self, stream: Any):
        super().__init__(stream)
        self._n_aliases = 0
        self._depth = 0
        self._sizes: dict[int, int] = {}  # id(node) -> nodes it stands for, aliases expanded

    def compose_document(self) -> Node | None:
        node = super().compose_document()
        self._sizes.clear()
        return node

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            self._n_aliases += 1
            if self._n_aliases > MAX_ALIASES:
                raise YamlLimitError(f"more than {MAX_ALIASES} aliases (*name): write the values out", event.start_mark)
            target = self.anchors.get(event.anchor)
            if target is not None and id(target) not in self._sizes:  # still being composed
                raise YamlLimitError(f"the alias *{event.anchor} is inside the node it names (a recursive document)",
                                     event.start_mark)
            node = super().compose_node(parent, index)
            self._count(node, event.start_mark)
            return node
        event = self.peek_event()
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise YamlLimitError(f"nested more than {MAX_DEPTH} levels deep", event.start_mark)
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        if isinstance(node, ScalarNode):
            size = 1
        elif isinstance(node, SequenceNode):
            size = 1 + sum(self._sizes.get(id(v), 1) for v in node.value)
        elif isinstance(node, MappingNode):
            size = 1 + sum(self._sizes.get(id(k), 1) + self._sizes.get(id(v), 1) for k, v in node.value)
        else:  # pragma: no cover - PyYAML composes only these three
            size = 1
        self._sizes[id(node)] = size
        self._count(node, event.start_mark)
        return node

    def _count(self, node: Node, mark: Any) -> None:
        if self._sizes.get(id(node), 1) > MAX_NODES:
            raise YamlLimitError(f"the document stands for more than {MAX_NODES} values once its aliases are "
                                 "expanded: write a smaller one", mark)

    def construct_mapping(self, node: Any, deep: bool = False) -> dict:
        if isinstance(node, MappingNode):
            seen: dict[Any, int] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.get(key)
                except TypeError:  # unhashable: PyYAML refuses it below
                    continue
                if first is not None:
                    raise YamlLimitError(f"the key {key!r} is given twice in this mapping (first on line {first}): "
                                         "give each key once", key_node.start_mark)
                seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)


def load_bounded(text: str) -> tuple[Any, Node | None]:
    """The document in ``text`` and its composed root node (for line numbers), within the limits."""
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_BYTES:
        raise YamlLimitError(f"the file has {size} bytes: at most {MAX_BYTES} are read")
    loader = BoundedLoader(text)
    try:
        root = loader.get_single_node()
        data = loader.construct_document(root) if root is not None else None
    except (ValueError, TypeError, OverflowError) as e:  # a scalar Python refuses (an int of 5,000 digits)
        raise YamlLimitError(f"cannot read a value: {e}") from None
    finally:
        loader.dispose()
    return data, root


def safe_load(text: str) -> Any:
    """``yaml.safe_load`` within the limits (every YAML touchbench reads goes through here)."""
    return load_bounded(text)[0]


def yaml_problem(err: yaml.YAMLError) -> tuple[int | None, str]:
    """``(line, message)`` of a YAML error: the 1-based line it names (None if none) and its problem."""
    mark = getattr(err, "problem_mark", None) or getattr(err, "context_mark", None)
    line = mark.line + 1 if mark is not None else None
    problem = getattr(err, "problem", None) or str(err)
    if not isinstance(err, YamlLimitError):
        problem = f"invalid YAML: {problem}"
    return line, problem


def yaml_nodes(root: Node | None) -> Iterator[tuple[tuple, Node, int]]:
    """(path, node, 1-based line) of every node of a composed YAML document, a mapping's keys by their
    key's line. The document comes from the bounded loader: its aliases, once expanded, stand for a
    bounded number of nodes, and none is recursive, so this walk is bounded too."""
    stack = [((), root, root.start_mark.line + 1)] if root is not None else []
    while stack:
        path, node, line = stack.pop()
        yield path, node, line
        if isinstance(node, MappingNode):
            stack += [(path + (str(k.value),), v, k.start_mark.line + 1) for k, v in reversed(node.value)]
        elif isinstance(node, SequenceNode):
            stack += [(path + (i,), v, v.start_mark.line + 1) for i, v in reversed(list(enumerate(node.value)))]


def node_lines(root: Node | None) -> dict[tuple, int]:
    """Path (tuple of keys / indices) -> 1-based line of every node of a composed YAML document."""
    return {path: line for path, _, line in yaml_nodes(root)}


def best_line(lines: dict[tuple, int], loc: tuple) -> int | None:
    """The line of field ``loc`` in a document's :func:`node_lines`, or of the deepest field above it
    that the document writes (a value left to its default is named by its parent's line)."""
    best = lines.get((), None)
    prefix: tuple = ()
    for part in loc:
        cand = prefix + (part if isinstance(part, int) else str(part),)
        if cand in lines:
            prefix = cand
            best = lines[cand]
        else:
            break
    return best


#: a number with an exponent that YAML 1.1 reads as a string: no dot in the mantissa, or no sign
#: in the exponent (``1e-09``, ``1.0e300``, ``5E3``)
_EXPONENT = re.compile(r"([-+]?)(\d+)(?:\.(\d*))?[eE]([-+]?)(\d+)")


def number_as_text(value: Any) -> str | None:
    """Why ``value``, a string written as a number with an exponent, is not a number, and how to
    write it so that YAML reads a number; None for any other value."""
    m = _EXPONENT.fullmatch(value.strip()) if isinstance(value, str) else None
    if m is None:
        return None
    sign, whole, frac, exp_sign, exp = m.groups()
    fixed = f"{sign}{whole}.{frac or '0'}e{exp_sign or '+'}{exp}"
    return (f"YAML read {value!r} as a string, not a number: YAML 1.1 reads an exponent as a number only "
            f"after a dot and with a sign; write {fixed}")
