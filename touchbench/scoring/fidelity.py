"""Hold a scene against real data, and measure how separable a scene is.

Fidelity (``touchbench scenes fidelity haart-like``) compares, per
gesture, the distributions of three capture statistics on the scene and on
the real dataset it names (``real_counterpart``), and the accuracy of the
same protocol on both:

- total pressure: the mean over frames of the frame's summed values
  (counts; baseline included, as a feature extractor sees it);
- contact area: the mean over frames of the number of cells above
  ``threshold`` counts (default 10: just above HAART's resting noise, whose
  95th percentile on no-touch recordings is 9);
- centroid speed: the mean speed (cells/s) of the centroid of the pressure
  above ``threshold``, over consecutive frames that both have contact; 0
  for a capture with fewer than two such frames.

Target: each per-gesture median of the scene within the real
interquartile range, and accuracy within 10 points of the real data's under
the same protocol: Gaus et al. (2015) feature sets and a random forest,
leave-one-subject-out and the challenge split.

Separability (:func:`separability`): the best accuracy of a few methods
(feature sets of the papers + random forest) on a scene, so that no shipped
scene is trivially separable.

Interpretation: the random forest is scikit-learn's with ``n_estimators``
trees (default 100, not the paper's 1000, to keep the report quick); the
features are whichever of ``sd, bmh, msd, smmhh, lbptop`` the FEATURES
registry holds, with their default parameters for the dataset's sensor.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import pandas as pd
from sklearn.ensemble import RandomForestClassifier
from sklearn.model_selection import GroupKFold, StratifiedKFold

from ..catalog import load_dataset
from ..core.errors import TouchbenchError
from ..datasets.model import TouchDataset
from ..features import FEATURES
from ..scenes import generate_scene, load_scene

METRICS = ("total", "area", "speed")
GAUS_SETS = ("sd", "bmh", "msd", "smmhh", "lbptop")


# ------------------------------------------------------------------ metrics
def capture_metrics(capture: np.ndarray, frame_rate: float, threshold: float = 10.0) -> tuple[float, float, float]:
    """(total pressure, contact area, centroid speed) of one (T, H, W) capture."""
    x = np.asarray(capture, dtype=np.float64)
    T, H, W = x.shape
    flat = x.reshape(T, -1)
    total = float(flat.sum(axis=1).mean())
    area = float((flat > threshold).sum(axis=1).mean())
    w = np.clip(x - threshold, 0.0, None)
    ws = w.sum(axis=(1, 2))
    ok = ws > 0
    safe = np.where(ok, ws, 1.0)
    cy = (w.sum(axis=2) * np.arange(H)).sum(axis=1) / safe
    cx = (w.sum(axis=1) * np.arange(W)).sum(axis=1) / safe
    both = ok[1:] & ok[:-1]
    if both.any():
        step = np.hypot(np.diff(cy), np.diff(cx))[both]
        speed = float(step.mean() * frame_rate)
    else:
        speed = 0.0
    return total, area, speed


def metric_table(ds: TouchDataset, threshold: float = 10.0) -> pd.DataFrame:
    """One row per capture: gesture, subject and the three metrics."""
    rows = [capture_metrics(c, ds.sensor.frame_rate, threshold) for c in ds.captures]
    out = pd.DataFrame(rows, columns=list(METRICS))
    out.insert(0, "subject", ds.meta["subject"].to_numpy())
    out.insert(0, "gesture", ds.meta["gesture"].to_numpy())
    return out


def compare_distributions(real: pd.DataFrame, synth: pd.DataFrame) -> pd.DataFrame:
    """Per gesture and metric: real quartiles, scene quartiles, and whether
    the scene's median lies within the real interquartile range."""
    rows = []
    for g in sorted(set(real["gesture"]) & set(synth["gesture"])):
        r = real[real["gesture"] == g]
        s = synth[synth["gesture"] == g]
        for m in METRICS:
            rq = r[m].quantile([0.25, 0.5, 0.75]).to_numpy()
            sq = s[m].quantile([0.25, 0.5, 0.75]).to_numpy()
            rows.append(
                {
                    "gesture": g,
                    "metric": m,
                    "real_q25": rq[0],
                    "real_median": rq[1],
                    "real_q75": rq[2],
                    "scene_q25": sq[0],
                    "scene_median": sq[1],
                    "scene_q75": sq[2],
                    "within_iqr": bool(rq[0] <= sq[1] <= rq[2]),
                }
            )
    return pd.DataFrame(rows)


# ----------------------------------------------------------------- accuracy
def available_sets(names: Sequence[str]) -> list[str]:

    return [n for n in names if n in FEATURES]


def feature_matrix(ds: TouchDataset, sets: Sequence[str], train: np.ndarray | None = None) -> np.ndarray:
    """Features of every capture; fold-dependent sets are fitted on
    ``train`` (positions) only."""

    blocks = []
    for name in sets:
        fs = FEATURES.create(name, sensor=ds.sensor)
        fit_on = ds.captures if train is None else [ds.captures[i] for i in train]
        fs.fit(fit_on, ds.labels if train is None else ds.labels[train])
        blocks.append(np.asarray(fs.transform(ds.captures), dtype=np.float64))
    return np.hstack(blocks)


def _folds(meta: pd.DataFrame, scheme: str, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    idx = np.arange(len(meta))
    subj = meta["subject"].to_numpy()
    if scheme == "loso":
        return [(idx[subj != s], idx[subj == s]) for s in sorted(set(subj))]
    if scheme == "challenge":
        if "split" not in meta.columns:
            raise ValueError("the challenge split needs a 'split' column")
        sp = meta["split"].to_numpy()
        return [(idx[sp == "train"], idx[sp == "test"])]
    if scheme.startswith("subject-kfold"):

        k = int(scheme.split(":")[1]) if ":" in scheme else 5
        k = min(k, len(set(subj)))
        return [(tr, te) for tr, te in GroupKFold(n_splits=k).split(idx, groups=subj)]
    if scheme.startswith("kfold"):

        k = int(scheme.split(":")[1]) if ":" in scheme else 5
        skf = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
        return [(tr, te) for tr, te in skf.split(idx, meta["gesture"].to_numpy())]
    raise ValueError(f"unknown scheme {scheme!r} (loso, challenge, subject-kfold:K, kfold:K)")


def accuracy(
    ds: TouchDataset,
    sets: Sequence[str],
    schemes: Sequence[str] = ("loso",),
    n_estimators: int = 100,
    seed: int = 0,
) -> dict[str, float]:
    """Pooled accuracy (correct / tested) of ``sets`` + random forest under
    each scheme. Fold-independent features are computed once."""

    y = ds.labels
    fixed = [s for s in sets if not FEATURES.get(s).fold_dependent]
    per_fold = [s for s in sets if FEATURES.get(s).fold_dependent]
    X_fixed = feature_matrix(ds, fixed) if fixed else np.zeros((len(ds), 0))
    out = {}
    for scheme in schemes:
        correct = tested = 0
        for tr, te in _folds(ds.meta, scheme, seed):
            if len(tr) == 0 or len(te) == 0:
                continue
            X = X_fixed if not per_fold else np.hstack([X_fixed, feature_matrix(ds, per_fold, train=tr)])
            rf = RandomForestClassifier(n_estimators=n_estimators, random_state=seed, n_jobs=1)
            rf.fit(X[tr], y[tr])
            correct += int((rf.predict(X[te]) == y[te]).sum())
            tested += len(te)
        out[scheme] = correct / tested if tested else float("nan")
    return out


# ------------------------------------------------------------------ reports
@dataclass
class Fidelity:
    scene: str
    real: str
    seed: int
    distributions: pd.DataFrame
    accuracy: pd.DataFrame  # rows: scheme; columns: real, scene
    sets: list[str]
    n_estimators: int
    notes: list[str] = field(default_factory=list)

    @property
    def within(self) -> int:
        return int(self.distributions["within_iqr"].sum())

    def to_text(self) -> str:
        d = self.distributions
        lines = [
            f"fidelity of scene {self.scene!r} (seed {self.seed}) against {self.real!r}",
            "",
            "per-gesture distributions: real quartiles [q25 median q75] vs scene median (ok = within the real IQR)",
        ]
        for m in METRICS:
            lines.append(f"  {m}:")
            for _, r in d[d["metric"] == m].iterrows():
                ok = "ok" if r["within_iqr"] else "OUT"
                lines.append(
                    f"    {r['gesture']:<10} real [{r['real_q25']:9.2f} {r['real_median']:9.2f} {r['real_q75']:9.2f}]"
                    f"   scene {r['scene_median']:9.2f}   {ok}"
                )
        lines.append(f"  {self.within} of {len(d)} medians within the real IQR")
        lines.append("")
        lines.append(f"accuracy: {' + '.join(self.sets)} features, random forest ({self.n_estimators} trees)")
        for scheme, r in self.accuracy.iterrows():
            diff = 100 * (r["scene"] - r["real"])
            lines.append(f"  {scheme:<10} real {100 * r['real']:5.1f} %   scene {100 * r['scene']:5.1f} %   ({diff:+.1f} points)")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)


def check_fidelity(
    scene: str,
    real: str | None = None,
    seed: int | None = None,
    sets: Sequence[str] | None = None,
    schemes: Sequence[str] = ("loso", "challenge"),
    n_estimators: int = 100,
    threshold: float = 10.0,
    accuracy_too: bool = True,
) -> Fidelity:
    """Compare scene ``scene`` with the real dataset it names (or ``real``)."""

    spec = load_scene(scene)
    real_name = real or spec.real_counterpart
    if not real_name:
        raise TouchbenchError(f"scene {scene!r} names no real dataset to hold it against (real_counterpart)")
    seed = spec.seed if seed is None else seed
    synth = generate_scene(scene, seed=seed)
    ref = load_dataset(real_name)
    dist = compare_distributions(metric_table(ref, threshold), metric_table(synth, threshold))
    notes = []
    chosen = list(sets) if sets is not None else available_sets(GAUS_SETS)
    missing = [s for s in (sets or GAUS_SETS) if s not in chosen]
    if missing:
        notes.append(f"feature sets not available: {', '.join(missing)}")
    acc = pd.DataFrame(columns=["real", "scene"], dtype=float)
    if accuracy_too and chosen:
        use = [s for s in schemes if s != "challenge" or ("split" in ref.meta.columns and "split" in synth.meta.columns)]
        a_real = accuracy(ref, chosen, use, n_estimators, seed=0)
        a_scene = accuracy(synth, chosen, use, n_estimators, seed=0)
        acc = pd.DataFrame({"real": a_real, "scene": a_scene})
    return Fidelity(spec.name, real_name, seed, dist, acc, chosen, n_estimators, notes)


# a method = (label, feature sets); the classifier is a random forest
METHODS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("gaus-msd+rf", ("msd",)),
    ("gaus-all+rf", GAUS_SETS),
    ("zhou+rf", ("zhou-basic", "zhou-wavelet")),
    ("flagg+rf", ("flagg-stats",)),
)


def separability(
    ds: TouchDataset,
    schemes: Sequence[str] = ("subject-kfold:5", "kfold:5"),
    methods: Sequence[tuple[str, Sequence[str]]] = METHODS,
    n_estimators: int = 100,
) -> pd.DataFrame:
    """Accuracy of each method (rows) under each scheme (columns); methods
    whose feature sets are missing or do not apply to the sensor are left
    out (the reason in column ``skipped``)."""
    rows: dict[str, dict[str, Any]] = {}
    for label, sets in methods:
        have = available_sets(sets)
        if len(have) < len(sets):
            continue
        try:
            rows[label] = accuracy(ds, have, schemes, n_estimators)
        except Exception as e:  # a feature set that does not apply to this sensor
            rows[label] = {"skipped": f"{type(e).__name__}: {e}"[:80]}
    return pd.DataFrame.from_dict(rows, orient="index")
