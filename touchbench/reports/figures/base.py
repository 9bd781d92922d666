"""What the figure kinds share: the registry ``FIGURES``, the calling convention of its entries,
:func:`plot_table` (every kind for one table), file names, print sizes and fonts, label placement.

A figure kind is one module of this package registering one function with
``@FIGURES.register(NAME, description="one line", order=N)``:
``draw(rs, lb, base, options) -> list[Path]`` draws the kind's figures of
the table ``lb`` (results ``rs``) and writes each through :func:`save`;
``base`` is the figure's path without suffix, ``<out>/<table stem>-<kind>``
(the stem: the results folder's name, :func:`figure_stem`),
and a kind drawing several figures (``confusion``: one per method) names
them ``base-<name>``. It returns the files written, none when the kind does
not apply to the table. ``options`` (:class:`FigureOptions`) carries what
the command line or the caller asked for: print size, file formats and the
inputs some kinds take (``references`` for ``pareto``, ``methods`` for
``confusion``). ``order`` places the kind's figures among a table's (the
HTML report, ``plot``'s output).

Figures are drawn with matplotlib (Agg backend), paper-ready: each written
as PDF, SVG and 300-dpi PNG (``FORMATS``), at a column or a text width
(``SIZES``: 3.5 and 7 inches) with every font at least ``MIN_FONT_PT``
(7 pt) at that size. Titles come from the dataset, scheme and method names,
file names from the results folder's and the methods' (never a hash);
names that would collide get ``-2``, ``-3``...
"""

from __future__ import annotations

import math
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from ...core.registry import Entry, Registry
from ..labels import owns_input

if TYPE_CHECKING:
    from ..leaderboard import Leaderboard
    from ..results import ResultSet

__all__ = ["FIGURES", "FORMATS", "MIN_FONT_PT", "SIZES", "FigureOptions", "figure_stem", "figure_width", "has_predictions",
           "kinds_in_order", "label_offsets", "plot_table", "pyplot", "save", "short_label", "slug", "unique_stem", "wrap"]

#: figure widths in inches: one column of a two-column paper, the text width
SIZES = {"column": 3.5, "text": 7.0}
FORMATS = ("pdf", "svg", "png")
MIN_FONT_PT = 7.0
PNG_DPI = 300


@dataclass(frozen=True)
class FigureOptions:
    """What a figure kind is asked for besides the table: ``size`` (a key of ``SIZES``), ``formats``
    (of ``FORMATS``), ``references`` ((label, accuracy in %) pairs drawn as lines by ``pareto``) and
    ``methods`` (method ids for ``confusion``; None: the table's best)."""

    size: str = "text"
    formats: tuple[str, ...] = FORMATS
    references: tuple[tuple[str, float], ...] = ()
    methods: tuple[str, ...] | None = None


#: an entry: draws a kind's figures of one table (see the module docstring)
Draw = Callable[["ResultSet", "Leaderboard", Path, FigureOptions], "list[Path]"]

# Filled by every module of touchbench.reports.figures (imported on first use of the registry).
FIGURES: Registry[Draw] = Registry("figure kind", package="touchbench.reports.figures")


def kinds_in_order() -> list[Entry[Draw]]:
    """The registered kinds in the order their figures come (their ``order`` tag, then name)."""
    return sorted(FIGURES.entries(), key=lambda e: (e.tags.get("order", math.inf), e.name))


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend with touchbench's rcParams (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # text stays text in SVG (searchable, smaller); fixed hash salt: the same plot gives the same file;
    # every font at least MIN_FONT_PT at print size (figures are drawn at their print width)
    plt.rcParams.update({
        "svg.hashsalt": "touchbench", "svg.fonttype": "none", "pdf.fonttype": 42,
        "font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "figure.titlesize": 8,
        "xtick.labelsize": MIN_FONT_PT, "ytick.labelsize": MIN_FONT_PT, "legend.fontsize": MIN_FONT_PT,
        "legend.title_fontsize": MIN_FONT_PT,
    })
    return plt


def figure_width(size: str) -> float:
    """The print width in inches of a size of ``SIZES``."""
    if size not in SIZES:
        raise ValueError(f"unknown figure size {size!r} (known: {', '.join(SIZES)})")
    return SIZES[size]


def wrap(text: str, width_in: float) -> str:
    """``text`` wrapped to the figure's width (about 15 characters per inch at 8 pt)."""
    return "\n".join(textwrap.fill(line, max(20, int(width_in * 15))) for line in text.split("\n"))


def clean(text: str) -> str:
    """``text`` as a part of a file name: lower case, runs of other characters as ``-``."""
    return re.sub(r"[^A-Za-z0-9._+-]+", "-", text).strip("-.").lower()


def slug(lb: Leaderboard) -> str:
    """A file stem from the table's dataset (a file's name without its suffix), scheme and target
    (and ``adapted`` for the table of methods adapted to the test sessions)."""
    dataset = Path(lb.dataset).stem if lb.dataset.endswith((".parquet", ".csv", ".gz")) else lb.dataset
    parts = [dataset, lb.scheme] + ([f"target-{lb.target}"] if lb.target != "gesture" else [])
    parts += [lb.variant] if getattr(lb, "variant", "") else []
    parts += ["adapted"] if getattr(lb, "adaptation", "") else []
    return clean("-".join(parts))[:80] or "table"


def figure_stem(lb: Leaderboard) -> str:
    """A figure's file stem for the table: the results folder it comes from (``lb.name``:
    ``stream-skin``, ``touch-all-loso``), with the table's target, variant and ``adapted`` where
    they apply; :func:`slug` when the table does not say its folder. Short and stable: never built
    from a scheme's parameters."""
    if not getattr(lb, "name", ""):
        return slug(lb)
    parts = [lb.name] + ([f"target-{lb.target}"] if lb.target != "gesture" else [])
    parts += [lb.variant] if getattr(lb, "variant", "") else []
    parts += ["adapted"] if getattr(lb, "adaptation", "") else []
    return clean("-".join(parts))[:80] or "table"


def unique_stem(stem: str, taken: set[str]) -> str:
    """``stem``, or ``stem-2``, ``stem-3``... the first not in ``taken`` (which it joins)."""
    out, k = stem, 1
    while out in taken:
        k += 1
        out = f"{stem}-{k}"
    taken.add(out)
    return out


def save(fig, base: Path, formats: tuple[str, ...] = FORMATS, tight: bool = False) -> list[Path]:
    """``base``.pdf/.svg/.png (``base`` may hold dots: the extension is appended, never substituted);
    ``tight``: trimmed to what is drawn (a figure drawn by another library, not laid out by us)."""
    plt = pyplot()
    base.parent.mkdir(parents=True, exist_ok=True)
    out = []
    meta = {"svg": {"Date": None}, "pdf": {"CreationDate": None, "ModDate": None}, "png": {"Software": None}}
    for ext in formats:
        if ext not in meta:
            raise ValueError(f"unknown figure format {ext!r} (known: {', '.join(FORMATS)})")
        p = base.parent / f"{base.name}.{ext}"
        # constrained layout: no bbox_inches="tight" (a second draw) unless asked
        fig.savefig(p, dpi=PNG_DPI, metadata=meta[ext], **({"bbox_inches": "tight", "pad_inches": 0.05} if tight else {}))
        out.append(p)
    plt.close(fig)
    return out


def short_label(r: Any, width: int = 28, with_features: bool = True) -> str:
    """A leaderboard row as ``features/classifier`` (or the classifier alone: asked for, or a method
    that brings its own input), cut to ``width`` characters."""
    lab = f"{r['features']}/{r['classifier']}" if with_features and not owns_input(r) else str(r["classifier"])
    return lab if len(lab) <= width else lab[: width - 1] + "…"


#: a label's height at fontsize 7, in points (a generous estimate)
LABEL_H = 8.5
#: where a label goes (points from its point) when nothing is in its way, right of its point
LABEL_OFFSET = (4, 3)


def label_offsets(points_pt: np.ndarray, widths_pt: np.ndarray, taken: Sequence[tuple[float, float, float, float]] = (),
                  bounds: tuple[float, float, float, float] | None = None,
                  heights_pt: np.ndarray | None = None) -> list[tuple[float, float]]:
    """Offsets (points) for labels at ``points_pt`` (N, 2 display points, top to bottom) so that their
    boxes never overlap one another nor a box of ``taken`` (other text already drawn, in the same points).

    Each label goes at ``LABEL_OFFSET``, right of its point, or as far left of it when its box
    (``widths_pt`` wide, ``heights_pt`` high, ``LABEL_H`` when not given) would pass the right edge of
    ``bounds`` (x0, y0, x1, y1: the panel, when given); a label whose box would overlap a box already
    placed moves down below it, 1 point apart (:func:`free_height`). Labels given top to bottom keep
    that order wherever they meet, so the lines to moved labels do not cross.
    """
    placed: list[tuple[float, float, float, float]] = [tuple(map(float, b)) for b in taken]
    heights = np.full(len(widths_pt), LABEL_H) if heights_pt is None else np.asarray(heights_pt, dtype=float)
    out = []
    for (x, y), w, h in zip(np.asarray(points_pt, dtype=float), np.asarray(widths_pt, dtype=float), heights):
        dx, dy = LABEL_OFFSET
        if bounds is not None and x + dx + w > bounds[2]:
            dx = -int(math.ceil(w)) - dx
        bottom = free_height(x + dx, w, h, y + dy, placed)
        placed.append((x + dx, bottom, x + dx + w, bottom + h))
        out.append((dx, dy) if bottom == y + dy else (dx, bottom - y))
    return out


def free_height(x0: float, w: float, h: float, y: float, placed: Sequence[tuple[float, float, float, float]],
                gap: float = 1.0) -> float:
    """The highest bottom, at most ``y``, of a box from ``x0`` to ``x0 + w`` and ``h`` high that overlaps
    none of ``placed``: ``y`` itself, or ``gap`` below a placed box in its columns."""
    cols = [b for b in placed if b[0] < x0 + w and x0 < b[2]]
    tries = sorted({y} | {b[1] - h - gap for b in cols if b[1] - h - gap < y}, reverse=True)
    return next(c for c in tries if not any(c < b[3] and b[1] < c + h for b in cols))


def text_size(fig, text: str, fontsize: float = MIN_FONT_PT) -> tuple[float, float]:
    """Width and height (points) of ``text`` as ``fig``'s renderer draws it."""
    t = fig.text(0, 0, text, fontsize=fontsize)
    box = t.get_window_extent(fig.canvas.get_renderer())
    t.remove()
    return box.width * 72.0 / fig.dpi, box.height * 72.0 / fig.dpi


def overlap(a: Sequence[float], b: Sequence[float]) -> float:
    """Area shared by two boxes (x0, y0, x1, y1)."""
    return max(0.0, min(a[2], b[2]) - max(a[0], b[0])) * max(0.0, min(a[3], b[3]) - max(a[1], b[1]))


def has_predictions(rs: ResultSet, lb: Leaderboard) -> bool:
    """Whether the results hold predictions of the table (what confusion matrices and per-subject
    accuracy need)."""
    return rs.predictions is not None and bool((rs.predictions["table_key"] == lb.key).any())


def plot_table(rs: ResultSet, lb: Leaderboard, out_dir: Path, kinds: Sequence[str] | None = None,
               methods: list[str] | None = None, references: list[tuple[str, float]] | None = None,
               name: str | None = None, *, size: str = "text", formats: tuple[str, ...] = FORMATS,
               taken: set[str] | None = None) -> dict[str, list[Path]]:
    """Every applicable figure of one table into ``out_dir``; ``{name: [pdf, svg, png]}``.

    ``kinds``: names of ``FIGURES`` (default: every kind), drawn in the
    kinds' order. ``references`` go to ``pareto`` (reference accuracies in
    %). Files are named ``<name>-<kind>`` (``name`` defaults to
    :func:`figure_stem`: the results folder's name), a kind drawing
    several figures ``<name>-<kind>-<figure>`` (confusion matrices
    ``<name>-confusion-<features>-<classifier>``); the keys of the result
    are these names without ``<name>-``. ``taken`` (shared over the tables
    of one call) makes names unique with ``-2``, ``-3``... A stable
    ``name`` gives stable file names, e.g. for figures a document links to.

    Confusion matrices are drawn for ``methods`` (ids), by default the best
    method of the table. A kind that does not apply (``frames`` outside an
    ``early`` scheme, ``confusion`` without predictions, ``cd`` with fewer
    than two methods or folds) draws nothing.
    """
    wanted = None if kinds is None else {FIGURES.entry(k).name for k in kinds}  # an unknown name is refused
    options = FigureOptions(size=size, formats=tuple(formats), references=tuple(references or ()),
                            methods=None if methods is None else tuple(methods))
    taken = set() if taken is None else taken
    s = unique_stem(clean(name) if name else figure_stem(lb), taken)
    made: dict[str, list[Path]] = {}
    for entry in kinds_in_order():
        if wanted is None or entry.name in wanted:
            for path in entry.obj(rs, lb, Path(out_dir) / f"{s}-{entry.name}", options):
                made.setdefault(path.name[len(s) + 1: -len(path.suffix)], []).append(path)
    return made
