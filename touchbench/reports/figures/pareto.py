"""``pareto``: accuracy (mean over folds, 95 % interval as error bar) against the three measured
costs -- latency per capture (the CPU time of labelling it; wall-clock time for results without one),
fit time per fold and feature extraction time per capture -- with the accuracy / latency Pareto front
drawn as a step line (per machine when several machines measured)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..leaderboard import Leaderboard
from ..pareto import pareto_cost
from ..results import ResultSet
from .base import (
    FIGURES,
    FORMATS,
    LABEL_OFFSET,
    MIN_FONT_PT,
    FigureOptions,
    figure_width,
    free_height,
    label_offsets,
    overlap,
    pyplot,
    save,
    short_label,
    text_size,
    wrap,
)

__all__ = ["draw", "plot_pareto"]


def _plain_log_ticks(ax) -> None:
    """Tick labels as plain numbers (no mathtext: much faster to draw); 1-2-5 ticks over at most two
    decades, powers of ten beyond (so that labels never run into each other on a narrow panel)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    lo, hi = ax.get_xlim()
    decades = math.log10(max(hi, 1e-12) / max(lo, 1e-12))
    subs = (1.0, 2.0, 5.0) if decades <= 2 else (1.0,)
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=subs, numticks=8))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_locator(NullLocator())


def _reference_labels(ax, fig, references: list[tuple[str, float]]) -> list[tuple[float, float, float, float]]:
    """Write each reference's label at the left of the panel, below its line, or above it when that
    would run into the label of a reference close by; their boxes (points), for the point labels to avoid."""
    x0 = ax.transAxes.transform((0.01, 0.0))[0] * 72.0 / fig.dpi
    boxes: list[tuple[float, float, float, float]] = []
    for label, value in sorted(references, key=lambda r: -r[1]):
        text = f"{label} {value:g} %"
        w, h = text_size(fig, text)
        y = ax.transData.transform((1.0, value))[1] * 72.0 / fig.dpi
        for dy in (-9, 2, -18, 11):
            box = (x0, y + dy, x0 + w, y + dy + h)
            if not any(overlap(box, b) for b in boxes):
                break
        else:
            dy = free_height(x0, w, h, y - 9, boxes) - y
            box = (x0, y + dy, x0 + w, y + dy + h)
        boxes.append(box)
        ax.annotate(text, (0.01, value), xycoords=("axes fraction", "data"), textcoords="offset points",
                    xytext=(0, dy), fontsize=MIN_FONT_PT, color="0.35", va="bottom").set_in_layout(False)
    return boxes


def plot_pareto(lb: Leaderboard, base: Path, references: list[tuple[str, float]] | None = None,
                size: str = "text", formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Accuracy against latency, fit time and feature time (see the module docstring).

    ``references``: (label, accuracy in %) pairs drawn as dashed horizontal
    lines on every panel (published results, targets). Points are labelled
    by classifier alone when every method of the table has the same
    features; labels are moved apart so that they do not overlap.
    """
    plt = pyplot()
    rows = lb.rows
    latency = pareto_cost(rows)  # CPU time; wall-clock where results have none (a note says so)
    costs = [(latency, "CPU time per capture (ms)" if latency == "latency_cpu_ms"
              else "wall-clock latency per capture (ms)"),
             ("fit_seconds", "fit time per fold (s)"), ("feature_ms", "feature extraction per capture (ms)")]
    w = figure_width(size)
    if size == "column":  # three panels stacked
        fig, axes = plt.subplots(3, 1, figsize=(w, 7.0), sharey=True, layout="constrained")
    else:
        fig, axes = plt.subplots(1, 3, figsize=(w, 3.2), sharey=True, layout="constrained")
    machines = sorted(set(rows["timing_machine"]))
    markers = ["o", "s", "^", "D", "v"]
    label_all = len(rows) <= (6 if size == "column" else 10)
    with_features = rows["features"].nunique() > 1
    if references:
        lows = [100 * rows["ci_low"].min(), min(v for _, v in references) - 2]
        highs = [100 * rows["ci_high"].max(), max(v for _, v in references) + 3]
        axes[0].set_ylim(np.nanmin(lows), np.nanmax(highs))
    panels = []
    for ax, (col, title) in zip(axes, costs):
        labelled, n_zero = [], 0
        for mi, m in enumerate(machines):
            g = rows[(rows["timing_machine"] == m) & np.isfinite(rows[col]) & np.isfinite(rows["accuracy"])]
            n_zero += int((g[col] <= 0).sum())
            g = g[g[col] > 0]  # a log axis has no 0: a method whose features are computed by its estimator
            if g.empty:
                continue
            x = g[col].to_numpy(dtype=float)
            y = 100 * g["accuracy"].to_numpy(dtype=float)
            lo = 100 * g["ci_low"].to_numpy(dtype=float)
            hi = 100 * g["ci_high"].to_numpy(dtype=float)
            err = np.vstack([np.where(np.isfinite(lo), y - lo, 0), np.where(np.isfinite(hi), hi - y, 0)])
            colors = np.where(g["pareto"].to_numpy(dtype=bool), "tab:red", "tab:blue")
            ax.errorbar(x, y, yerr=err, fmt="none", ecolor="0.7", elinewidth=0.8, zorder=1)
            ax.scatter(x, y, c=list(colors), marker=markers[mi % len(markers)], s=28, zorder=2,
                       label=m if len(machines) > 1 else None)
            if col == latency:
                front = g[g["pareto"].to_numpy(dtype=bool)].sort_values(latency)
                if len(front) > 1:
                    ax.step(front[latency].to_numpy(float), 100 * front["accuracy"].to_numpy(float),
                            where="post", color="tab:red", lw=1, alpha=0.6)
            labelled.append((g, x, y))
        ax.set_xscale("log")
        for _, value in references or []:
            ax.axhline(value, color="0.45", lw=0.8, ls="--", zorder=0)
        if n_zero:
            ax.annotate(f"not shown: {n_zero} without this cost", (0.99, 0.02), xycoords="axes fraction",
                        ha="right", fontsize=MIN_FONT_PT, color="0.35")
        ax.autoscale_view()
        if labelled:
            lo, hi = ax.get_xlim()  # room on the log axis for the labels beside the extreme points
            ax.set_xlim(lo / 1.3, hi * 1.3)
        _plain_log_ticks(ax)
        ax.set_xlabel(title)
        ax.grid(True, which="major", alpha=0.3)
        panels.append((ax, labelled))
    axes[0].set_ylabel("accuracy (%)")
    if len(machines) > 1:
        axes[0].legend(title="machine")
    fig.suptitle(wrap(f"{lb.title}: accuracy vs cost (red: Pareto front on accuracy / latency)", w))
    fig.draw_without_rendering()  # the constrained layout places the panels: label boxes in final points
    for ax, labelled in panels:
        taken = _reference_labels(ax, fig, references) if references and ax is axes[0] else []
        _label_points(ax, fig, labelled, label_all, with_features, taken)
    return save(fig, base, formats)


def _label_points(ax, fig, labelled: list, label_all: bool, with_features: bool,
                  taken: list[tuple[float, float, float, float]]) -> None:
    """Label the points of ``labelled`` ((rows, x, y) per machine; all, or the Pareto front's) apart from
    each other, from ``taken`` and from the panel's edge, with a line to a label moved away."""
    texts, pts = [], []
    for g, x, y in labelled:
        for (_, r), xi, yi in zip(g.iterrows(), x, y):
            if label_all or r["pareto"]:
                texts.append((short_label(r, with_features=with_features), xi, yi))
                pts.append(ax.transData.transform((xi, yi)) * 72.0 / fig.dpi)
    if not texts:
        return
    order = np.argsort([-p[1] for p in pts], kind="stable")  # top to bottom
    bbox = ax.get_window_extent()
    bounds = tuple(v * 72.0 / fig.dpi for v in (bbox.x0, bbox.y0, bbox.x1, bbox.y1))
    sizes = np.array([text_size(fig, texts[i][0]) for i in order])
    offs = label_offsets(np.array(pts)[order], sizes[:, 0], taken=taken, bounds=bounds, heights_pt=sizes[:, 1])
    for i, off in zip(order, offs):
        lab, xi, yi = texts[i]
        leader = None if off == LABEL_OFFSET else {"arrowstyle": "-", "color": "0.6", "lw": 0.5,
                                                        "shrinkA": 0, "shrinkB": 0}
        ax.annotate(lab, (xi, yi), textcoords="offset points", xytext=off, fontsize=MIN_FONT_PT,
                    va="bottom", arrowprops=leader).set_in_layout(False)  # labels may run over: panels keep their width


@FIGURES.register("pareto", description="accuracy against latency, fit time and feature time, with the Pareto front",
                  order=1)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The Pareto plot of a table with accuracies (none without)."""
    if not lb.rows["accuracy"].notna().any():
        return []
    return plot_pareto(lb, base, list(options.references) or None, options.size, options.formats)
