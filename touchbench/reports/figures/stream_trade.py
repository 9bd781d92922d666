"""``stream-trade``: a stream evaluation's trade, accuracy against time to decision and against CPU per
decision, one point per method and decision rule (:mod:`touchbench.reports.stream_table`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import FIGURES, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["draw", "plot_stream_trade"]


def plot_stream_trade(lb: Leaderboard, base: Path, size: str, formats: tuple[str, ...]) -> list[Path]:
    """Two panels: frame accuracy (the idle-only baseline dashed) against the median time from onset
    to the first correct decision, and against the median CPU time of one decision."""
    plt = pyplot()
    rows = lb.live
    w = figure_width(size)
    fig, axes = plt.subplots(1, 2, figsize=(w, 3.2), layout="constrained", sharey=True)
    panels = (("time_to_decision_median_s", "median time to a correct decision (s)"),
              ("decision_cpu_ms", "CPU per decision (ms, one thread)"))
    for ax, (col, xlabel) in zip(axes, panels):
        for i, r in rows.iterrows():
            ax.scatter(r[col], 100 * r["frame_accuracy"], marker="os^Dv<>p*h"[i % 10], s=28,
                       label=f"{r['method']} · {r['rule']}")
        ax.axhline(100 * float(np.nanmean(rows["idle_baseline"])), color="0.5", ls="--", lw=1)
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("frame accuracy (%)")
    axes[0].annotate("answering idle throughout", (0.02, 100 * float(np.nanmean(rows["idle_baseline"]))),
                     xycoords=("axes fraction", "data"), va="bottom", fontsize=7, color="0.4")
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2, frameon=False, fontsize=7)
    fig.suptitle(wrap(f"{lb.title}: accuracy against time and CPU", w), fontsize=9)
    return save(fig, base, formats)


@FIGURES.register("stream-trade", description="a stream table's accuracy against time to decision and CPU",
                  order=6)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The trade plot of a stream evaluation's table (none for a table of captures)."""
    if lb.live is None or not len(lb.live):
        return []
    return plot_stream_trade(lb, base, options.size, options.formats)
