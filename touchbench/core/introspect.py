"""Small introspection helpers: does a callable take a given parameter?"""

from __future__ import annotations

import inspect
from typing import Any

__all__ = ["accepts"]


def accepts(fn: Any, name: str) -> bool:
    """Whether ``fn`` (a function, class or bound method) takes a parameter ``name``."""
    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False
