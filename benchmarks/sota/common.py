"""Shared helpers for the Phase-1 SOTA exploration scripts (benchmarks only)."""
from __future__ import annotations
import numpy as np
from touchbench.catalog import load_dataset

_CACHE = {}

def data(name="haart"):
    if name not in _CACHE:
        ds = load_dataset(name)
        X = np.stack(ds.captures).astype(np.float64)  # (N, T, 8, 8)
        _CACHE[name] = (ds, X, ds.meta.reset_index(drop=True))
    return _CACHE[name]

def challenge_split(meta):
    tr = np.flatnonzero(meta.split.to_numpy() == "train")
    te = np.flatnonzero(meta.split.to_numpy() == "test")
    return tr, te

def loso(meta):
    s = meta.subject.to_numpy()
    return [(sub, np.flatnonzero(s != sub), np.flatnonzero(s == sub)) for sub in sorted(set(s))]

def inner_loso(meta, idx):
    """Leave-one-training-subject-out folds inside `idx` (positions)."""
    s = meta.subject.to_numpy()[idx]
    return [(sub, idx[s != sub], idx[s == sub]) for sub in sorted(set(s))]


OWN_SETS = ["touch-rhythm", "cell-rhythm", "contact-motion"]


def cached_inner(ds_name):
    """Features cached by cache_feats_pkg.py, labels, and the inner folds of the challenge's training subjects.

    Returns (meta, F dict, y codes, training positions, folds as (subject, train, test) positions).
    """
    import pandas as pd
    from sklearn.preprocessing import LabelEncoder

    meta = pd.read_parquet(f"/tmp/exp/{ds_name}-meta.parquet")
    F = dict(np.load(f"/tmp/exp/{ds_name}-feats.npz"))
    y = LabelEncoder().fit_transform(meta.gesture.astype(str))
    tr = np.flatnonzero(meta.split.astype(str).to_numpy() == "train")
    return meta, F, y, tr, inner_loso(meta, tr)


def own_features(ds, caps):
    """touchbench's three own feature sets of ``caps`` (N, T, H, W), concatenated."""
    from touchbench.features.base import FEATURES

    return np.hstack([FEATURES.create(n, sensor=ds.sensor).fit(caps[:2]).transform(caps) for n in OWN_SETS])


def inner_setup(ds_name):
    """(dataset, captures array, meta, cached features, y, training positions, inner folds, own-set matrix)."""
    ds = load_dataset(ds_name)
    meta, F, y, tr, folds = cached_inner(ds_name)
    return ds, np.stack(ds.captures), meta, F, y, tr, folds, np.hstack([F[n] for n in OWN_SETS])
