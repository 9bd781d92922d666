"""``frames``: from an ``early`` scheme, accuracy against the number of frames seen (bottom axis)
and seconds seen (top axis, from the dataset's frame rate), one curve per method."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..leaderboard import Leaderboard
from ..results import ResultSet
from .base import FIGURES, FORMATS, FigureOptions, figure_width, pyplot, save, short_label, wrap

__all__ = ["draw", "plot_frames"]


def _base_method(r: Any) -> str:
    return f"{r['feature_params']}|{r['classifier_name']}|{r['classifier_params']}"


def plot_frames(lb: Leaderboard, base: Path, size: str = "text", formats: tuple[str, ...] = FORMATS) -> list[Path]:
    """Accuracy against frames (and seconds) seen, from an ``early`` scheme."""
    plt = pyplot()
    rows = lb.rows[np.isfinite(lb.rows["early_frames"])].copy()
    if rows.empty:
        raise ValueError(f"{lb.title}: not an early scheme (no frames-seen values)")
    rows["base"] = [_base_method(r) for _, r in rows.iterrows()]
    w = figure_width(size)
    fig, ax = plt.subplots(figsize=(w, 0.62 * w if size == "text" else 3.4), layout="constrained")
    for _, g in rows.groupby("base", sort=False):
        g = g.sort_values("early_frames")
        x = g["early_frames"].to_numpy(float)
        y = 100 * g["accuracy"].to_numpy(float)
        line = ax.plot(x, y, marker="o", ms=4, label=short_label(g.iloc[0], 40))[0]
        lo, hi = 100 * g["ci_low"].to_numpy(float), 100 * g["ci_high"].to_numpy(float)
        if np.isfinite(lo).all():
            ax.fill_between(x, lo, hi, color=line.get_color(), alpha=0.15)
    ax.set_xlabel("frames seen")
    ax.set_ylabel("accuracy (%)")
    ax.grid(True, alpha=0.3)
    fr = lb.frame_rate
    if np.isfinite(fr) and fr > 0:
        sec = ax.secondary_xaxis("top", functions=(lambda f: f / fr, lambda s: s * fr))
        sec.set_xlabel(f"seconds seen (at {fr:g} frames/s)")
    ax.legend()
    ax.set_title(wrap(f"{lb.title}: accuracy vs frames seen", w), pad=20 if np.isfinite(fr) else 6)
    return save(fig, base, formats)


@FIGURES.register("frames", description="accuracy against frames and seconds seen, from an early scheme", order=2)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The frames plot of an ``early`` table (none for another scheme)."""
    if not lb.is_early:
        return []
    return plot_frames(lb, base, options.size, options.formats)
