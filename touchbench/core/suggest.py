"""The one "did you mean" helper used by every message that names an unknown word."""

from __future__ import annotations

import difflib
from typing import Iterable

__all__ = ["did_you_mean"]


def did_you_mean(word: object, choices: Iterable[str], cutoff: float = 0.5, quote: bool = True) -> str:
    """``"; did you mean 'a', 'b'?"`` for the (up to 3) nearest choices, or ``""``."""
    close = difflib.get_close_matches(str(word), list(choices), n=3, cutoff=cutoff)
    shown = [repr(c) if quote else str(c) for c in close]
    return f"; did you mean {', '.join(shown)}?" if close else ""
