"""Method labels fitted to a narrow terminal column, each still telling its row apart.

:func:`fit_labels` shortens a column of labels (a leaderboard's method names) to a width in three
steps, each only where the labels do not fit yet:

1. the start and the end that every label shares are left out (cut at a separator, so that no
   word is halved; :func:`shared_affixes`), said once above the table (:meth:`FittedLabels.heading`);
2. a label still too long is shortened around "…" (its start and its end kept, then other cuts
   around the part where it differs from its nearest labels), and a shortening is taken only when
   it *identifies* the label: no other label of the column reads as it (:func:`reads_as`);
3. a label no shortening identifies is numbered (``[1] sd+m…rf``), and only such labels are
   listed in a one-line legend under the table (:meth:`FittedLabels.legend`).

Two labels never show the same text.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from rich.cells import cell_len

__all__ = ["FittedLabels", "fit_labels", "reads_as", "shared_affixes"]

#: where a shared start or end may be cut (so that "touch-rhythm / " goes, never "touc")
SEPARATORS = frozenset(" /+-_,;:=()[]@.")
#: the shortest shared start or end worth leaving out (and saying so)
MIN_AFFIX = 3
ELLIPSIS = "…"


@dataclass
class FittedLabels:
    """A column of labels as a terminal of some width shows them."""

    #: per label given, the text shown (in the order given)
    shown: list[str]
    #: the start every label shares, left out ("" when none was)
    prefix: str = ""
    #: the end every label shares, left out ("" when none was)
    suffix: str = ""
    #: number -> full label, for each label replaced by a number (in the order of the rows)
    numbered: dict[str, str] = field(default_factory=dict)

    def heading(self, what: str = "method names") -> str | None:
        """The line above the table saying what the shown labels leave out (None: nothing)."""
        parts = ([f"the start “{self.prefix}”"] if self.prefix else []) + ([f"the end “{self.suffix}”"] if self.suffix else [])
        return f"{what[:1].upper()}{what[1:]} below leave out {' and '.join(parts)} that all share." if parts else None

    def legend(self) -> str | None:
        """One line naming each numbered label in full (None: no label was numbered)."""
        if not self.numbered:
            return None
        return "Numbered: " + "; ".join(f"{k} {v}" for k, v in self.numbered.items()) + "."


def _cut_prefix(labels: list[str]) -> str:
    """The start every one of ``labels`` shares, up to and with its last separator."""
    common = os.path.commonprefix(labels)
    if len(common) == min(len(x) for x in labels):  # one label is the whole shared start: keep a word of it
        common = common[:-1]
    cut = max((i for i, ch in enumerate(common) if ch in SEPARATORS), default=-1)
    return common[:cut + 1]


def shared_affixes(labels: list[str]) -> tuple[str, str]:
    """The start and the end that every one of ``labels`` (two or more different ones) shares, each
    cut at a separator so that no word is halved, each at least :data:`MIN_AFFIX` characters
    ("" otherwise); what is left of a label is never empty."""
    distinct = list(dict.fromkeys(labels))
    if len(distinct) < 2:
        return "", ""
    prefix = _cut_prefix(distinct)
    prefix = prefix if len(prefix) >= MIN_AFFIX else ""
    rests = [x[len(prefix):] for x in distinct]
    suffix = _cut_prefix([x[::-1] for x in rests])[::-1]
    suffix = suffix if len(suffix) >= MIN_AFFIX else ""
    if any(not x[:len(x) - len(suffix)].strip() for x in rests):
        suffix = ""
    return prefix, suffix


def reads_as(shown: str, label: str) -> bool:
    """Whether ``label`` could be the one ``shown`` stands for: equal to it, or, where ``shown``
    holds "…", made of its pieces in order with anything in place of each "…"."""
    pieces = shown.split(ELLIPSIS)
    if len(pieces) == 1:
        return shown == label
    head, *middle, tail = pieces
    if len(head) + len(tail) > len(label) or not label.startswith(head) or not label.endswith(tail):
        return False
    pos, end = len(head), len(label) - len(tail)
    for piece in middle:
        at = label.find(piece, pos, end)
        if at < 0:
            return False
        pos = at + len(piece)
    return True


def _fit(text: str, width: int) -> str:
    """The longest start of ``text`` in ``width`` terminal cells."""
    used = 0
    for i, ch in enumerate(text):
        used += cell_len(ch)
        if used > width:
            return text[:i]
    return text


def _fit_end(text: str, width: int) -> str:
    """The longest end of ``text`` in ``width`` terminal cells."""
    return _fit(text[::-1], width)[::-1]


def _first_difference(label: str, others: list[str]) -> int:
    """Where ``label`` first differs from the other label that shares the longest start with it."""
    return max((len(os.path.commonprefix([label, o])) for o in others), default=0)


def _candidates(label: str, others: list[str], width: int):
    """Shortenings of ``label`` in ``width`` cells, the most readable first: its start and end
    around "…" (the start the longer half, then each other split), then a piece from where it
    differs from its nearest label (from the separator before), with or without its end."""
    keep = width - 1
    splits = sorted(range(keep + 1), key=lambda k: (abs(k - (keep - keep // 2)), -k))
    for k in splits:
        yield _fit(label, k) + ELLIPSIS + _fit_end(label, keep - k)
    diff = min(_first_difference(label, others), len(label) - 1)
    starts = sorted({diff, max((i + 1 for i in range(diff) if label[i] in SEPARATORS), default=0)}, reverse=True)
    for start in (s for s in starts if s > 0):
        piece = label[start:]
        yield ELLIPSIS + _fit(piece, width - 2) + ELLIPSIS
        for k in range(width - 3, 0, -1):  # the piece, then the end
            yield ELLIPSIS + _fit(piece, k) + ELLIPSIS + _fit_end(label, width - 2 - k)


def _identifying(label: str, rivals: list[str], width: int, taken: set[str]) -> str | None:
    """The first shortening of ``label`` (:func:`_candidates`) that no label of ``rivals`` reads
    as and no other row shows; None when there is none."""
    for cand in _candidates(label, rivals, width):
        if (cand not in taken and cand != ELLIPSIS and reads_as(cand, label)
                and not any(reads_as(cand, r) for r in rivals)):
            return cand
    return None


def fit_labels(labels: list[str], width: int) -> FittedLabels:
    """``labels`` (a column's cells) each in at most ``width`` terminal cells, told apart
    (module docstring): as given where they all fit; else without their shared start and end,
    then each too long one shortened so that no other label reads as it, else numbered."""
    distinct = list(dict.fromkeys(labels))
    if all(cell_len(x) <= width for x in distinct):
        return FittedLabels(list(labels))
    prefix, suffix = shared_affixes(distinct)
    core = {x: x[len(prefix):len(x) - len(suffix)] for x in distinct}
    cores = list(core.values())
    shown: dict[str, str] = {x: c for x, c in core.items() if cell_len(c) <= width}
    taken = set(shown.values())
    numbered: dict[str, str] = {}
    for x in distinct:
        if x in shown:
            continue
        rivals = [c for c in cores if c != core[x]]
        short = _identifying(core[x], rivals, width, taken)
        if short is None:
            tag = f"[{len(numbered) + 1}]"
            numbered[tag] = x
            room = width - cell_len(tag) - 1
            short = f"{tag} {next(_candidates(core[x], [], room))}" if room >= 3 else tag
        shown[x] = short
        taken.add(short)
    return FittedLabels([shown[x] for x in labels], prefix, suffix, numbered)
