"""How leaderboard rows read: a method's readable label and name (with the parameters that tell
colliding rows apart) and numbers as table cells."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pandas as pd

from ..methods.base import METHODS

__all__ = ["method_label", "method_labels", "method_names", "owns_input"]


def _pct(v: float, d: int = 1) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{100 * v:.{d}f}"


def _num(v: float, d: int = 2) -> str:
    if v is None or not np.isfinite(v):
        return "—"
    if abs(v) >= 100:
        return f"{v:.0f}"
    return f"{v:.{d}g}" if abs(v) < 0.01 else f"{v:.{d}f}"


def _p(v: float) -> str:
    if v is None or not np.isfinite(v):
        return "—"
    return "<0.001" if v < 0.001 else f"{v:.3f}"


def owns_input(r: Any) -> bool:
    """Whether a row's method brings its own input (a registered method, an estimator on the
    captures): its label names it alone, where a feature combination's row is ``features / label``."""
    return str(r.get("classifier_name", "")) in METHODS.names() or str(r["features"]).startswith("captures")


def method_label(r: Any) -> str:
    """A row's name: its label for a method that brings its own input, else ``features / label``;
    with the frames an early cut saw."""
    lab = str(r["classifier"]) if owns_input(r) else f"{r['features']} / {r['classifier']}"
    if np.isfinite(r.get("early_frames", math.nan)):
        lab += f" @ {int(r['early_frames'])} frames"
    return lab


def _params(text: Any) -> str:
    """Parameters as stored (canonical JSON) in a short readable form: ``{"bins": 8}`` -> ``bins=8``."""
    try:
        value = json.loads(str(text))
    except (TypeError, ValueError):
        return str(text)
    if isinstance(value, dict):
        return ", ".join(f"{k}={_params(json.dumps(v))}" for k, v in value.items())
    if isinstance(value, list):
        return "; ".join(p for p in (_params(json.dumps(v)) for v in value) if p)
    return str(value)


def _label_parts(rows: pd.DataFrame) -> dict[str, list[str]]:
    """Per method id, what its readable label adds to ``features / method``: the feature parameters,
    then the method's parameters, where two rows would otherwise read the same, and a ``#2`` suffix if
    they still do (``[feature part, method part, suffix]``)."""
    base = {r["method_id"]: method_label(r) for _, r in rows.iterrows()}
    parts = {mid: ["", "", ""] for mid in base}
    for i, extra in enumerate(("feature_params", "classifier_params")):
        full = {mid: base[mid] + "".join(parts[mid]) for mid in base}
        counts = pd.Series(list(full.values())).value_counts()
        for _, r in rows.iterrows():
            if counts.get(full[r["method_id"]], 0) > 1 and r.get(extra) not in (None, "", "{}", "[]"):
                p = _params(r[extra])
                if p:
                    parts[r["method_id"]][i] += f" ({'features' if i == 0 else 'method'}: {p})"
    seen: dict[str, int] = {}
    for mid in base:
        lab = base[mid] + "".join(parts[mid])
        seen[lab] = seen.get(lab, 0) + 1
        if seen[lab] > 1:
            parts[mid][2] = f" #{seen[lab]}"
    return parts


def method_labels(rows: pd.DataFrame) -> dict[str, str]:
    """A readable label per method id: ``features / method`` (and frames), with the feature
    parameters, then the method's parameters, where two rows would otherwise read the same; a
    ``#2`` suffix if they still do."""
    parts = _label_parts(rows)
    return {r["method_id"]: method_label(r) + "".join(parts[r["method_id"]]) for _, r in rows.iterrows()}


def _name_cell(r: pd.Series, parts: list[str]) -> str:
    """A row's readable name: its label for a method that brings its own input (a registered method,
    an estimator on the captures), else ``features / label``; with the parameters that tell colliding
    rows apart and its early cut, so that the name alone tells the rows apart."""
    feat_extra, method_extra, suffix = parts
    name = str(r["classifier"]) + method_extra + suffix
    if not owns_input(r):
        name = f"{r['features']}{feat_extra} / {name}"
    if np.isfinite(r["early_frames"]):
        name += f" @ {int(r['early_frames'])} frames"
    return name


def method_names(rows: pd.DataFrame) -> dict[str, str]:
    """A table's readable name per method id, as its rows show it (:func:`touchbench.reports.rendering.display_rows`)."""
    parts = _label_parts(rows)
    return {r["method_id"]: _name_cell(r, parts[r["method_id"]]) for _, r in rows.iterrows()}
