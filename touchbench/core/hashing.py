"""Canonical JSON for hashing and for parameter columns."""

from __future__ import annotations

import json
from typing import Any

__all__ = ["canonical_json"]


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no spaces, for hashing and for the ``params`` columns."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
