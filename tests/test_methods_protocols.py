"""Protocols name methods: the ``methods:`` block, named methods beside ``[raw-window]``,
the feature cache serving a named method, and ``train`` fitting the same method."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.features.base import make_feature_set
from touchbench.methods import FeaturePipeline, method_spec
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol

SENSOR = SensorSpec("test-6x6", (6, 6), 20.0, (0.0, 255.0))

SHORTHAND = """\
name: m
dataset: {data}
scheme: loso
features:
  - [{{name: raw-window, params: {{frames: 24}}}}]
classifiers:
  - {{name: touch-et-fast, params: {{n_estimators: 15}}}}
seed: 3
"""

METHODS = """\
name: m
dataset: {data}
scheme: loso
methods:
  - {{name: touch-et-fast, params: {{n_estimators: 15}}}}
  - {{features: [msd, flagg-stats], estimator: zhou-lda, label: two-sets-lda}}
seed: 3
"""


@pytest.fixture()
def data(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    ds = random_dataset(subjects=("s1", "s2", "s3"), per_cell=3, frames=(24, 24), sensor=SENSOR, name="six")
    ds = TouchDataset(ds.name, [np.clip(c, 0, 255).astype(np.uint8) for c in ds.captures], ds.meta, ds.sensor)
    return ds.to_parquet(tmp_path / "six.parquet")


def _run(text, tmp_path, name):
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    return run_protocol(path, out=tmp_path / name, cache_root=tmp_path / "features", jobs=1, progress=False)


def _preds(res):
    return pd.read_parquet(res.out / "predictions.parquet")


def test_a_named_method_in_methods_equals_it_beside_raw_window(data, tmp_path):
    a = _run(SHORTHAND.format(data=data), tmp_path, "shorthand")
    b = _run(METHODS.format(data=data), tmp_path, "methods")
    assert (a.scores["status"] == "ok").all() and (b.scores["status"] == "ok").all()
    key = ["fold", "capture_id"]
    pa = _preds(a).sort_values(key).reset_index(drop=True)
    pb = _preds(b)
    pb = pb[pb["classifier"] == "touch-et-fast"].sort_values(key).reset_index(drop=True)
    assert pa["predicted_label"].tolist() == pb["predicted_label"].tolist()  # same method, same seeds
    assert sorted(b.scores["classifier"].unique()) == ["touch-et-fast", "two-sets-lda"]


def test_a_named_method_is_the_pipeline_fitted_by_hand(data, tmp_path):
    """One fold of the run equals touch-rhythm computed through the registry -> the estimator,
    fitted with the task's seed on that fold's training captures."""
    res = _run(SHORTHAND.format(data=data), tmp_path, "one")
    ds = TouchDataset.from_parquet(data)
    row = res.scores.iloc[0]
    test_subject = row["fold"].split("=")[-1]
    subj = ds.meta["subject"].astype(str).to_numpy()
    tr, te = np.flatnonzero(subj != test_subject), np.flatnonzero(subj == test_subject)
    y = ds.meta["gesture"].astype(str).to_numpy()
    pipe = FeaturePipeline(method_spec("touch-et-fast", n_estimators=15), random_state=int(row["seed"]), sensor=SENSOR)
    pipe.fit([ds.captures[i] for i in tr], y[tr])
    want = pd.Series(pipe.predict([ds.captures[i] for i in te]), index=ds.meta["capture_id"].to_numpy()[te])
    preds = _preds(res)
    got = preds[preds["fold"] == row["fold"]].set_index("capture_id")["predicted_label"]
    assert got.loc[want.index].tolist() == want.tolist()


def test_the_feature_cache_serves_a_named_method(data, tmp_path):
    _run(SHORTHAND.format(data=data), tmp_path, "cache")
    names = [json.loads(p.read_text())["name"] for p in (tmp_path / "features").glob("*.json")]
    # the method's own set is computed once per dataset; the frames beside it are not materialised
    assert names == ["touch-rhythm"]


@pytest.mark.parametrize("text, message", [
    ("methods:\n  - {name: touch-et, estimator: zhou-lda, features: [msd]}\n",
     "x.yaml:6: methods[0]: a method entry is either a registered method"),
    ("methods:\n  - touch-ett\n", "x.yaml:6: methods[0].name: unknown method 'touch-ett'; did you mean 'touch-et'"),
    ("methods:\n  - {name: touch-et, params: {n_estimator: 3}}\n",
     "x.yaml:6: methods[0].params.n_estimator: unknown parameter 'n_estimator' for method 'touch-et'"),
    ("features:\n  - [msd]\n", "x.yaml:1: classifiers: features and classifiers go together"),
    ("seed: 1\n", "x.yaml:1: methods: a protocol needs methods:, or features and classifiers"),
])
def test_bad_methods_are_refused_with_the_line(text, message):
    with pytest.raises(ProtocolError) as e:
        parse_protocol("name: m\ndataset: scene:tiny\nscheme: loso\ntarget: gesture\n" + text, "x.yaml")
    assert str(e.value).startswith(message), str(e.value)


def test_a_method_beside_a_feature_set_that_is_not_raw_window_is_refused(data, tmp_path):
    text = SHORTHAND.format(data=data).replace("[{name: raw-window, params: {frames: 24}}]", "[msd]")
    with pytest.raises(ProtocolError, match="computes its own feature sets .*pair it with the feature combination"):
        _run(text, tmp_path, "bad")


def test_features_of_a_named_method_use_the_sensor_of_the_data():
    spec = method_spec("touch-et-fast")
    fs = make_feature_set(*spec.feature_sets[0], SENSOR)
    assert fs.sensor is SENSOR


CAPTURES_PROTOCOL = """\
name: c
dataset: {data}
scheme: loso
features:
  - [{{name: raw-window, params: {{frames: 24}}}}]
classifiers:
  - {{name: minirocket, params: {{n_kernels: 84}}}}
seed: 5
"""


def test_an_estimator_that_takes_captures_gets_them_as_recorded(data, tmp_path, monkeypatch):
    """Beside [raw-window], the peers (and the CNN) receive the fold's captures in their native
    dtype, not a float64 matrix; they give the same predictions as on raw-window's rows."""
    from touchbench.classifiers import make_classifier
    from touchbench.classifiers.peers import MiniRocketPeer
    seen = []
    original = MiniRocketPeer.fit
    monkeypatch.setattr(MiniRocketPeer, "fit", lambda self, X, y: seen.append(X) or original(self, X, y))
    res = _run(CAPTURES_PROTOCOL.format(data=data), tmp_path, "captures")
    assert (res.scores["status"] == "ok").all()
    assert seen and all(isinstance(X, list) and X[0].dtype == np.uint8 and X[0].shape == (24, 6, 6) for X in seen)
    assert not list((tmp_path / "features").glob("*.json"))  # no raw-window matrix was materialised
    # one fold by hand, on raw-window's flattened rows
    ds = TouchDataset.from_parquet(data)
    row = res.scores.iloc[0]
    subj = ds.meta["subject"].astype(str).to_numpy()
    tr, te = np.flatnonzero(subj != row["fold"].split("=")[-1]), np.flatnonzero(subj == row["fold"].split("=")[-1])
    rows = make_feature_set("raw-window", {"frames": 24}, SENSOR).fit_transform(ds.captures)
    y = ds.meta["gesture"].astype(str).to_numpy()
    classes = sorted(set(y[tr]))
    codes = np.array([classes.index(v) for v in y[tr]])
    est = make_classifier("minirocket", random_state=int(row["seed"]), sensor=SENSOR, n_kernels=84).fit(rows[tr], codes)
    want = np.array(classes)[est.predict(rows[te]).astype(int)]
    preds = _preds(res)
    got = preds[preds["fold"] == row["fold"]].set_index("capture_id").loc[ds.meta["capture_id"].to_numpy()[te], "predicted_label"]
    assert got.tolist() == want.tolist()


@pytest.mark.parametrize("method", ["touch-rhythm/touch-et-fast", "minirocket"])
def test_train_fits_the_same_method_as_the_run(data, tmp_path, method):
    """``train --fold F`` fits the method the run evaluated (a named method, named by its features
    and label; an estimator that takes captures, named in methods: and by its label alone) and
    labels that fold's test captures as the run did."""
    from touchbench.deploy.train import train_from_protocol

    text = METHODS.format(data=data).replace(
        "  - {features: [msd, flagg-stats], estimator: zhou-lda, label: two-sets-lda}\n",
        "  - {name: minirocket, params: {n_kernels: 84}}\n")
    res = _run(text, tmp_path, "trained")
    ds = TouchDataset.from_parquet(data)
    preds = _preds(res)
    preds = preds[(preds["fold"] == "subject=s2") & (preds["classifier"] == method.split("/")[-1])]
    model = train_from_protocol(tmp_path / "trained.yaml", method, fold="s2")
    test = ds.meta["subject"].astype(str).to_numpy() == "s2"
    got = model.predict([c for c, t in zip(ds.captures, test) if t])
    want = preds.set_index("capture_id").loc[ds.meta["capture_id"].to_numpy()[test], "predicted_label"]
    assert got.tolist() == want.tolist()
