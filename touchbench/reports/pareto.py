"""The accuracy / cost Pareto front.

A method is on the front when no other method measured on the same machine
is at least as accurate and at most as costly, and strictly better in one of
the two. Methods without a cost measurement (every fold failed to time) are
never on the front. Ties (same accuracy and cost) are all on the front.

The cost of a leaderboard's front is the CPU time of labelling one capture
(:func:`pareto_cost`): the load of other processes changes it far less than
the wall-clock latency.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

__all__ = ["pareto_cost", "pareto_front"]


def pareto_front(accuracy: Sequence[float], cost: Sequence[float]) -> np.ndarray:
    """Boolean mask of the points not dominated (higher accuracy, lower cost is better)."""
    a = np.asarray(accuracy, dtype=np.float64)
    c = np.asarray(cost, dtype=np.float64)
    if a.shape != c.shape:
        raise ValueError("accuracy and cost differ in length")
    ok = np.isfinite(a) & np.isfinite(c)
    front = np.zeros(len(a), dtype=bool)
    for i in np.flatnonzero(ok):
        others = ok.copy()
        others[i] = False
        ge = (a >= a[i]) & (c <= c[i]) & others
        strictly = ge & ((a > a[i]) | (c < c[i]))
        front[i] = not strictly.any()
    return front


def pareto_cost(rows: pd.DataFrame) -> str:
    """The time a Pareto front of ``rows`` (one machine's) is computed on: the CPU time of labelling
    one capture (``latency_cpu_ms``), which other processes' load changes far less than the
    wall-clock latency; the wall-clock ``latency_ms`` when a timed method has no CPU time (results
    written before touchbench measured it, or rows without the column)."""
    if "latency_cpu_ms" not in rows:
        return "latency_ms"
    timed = rows[rows["latency_ms"].notna()]
    return "latency_cpu_ms" if len(timed) and timed["latency_cpu_ms"].notna().all() else "latency_ms"
