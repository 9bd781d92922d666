"""``stream-trade``: a stream evaluation's trade, accuracy against time to decision and against CPU per
decision, one point per method and decision rule (:mod:`touchbench.reports.stream_table`).

One row of two panels per method (the methods in the table's order), so that a method's rules are
compared where they can be told apart: each rule has one colour and one marker of its own, the same
in every panel (no two rules share the pair), named in one legend below the panels, outside every
axes; the default rule's point (the one ``touchbench stream`` decides with) is ringed and its legend
entry says ``(default)``. Each row's dashed line is answering idle at every frame of its streams.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import FIGURES, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["MARKERS", "draw", "plot_stream_trade", "rule_styles", "stream_trade_figure"]

#: one marker per rule, with the colours of ``tab10``: every (colour, marker) pair differs for up to
#: 110 rules (the colour cycles every 10, the marker every 11)
MARKERS = "os^Dv<>p*hX"
#: the height of one method's row of panels, inches
ROW_IN = 1.55


def rule_styles(rules: list[str]) -> dict[str, tuple[Any, str]]:
    """Each rule's (colour, marker), in the order given."""
    colours = pyplot().get_cmap("tab10")(np.arange(10))
    return {r: (tuple(colours[i % 10]), MARKERS[i % len(MARKERS)]) for i, r in enumerate(rules)}


def stream_trade_figure(lb: Leaderboard, size: str):
    """The figure (module docstring): per method, frame accuracy (the idle-only baseline dashed) against
    the median time from onset to the first correct decision, and against the median CPU time of one
    decision."""
    plt = pyplot()
    rows = lb.live
    methods = list(dict.fromkeys(rows["method"]))
    rules = list(dict.fromkeys(rows["rule"]))
    styles = rule_styles(rules)
    defaults = set(rows.loc[rows["default"].astype(bool), "rule"]) if "default" in rows else set()
    w = figure_width(size)
    ncol = 3 if w >= 6 else 2
    legend_in = 0.2 * (-(-len(rules) // ncol))
    fig, axes = plt.subplots(len(methods), 2, figsize=(w, 0.6 + ROW_IN * len(methods) + legend_in),
                             layout="constrained", sharey=True, sharex="col", squeeze=False)
    panels = (("time_to_decision_median_s", "median time to a correct decision (s)"),
              ("decision_cpu_ms", "CPU per decision (ms, one thread)"))
    for (left, right), method in zip(axes, methods):
        mine = rows[rows["method"] == method]
        baseline = 100 * float(np.nanmean(mine["idle_baseline"]))
        for ax, (col, xlabel) in zip((left, right), panels):
            for _, r in mine.iterrows():
                colour, marker = styles[r["rule"]]
                ax.plot([r[col]], [100 * r["frame_accuracy"]], ls="none", marker=marker, color=colour, ms=5,
                        mec="black" if r["rule"] in defaults else colour, mew=1.2 if r["rule"] in defaults else 0.5)
            ax.axhline(baseline, color="0.5", ls="--", lw=1)
            ax.grid(True, alpha=0.3)
            if ax in axes[-1]:
                ax.set_xlabel(wrap(xlabel, w / 2))
        left.set_ylabel("frame %")
        left.set_title(wrap(method, w / 2), loc="left", fontsize=8)
    axes[0][0].annotate("answering idle throughout", (0.02, 100 * float(np.nanmean(rows.loc[rows["method"] == methods[0],
                                                                                           "idle_baseline"]))),
                        xycoords=("axes fraction", "data"), va="bottom", fontsize=7, color="0.4")
    handles = [plt.Line2D([], [], ls="none", marker=styles[r][1], color=styles[r][0], ms=5,
                          mec="black" if r in defaults else styles[r][0]) for r in rules]
    labels = [f"{r} (default)" if r in defaults else r for r in rules]
    fig.legend(handles, labels, loc="outside lower center", ncol=ncol, frameon=False, fontsize=7,
               title="rule (ringed: the default)" if defaults else "rule")
    fig.suptitle(wrap(f"{lb.title}: accuracy against time and CPU", w), fontsize=9)
    return fig


def plot_stream_trade(lb: Leaderboard, base: Path, size: str, formats: tuple[str, ...]) -> list[Path]:
    """:func:`stream_trade_figure`, written in ``formats``."""
    return save(stream_trade_figure(lb, size), base, formats)


@FIGURES.register("stream-trade", description="a stream table's accuracy against time to decision and CPU",
                  order=6)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The trade plot of a stream evaluation's table (none for a table of captures)."""
    if lb.live is None or not len(lb.live):
        return []
    return plot_stream_trade(lb, base, options.size, options.formats)
