"""``timeline``: one test stream of a stream evaluation, its truth against the decisions of the table's
best method and rule, over time: a figure a paper can print."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..leaderboard import Leaderboard
from ..results import ResultSet
from ..stream_table import rule_label
from .base import FIGURES, FigureOptions, figure_width, pyplot, save, wrap

__all__ = ["draw", "plot_timeline"]


def _runs(runs: list, n: int) -> list[tuple[int, int, str]]:
    """Run-length labels ``[[first frame, label], ...]`` as ``(first, stop, label)``."""
    return [(int(a), int(runs[k + 1][0]) if k + 1 < len(runs) else n, str(lab)) for k, (a, lab) in enumerate(runs)]


def _first_stream(rs: ResultSet, lb: Leaderboard) -> tuple[dict[str, Any], int, dict[str, Any]] | None:
    """The best row's first stream (by name), the rule's index and the task's payload."""
    best = lb.live.iloc[0]
    s = rs.scores
    tasks = s[(s["table_key"] == lb.key) & (s["method_id"] == best["method_id"]) & (s["status"] == "ok")]
    payloads = [json.loads(x) for x in tasks["live"] if x]
    streams = sorted((st for p in payloads for st in p["streams"]), key=lambda st: st["name"])
    if not streams:
        return None
    k = next((i for i, r in enumerate(payloads[0]["rules"]) if rule_label(r) == best["rule"]), 0)
    return streams[0], k, payloads[0]


def plot_timeline(rs: ResultSet, lb: Leaderboard, base: Path, size: str, formats: tuple[str, ...],
                  seconds: float = 60.0) -> list[Path]:
    """Truth and decisions of the first ``seconds`` of the best row's first stream, one lane each."""
    found = _first_stream(rs, lb)
    if found is None:
        return []
    stream, k, payload = found
    rate = float(payload["frame_rate"])
    n = int(min(stream["frames"], round(seconds * rate)))
    truth = _runs(stream["truth"], stream["frames"])
    decided = _runs(stream["results"][k]["decisions"], stream["frames"])
    labels = sorted({lab for _, _, lab in truth + decided})
    colours = dict(zip(labels, pyplot().get_cmap("tab10")(np.arange(len(labels)) % 10)))
    plt = pyplot()
    w = figure_width(size)
    fig, ax = plt.subplots(figsize=(w, 2.2), layout="constrained")
    for lane, runs in ((1, truth), (0, decided)):
        for a, b, lab in runs:
            if a < n:
                ax.broken_barh([(a / rate, (min(b, n) - a) / rate)], (lane - 0.4, 0.8), color=colours[lab])
    ax.set_yticks([0, 1], labels=["decided", "truth"])
    ax.set_xlim(0, n / rate)
    ax.set_xlabel("time (s)")
    handles = [plt.Rectangle((0, 0), 1, 1, color=colours[lab]) for lab in labels]
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 7), frameon=False, fontsize=7)
    best = lb.live.iloc[0]
    ax.set_title(wrap(f"{lb.title}: stream {stream['name']} ({stream['source']}), {best['method']} · {best['rule']}",
                      w), fontsize=8)
    return save(fig, base, formats)


@FIGURES.register("timeline", description="one test stream: truth against the best method's decisions", order=7)
def draw(rs: ResultSet, lb: Leaderboard, base: Path, options: FigureOptions) -> list[Path]:
    """The timeline of a stream evaluation's table (none for a table of captures)."""
    if lb.live is None or not len(lb.live):
        return []
    return plot_timeline(rs, lb, base, options.size, options.formats)
