"""What the five Gaus et al. (2015, section 3.2) feature sets share:
the per-dataset presets.

Section 3.2: "Parameters tuning is used to optimize their discriminative
power to the different recording settings used for the two dataset but not
between surfaces within the HAART dataset." So each set that the paper
tunes takes ``preset="haart"`` or ``preset="cost"`` (Tables 3 and 4 and
section 3.2.2), and every preset value can be overridden by an explicit
parameter (``None`` means "the preset's value").
"""

from __future__ import annotations

from typing import Any

from .base import FeatureInputError

GAUS_PAPER = "Gaus et al. 2015 (ICMI), section 3.2"


def resolve(owner: str, preset: str, table: dict[str, dict[str, Any]], key: str, explicit: Any) -> Any:
    """``explicit`` if given, else ``table[preset][key]``; unknown preset -> FeatureInputError."""
    if explicit is not None:
        return explicit
    if preset not in table:
        raise FeatureInputError(f"{owner}: unknown preset {preset!r} (known: {', '.join(sorted(table))})")
    return table[preset][key]
