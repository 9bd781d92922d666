"""Data curves: a method's accuracy against the training data it was given, from one table's tasks.

A scheme that sweeps the training data writes one task per point of its
curve (the scores' ``curve``, ``curve_size`` and ``curve_draw``,
:class:`touchbench.protocols.schemes.CurvePoint`; fold names such as
``n3#1/subject=s01``, the point before its base fold):

- ``subjects``, a learning curve: trained on ``n`` of each base fold's
  training subjects (a fraction of them when below 1), several random draws
  per ``n``, the full point (every training subject) always among them;
- ``calibration``: ``k`` labelled captures per class of the test subject
  joined the training data, ``k = 0`` (none) among them.

Every point of a base fold is scored on the same test captures as its other
points (paired; :mod:`touchbench.reports.results` keys a point's fold by the
point, then its base fold's captures).

The statistics (float64):

- a point's accuracy: per base fold (its test subject or subjects, the
  statistical unit), the mean over its draws (and seeds), then the mean over
  the base folds. Draws share their base fold's test captures, so they are
  averaged first and never counted as independent;
- its 95 % interval: Student's t over the base folds' means, clipped to
  [0, 1] (as the leaderboard's interval over folds,
  :func:`touchbench.reports.stats.fold_interval`). With a single base fold
  (one test set), a percentile bootstrap over the test captures and the
  draws crossed, Owen's pigeonhole bootstrap (2007;
  :mod:`touchbench.reports.bootstrap`, its degenerate cases there: fewer
  than two captures, none): each resample draws the captures and the
  draws with replacement, independently, so both the test set's and the
  draws' variation widen it (from the predictions; without them, none);
- ``reach``: the smallest size whose accuracy is at least ``fraction`` of
  the full accuracy: on a subjects curve the full point's (the largest
  ``n``); on a calibration curve the largest ``k`` swept's (``k = 0``, no
  label of the test subject, is the baseline the gains are measured from);
- ``added`` (calibration): the labelled captures per class each asked ``k`` really added, the mean
  and the least over the test side's (unit, class) pools (a pool with no more than ``k`` captures
  gives all but one); a capped point is labelled by them, never by the ``k`` asked alone;
- ``gains`` (calibration): each ``k`` over ``k = 0``, paired over base
  folds: per base fold the draws' mean at ``k`` minus that at ``k = 0``,
  the mean of those differences and their Student t interval (not clipped);
  one base fold: the pigeonhole bootstrap of the difference, the captures
  drawn once for both points and each point's draws on their own (not
  ``paired``).

The leaderboard's own table of a curve's tasks is its reference point
(:func:`reference_rows`): the full point of a subjects curve, ``k = 0`` of a
calibration curve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from ..core.errors import TouchbenchError
from .bootstrap import pigeonhole
from .stats import fold_interval

__all__ = ["Curve", "DEFAULT_FRACTION", "check_fraction", "curve_of", "reference_rows"]

#: the share of its full accuracy a method is asked to reach (``--fraction``)
DEFAULT_FRACTION = 0.95
LEVEL = 0.95


@dataclass
class Curve:
    """One table's curve: ``axis`` ("subjects" or "calibration"), ``sizes`` (ascending), and per method
    (``method_id``) its ``points`` (``size``, ``accuracy``, ``ci_low``, ``ci_high``, ``ci_method``: "t"
    over ``n_units`` base folds or "bootstrap" over draws and captures, ``n_draws``), its ``gains`` over
    ``k = 0`` (calibration only: ``size``, ``gain``, ``ci_low``, ``ci_high``, ``ci_method``, ``n_units``)
    and its ``reach`` (``full_size``, ``full_accuracy``, ``size``: the smallest size reaching
    ``fraction`` of ``full_accuracy``, ``accuracy`` there; ``baseline``: the accuracy at ``k = 0``)."""

    axis: str
    sizes: list[float]
    points: pd.DataFrame
    gains: pd.DataFrame
    reach: pd.DataFrame
    fraction: float
    #: a subjects curve whose base folds have different numbers of training subjects: the largest size
    #: is each base fold's full point ("all")
    full_varies: bool = False
    #: calibration: per size asked (k), the labelled captures per class its tasks really added, the
    #: mean and the least over the (unit, class) pools and tasks; sizes without a record are left out
    added: dict[float, tuple[float, float]] = field(default_factory=dict)

    def capped(self) -> dict[float, tuple[float, float]]:
        """The calibration points whose tasks added fewer captures than asked (size -> mean, least)."""
        return {k: a for k, a in self.added.items() if a[0] < k - 1e-9}

    @property
    def units(self) -> int:
        """The most base folds a point was scored on."""
        return int(self.points["n_units"].max()) if len(self.points) else 0


def check_fraction(fraction: float) -> float:
    """``fraction`` as a float in (0, 1], else one clear error."""
    f = float(fraction)
    if not (0.0 < f <= 1.0):
        raise TouchbenchError(f"fraction {fraction!r}: the share of the full accuracy must be above 0 and at most 1")
    return f


def _on_curve(s: pd.DataFrame) -> pd.Series:
    return s["curve"].astype(str) != "" if "curve" in s else pd.Series(False, index=s.index)


def _reference_sizes(scores: pd.DataFrame) -> dict[tuple[str, str], float]:
    """Per curve and base fold, the size of the reference point: the base fold's largest (its full
    point: every training subject of that fold) on a subjects curve, 0 on a calibration curve (its
    largest where 0 was not swept)."""
    on = scores[_on_curve(scores)]
    out = {}
    for (axis, base), g in on.groupby([on["curve"].astype(str), _base(on["fold_key"])], sort=False):
        sizes = g["curve_size"].astype(np.float64)
        out[(axis, base)] = 0.0 if axis == "calibration" and (sizes == 0).any() else float(sizes.max())
    return out


def reference_rows(scores: pd.DataFrame, ok: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """A table's tasks (``scores``) and its finished ones (``ok``) at the reference point of their
    curve (:func:`_reference_sizes`); both unchanged off a curve."""
    ref = _reference_sizes(scores)
    if not ref:
        return scores, ok

    def keep(frame: pd.DataFrame) -> pd.DataFrame:
        want = [ref.get((str(c), b), math.nan) for c, b in zip(frame["curve"], _base(frame["fold_key"]))]
        return frame[~_on_curve(frame) | np.isclose(frame["curve_size"].astype(np.float64), want)]

    return keep(scores), keep(ok)


def _base(fold_keys: pd.Series) -> pd.Series:
    """The base fold of each point's fold key (what follows the point)."""
    return fold_keys.astype(str).str.split("|", n=1).str[-1]


def _unit_means(g: pd.DataFrame) -> pd.Series:
    """Per base fold, the mean over its draws of each draw's accuracy (its seeds averaged first)."""
    return g.groupby(["base", "curve_draw"])["accuracy"].mean().groupby(level=0).mean()


def _interval(a: np.ndarray, b: np.ndarray | None = None) -> tuple[float, float]:
    """The pigeonhole interval of a point's captures x draws (minus another point's, its draws on their
    own: not paired; :mod:`touchbench.reports.bootstrap`)."""
    boot = pigeonhole(a, b, paired=False, level=LEVEL)
    return boot.low, boot.high


def _matrix(preds: pd.DataFrame | None, task_ids: pd.Series) -> pd.DataFrame:
    """Draws x test captures of the tasks ``task_ids``: each cell the capture's correctness (the mean
    over seeds; NaN where the draw did not score the capture)."""
    if preds is None or preds.empty:
        return pd.DataFrame()
    p = preds[preds["task_id"].isin(set(task_ids))]
    if p.empty:
        return pd.DataFrame()
    return p.astype({"correct": np.float64}).pivot_table(index="curve_draw", columns="capture_id", values="correct",
                                                         aggfunc="mean")


def _point(g: pd.DataFrame, preds: pd.DataFrame | None) -> dict:
    """The accuracy and interval of one method at one size (its tasks ``g``)."""
    units = _unit_means(g)
    out = {"n_units": int(len(units)), "n_draws": int(g["curve_draw"].nunique())}
    if len(units) >= 2:
        mean, _, lo, hi = fold_interval(units.to_numpy(np.float64), LEVEL)
        return {**out, "accuracy": mean, "ci_low": lo, "ci_high": hi, "ci_method": "t"}
    m = _matrix(preds, g["task_id"])
    lo, hi = _interval(m.to_numpy().T) if m.shape[1] else (math.nan, math.nan)
    return {**out, "accuracy": float(units.mean()) if len(units) else math.nan, "ci_low": lo, "ci_high": hi,
            "ci_method": "bootstrap" if np.isfinite(lo) else ""}


def _gain(g: pd.DataFrame, g0: pd.DataFrame, preds: pd.DataFrame | None) -> dict:
    """The paired gain of one method at a size (tasks ``g``) over ``k = 0`` (tasks ``g0``)."""
    d = (_unit_means(g) - _unit_means(g0)).dropna()
    n = int(len(d))
    if n >= 2:
        mean, sd = float(d.mean()), float(d.std(ddof=1))
        half = float(stats.t.ppf(0.5 + LEVEL / 2.0, n - 1)) * sd / math.sqrt(n)
        return {"gain": mean, "ci_low": mean - half, "ci_high": mean + half, "ci_method": "t", "n_units": n}
    out = {"gain": float(d.mean()) if n else math.nan, "ci_low": math.nan, "ci_high": math.nan, "ci_method": "",
           "n_units": n}
    m, m0 = _matrix(preds, g["task_id"]), _matrix(preds, g0["task_id"])
    if m.shape[1] and m0.shape[1]:
        caps = m.columns.union(m0.columns)
        lo, hi = _interval(m.reindex(columns=caps).to_numpy().T, m0.reindex(columns=caps).to_numpy().T)
        out.update(ci_low=lo, ci_high=hi, ci_method="bootstrap" if np.isfinite(lo) else "")
    return out


def _reach(points: pd.DataFrame, axis: str, fraction: float) -> dict:
    """One method's full accuracy and the smallest size reaching ``fraction`` of it (see the module)."""
    p = points.dropna(subset=["accuracy"]).sort_values("size")
    if p.empty:
        return {"full_size": math.nan, "full_accuracy": math.nan, "size": math.nan, "accuracy": math.nan,
                "baseline": math.nan}
    full = p.iloc[-1]
    # a tolerance of float rounding: a point equal to the target reaches it
    reached = p[p["accuracy"] >= fraction * full["accuracy"] - 1e-12].iloc[0]
    base = p[np.isclose(p["size"], 0.0)]
    return {"full_size": float(full["size"]), "full_accuracy": float(full["accuracy"]), "size": float(reached["size"]),
            "accuracy": float(reached["accuracy"]),
            "baseline": float(base["accuracy"].iloc[0]) if axis == "calibration" and len(base) else math.nan}


def _curve_tasks(ok: pd.DataFrame, preds: pd.DataFrame | None) -> tuple[pd.DataFrame, pd.DataFrame | None, bool]:
    """The finished tasks on a curve with their base fold, their predictions with each task's draw,
    and whether the full points of a subjects curve differ between base folds (each then set to the
    largest: one column)."""
    g = ok[_on_curve(ok)].copy()
    g["base"] = _base(g["fold_key"])
    g["curve_size"] = g["curve_size"].astype(np.float64)
    subjects = g["curve"] == "subjects"
    full = g[subjects].groupby("base")["curve_size"].transform("max")
    varies = full.nunique() > 1
    if varies:  # base folds with different numbers of training subjects: their full points form one column
        g.loc[full.index[g.loc[full.index, "curve_size"] == full], "curve_size"] = float(full.max())
    if preds is not None and len(preds):
        info = g.drop_duplicates("task_id").set_index("task_id")[["curve_draw"]]
        preds = preds.drop(columns=[c for c in ("curve_draw",) if c in preds]).join(info, on="task_id", how="inner")
    return g, preds, bool(varies)


def _added(g: pd.DataFrame) -> dict[float, tuple[float, float]]:
    """Per calibration size, the mean and least of the captures per class its tasks recorded adding
    (``curve_added``, ``curve_added_min``; results of versions that did not record them: none)."""
    if "curve_added" not in g or "curve_added_min" not in g:
        return {}
    out = {}
    for size, gs in g.groupby("curve_size"):
        mean, least = gs["curve_added"].astype(np.float64), gs["curve_added_min"].astype(np.float64)
        if mean.notna().all() and least.notna().all():
            out[float(size)] = (float(mean.mean()), float(least.min()))
    return out


def curve_of(ok: pd.DataFrame, preds: pd.DataFrame | None, fraction: float = DEFAULT_FRACTION) -> Curve | None:
    """The curve of one table's finished tasks ``ok`` (``preds``: their predictions; None when the
    table's tasks are on no curve)."""
    fraction = check_fraction(fraction)
    g, preds, varies = _curve_tasks(ok, preds)
    if g.empty:
        return None
    axis = str(g["curve"].value_counts().index[0])
    g = g[g["curve"] == axis]
    points, gains, reach = [], [], []
    for mid, gm in g.groupby("method_id", sort=False):
        mine = [{"method_id": mid, "size": size, **_point(gs, preds)} for size, gs in gm.groupby("curve_size")]
        points += mine
        zero = gm[np.isclose(gm["curve_size"], 0.0)]
        if axis == "calibration" and len(zero):
            gains += [{"method_id": mid, "size": size, **_gain(gs, zero, preds)}
                      for size, gs in gm.groupby("curve_size") if size > 0]
        reach.append({"method_id": mid, **_reach(pd.DataFrame(mine), axis, fraction)})
    reach_df = pd.DataFrame(reach).sort_values("full_accuracy", ascending=False, kind="stable", na_position="last")
    return Curve(axis=axis, sizes=sorted(set(g["curve_size"])), points=pd.DataFrame(points),
                 gains=pd.DataFrame(gains, columns=["method_id", "size", "gain", "ci_low", "ci_high", "ci_method",
                                                    "n_units"]),
                 reach=reach_df.reset_index(drop=True), fraction=fraction, full_varies=varies and axis == "subjects",
                 added=_added(g) if axis == "calibration" else {})
