"""Protocols: the YAML schema (``schema``) and the evaluation schemes (``schemes``), imported on first
use of a name, so that finding and listing protocols (``library``) imports neither."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .schemes import SPLITTERS, Crop, Fold, SplitError, Splitter, make_splitter

__all__: list[str] = []  # the schemes' names are documented in touchbench.protocols.schemes
_SCHEMES = ("SPLITTERS", "Crop", "Fold", "SplitError", "Splitter", "make_splitter")


def __getattr__(name: str) -> Any:
    if name in _SCHEMES:
        return getattr(importlib.import_module(".schemes", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_SCHEMES])
