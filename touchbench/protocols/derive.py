"""Protocols made from protocols: a study changed into another, as plain data, validated again.

The leakage audit's variants (:mod:`touchbench.engine.audit`) and the paper
reproduction's profiles (:mod:`touchbench.papers.profiles`) are functions
from a protocol to a protocol. They change :func:`protocol_data` -- the
validated protocol as the data of a protocol file, never the file's text --
and :func:`derive` validates the result like any protocol file, its text
the YAML of that data (with a header saying how it was made), so it can be
written beside its results and run again as is. Reading a protocol's own
data back gives the same protocol (the same content, expected numbers,
design and audit blocks): a test holds every shipped protocol to it.
"""

from __future__ import annotations

from typing import Any

import yaml

from .loading import parse_protocol
from .schema import Protocol

__all__ = ["derive", "protocol_data"]


def protocol_data(protocol: Protocol) -> dict[str, Any]:
    """The validated protocol as the data of a protocol file (defaults left out; a protocol of
    ``methods:`` alone without the empty ``features`` x ``classifiers``)."""
    data = protocol.model_dump(mode="json", exclude_defaults=True)
    if protocol.methods and not data.get("features"):
        data.pop("features", None)
        data.pop("classifiers", None)
    return data


def derive(protocol: Protocol, data: dict[str, Any], header: str = "") -> Protocol:
    """The protocol ``data`` describes, validated as a file beside ``protocol``'s (relative dataset
    paths resolve the same way); ``header`` (comment lines) opens its text."""
    text = header + yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    return parse_protocol(text, protocol.path)
