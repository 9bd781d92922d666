"""``learning-curve``: a data curve's accuracy against the training data, one line per method with its
95 % interval as a band (:mod:`touchbench.reports.curves`): training subjects n, or labelled captures
per class of the test subject k."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..curve_table import size_label
from ..labels import method_names
from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import FIGURES, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["draw", "plot_learning_curve"]


def _axis(lb: Leaderboard) -> tuple[str, str]:
    """The x axis's label and what the title says the curve is against."""
    curve = lb.curve
    if curve.axis == "calibration":
        return "labelled captures per class (k)", "k labelled captures per class from the test data"
    if size_label(curve, curve.sizes[-1]).endswith("%"):
        return "training subjects (%)", "the share of the training subjects"
    return "training subjects (n)", "n training subjects"


def plot_learning_curve(lb: Leaderboard, base: Path, size: str, formats: tuple[str, ...]) -> list[Path]:
    """Accuracy (%) on the held-out captures against the size, one line and band per method, best
    (at full size) first in the legend."""
    plt = pyplot()
    curve = lb.curve
    names = method_names(lb.rows)
    w = figure_width(size)
    fig, ax = plt.subplots(figsize=(w, 0.7 * w if w < 5 else 3.4), layout="constrained")
    for i, mid in enumerate(m for m in curve.reach["method_id"] if m in names):
        p = curve.points[curve.points["method_id"] == mid].sort_values("size")
        x = p["size"].to_numpy(np.float64)
        line, = ax.plot(x, 100 * p["accuracy"].to_numpy(np.float64), marker="os^Dv<>p*h"[i % 10], ms=3.5, lw=1.2,
                        label=names[mid])
        lo, hi = p["ci_low"].to_numpy(np.float64), p["ci_high"].to_numpy(np.float64)
        ax.fill_between(x, 100 * lo, 100 * hi, color=line.get_color(), alpha=0.18, lw=0)
    ax.set_xticks(curve.sizes, labels=[size_label(curve, s).removeprefix("n=").removeprefix("k=") for s in curve.sizes])
    xlabel, against = _axis(lb)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("accuracy (%)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", frameon=False)
    unit = (f"band: 95 % t interval over {curve.units} test folds" if curve.units >= 2
            else "band: 95 % bootstrap over draws and test captures")
    ax.set_title(wrap(f"{lb.title}: accuracy on the held-out captures against {against} ({unit})", w), fontsize=8)
    return save(fig, base, formats)


@FIGURES.register("learning-curve", description="a data curve: accuracy against training subjects or "
                  "calibration captures, with its interval", order=8)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The curve of a table whose tasks are points of a data curve (none for any other table)."""
    if lb.curve is None or lb.curve.points.empty:
        return []
    return plot_learning_curve(lb, base, options.size, options.formats)
