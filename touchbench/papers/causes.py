"""The cause column of REPORT.md: for each paper number, reproduced or, for a number outside
tolerance, its cause with the kind of knowledge behind it (the protocol's ``cause``, see
:class:`touchbench.protocols.expected.Cause`): measured (the command that isolates it and what it
gave), ruled out (the cause is open; what was excluded, each with its command or source and what
it gave) or unexplained (no cause known; a number without a cause in its protocol, and on a
synthetic scene the scene's data named). Ruled out and unexplained follow one rule
(:data:`touchbench.protocols.expected.KIND_RULE`, printed in the report): a candidate run on the
row itself and left outside tolerance is excluded; the cell lists the excluded candidates apart
from the others tried."""

from __future__ import annotations

from collections import Counter

from ..protocols.expected import CAUSE_KINDS, Cause, RuledOut, kind_by_rule

__all__ = ["KIND_LABELS", "KIND_SHORT", "cause_cell", "kind_counts"]

#: How the report names each kind of cause (the cause column's first word).
KIND_LABELS = {"measured": "measured", "ruled_out": "ruled out", "unexplained": "unexplained"}
#: Each kind in a few words, for the list of the differences.
KIND_SHORT = {"measured": "cause measured", "ruled_out": "cause open, candidates ruled out",
              "unexplained": "cause unexplained"}


def _tried(r: RuledOut, audit: dict[str, float]) -> str:
    where = f"`{r.command}`" if r.command is not None else r.source
    row = f"this row {r.row:g}; " if r.row is not None and f"{r.row:g}" not in r.gave else ""
    fresh = r.this_run(audit)
    this_run = f"; this report's own audit gave {fresh:.1f} %" if fresh is not None else ""
    return f"{r.tried} ({where}: {row}{r.gave}{this_run})"


def _text(kind: str, cause: Cause | None, scene: str | None, value: float, tolerance: float,
          audit: dict[str, float]) -> str:
    if cause is None:
        return f"synthetic data of scene {scene}" if scene else "no cause known"
    if kind == "measured":
        return f"{cause.text}; `{cause.command}` gave: {cause.output}"
    parts = []
    if kind == "ruled_out":
        parts.append("cause open" + (f", {cause.text}" if cause.text else ""))
    elif cause.text:
        parts.append(cause.text)
    if scene and kind == "unexplained":
        parts.append(f"synthetic data of scene {scene}")
    excluded = [r for r in cause.ruled_out if r.excludes(value, tolerance)]
    others = [r for r in cause.ruled_out if not r.excludes(value, tolerance)]
    if excluded:
        parts.append("ruled out: " + "; ".join(_tried(r, audit) for r in excluded))
    if others:
        parts.append(("also tried: " if excluded else "tried: ") + "; ".join(_tried(r, audit) for r in others))
    return "; ".join(parts) or "no cause known"


def cause_cell(within: bool | None, cause: Cause | None, scene: str | None, value: float,
               tolerance: float, audit: dict[str, float] | None = None) -> tuple[str | None, str]:
    """The kind (``None`` unless the number is outside tolerance; the rule's,
    :func:`touchbench.protocols.expected.kind_by_rule`) and the cause column's text of the paper
    number ``value`` (``tolerance`` its tolerance); ``scene`` is the scene's name where the data are
    synthetic; ``audit``: this report's leakage audit of the number's method, variant -> accuracy %
    (a candidate cited from an audit variant gets this run's figure beside it where they differ)."""
    if within is None:
        return None, "not run"
    if within:
        return None, f"reproduced on scene {scene}" if scene else "reproduced"
    kind = "unexplained" if cause is None else kind_by_rule(cause, value, tolerance)
    text = f"**{KIND_LABELS[kind]}:** {_text(kind, cause, scene, value, tolerance, audit or {})}"
    return kind, text.replace("|", "\\|")


def kind_counts(kinds: list[str | None]) -> Counter:
    """How many numbers outside tolerance have each kind of cause (every kind present, 0 if none)."""
    c = Counter({k: 0 for k in CAUSE_KINDS})
    c.update(k for k in kinds if k is not None)
    return c
