"""Model files hold data, not code: a crafted file is refused before anything runs, and every
method touchbench trains saves and reads back to the same predictions.

The crafted files are made here by hand: a pickle whose ``__reduce__`` would
create a marker file (what an attacker's model file does), behind a header
with a correct checksum (the checksum is no secret); a skops file naming a
type of this test module. The round trips compare the loaded model's
probabilities with the ones of the model in memory (the same numbers, not
values the format computes).
"""

from __future__ import annotations

import hashlib
import importlib.util
import io
import json
import logging
import pickle

import joblib
import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from sklearn.tree import DecisionTreeClassifier

from touchbench.classifiers.base import CLASSIFIERS
from touchbench.cli.main import cli
from touchbench.core.errors import DataError
from touchbench.core.hashing import canonical_json
from touchbench.deploy.model import TrainedModel, fit_model
from touchbench.deploy.predict import predict_dataset
from touchbench.deploy.safe_format import check_trees, dump_parts, load_parts
from touchbench.engine.testing import random_dataset
from touchbench.features.base import FEATURES
from touchbench.methods.base import MethodSpec


@pytest.fixture(scope="module")
def data():
    return random_dataset(subjects=("s1", "s2", "s3"), gestures=("pat", "rub", "stroke"), per_cell=3,
                          frames=(40, 44), seed=4)


class _Marker:
    """Unpickling it creates ``path``: what a harmful model file would do instead."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _file(body: bytes, manifest: dict, version: int) -> bytes:
    """A model file around ``body`` with a correct checksum of the format ``version``."""
    digest = hashlib.sha256(canonical_json(manifest).encode() + b"\n" + body).hexdigest()
    header = {"version": version, "sha256": digest, "size": len(body), "manifest": manifest}
    return b"touchbench-model\n" + json.dumps(header, sort_keys=True).encode() + b"\n" + body


def _crafted_pickle(tmp_path, manifest):
    marker = tmp_path / "ran"
    buf = io.BytesIO()
    joblib.dump({"feature_sets": [_Marker(marker)], "estimator": None, "classes": ["a"]}, buf)
    path = tmp_path / "crafted.joblib"
    path.write_bytes(_file(buf.getvalue(), manifest, 3))
    return path, marker


@pytest.fixture()
def saved(tmp_path, data):
    model = fit_model(data, MethodSpec("lda", (("flagg-stats", {}),), "zhou-lda"))
    return model, model.save(tmp_path / "m.joblib")


def test_a_crafted_pickle_is_refused_without_trust_and_never_runs(tmp_path, data, saved):
    model, _ = saved
    path, marker = _crafted_pickle(tmp_path, json.loads(json.dumps(model.manifest, default=str)))
    with pytest.raises(DataError, match="pickle.*--trust") as e:
        TrainedModel.load(path)
    assert str(path) in str(e.value)
    assert not marker.exists()
    data.to_parquet(tmp_path / "d.parquet")
    for args in (["predict", path, tmp_path / "d.parquet"], ["stream", path, tmp_path / "d.parquet"]):
        res = CliRunner().invoke(cli, [str(a) for a in args])
        assert res.exit_code != 0 and "--trust" in res.output and "pickle" in res.output, res.output
        assert not marker.exists()


def test_an_older_pickle_file_is_read_with_trust(tmp_path, data, saved):
    model, _ = saved
    manifest = json.loads(json.dumps(model.manifest, default=str))
    buf = io.BytesIO()
    joblib.dump({"feature_sets": model.feature_sets, "estimator": model.estimator,
                 "classes": [str(c) for c in model.classes]}, buf)
    path = tmp_path / "old.joblib"
    path.write_bytes(_file(buf.getvalue(), manifest, 3))
    with pytest.raises(DataError, match="--trust"):
        TrainedModel.load(path)
    old = TrainedModel.load(path, trust=True)
    np.testing.assert_array_equal(old.predict_proba(data.captures), model.predict_proba(data.captures))
    assert any("pickle" in n for n in old.version_notes())
    data.to_parquet(tmp_path / "d.parquet")
    res = CliRunner().invoke(cli, ["predict", str(path), str(tmp_path / "d.parquet"), "--trust"])
    assert res.exit_code == 0, res.output


def test_a_file_naming_an_unlisted_type_is_refused_by_name(tmp_path, saved):
    model, _ = saved
    manifest = json.loads(json.dumps(model.manifest, default=str))
    body = dump_parts({"feature_sets": [_Marker(tmp_path / "ran")], "estimator": None, "classes": ["a"]})
    path = tmp_path / "other.joblib"
    path.write_bytes(_file(body, manifest, 4))
    with pytest.raises(DataError, match=r"test_deploy_safe_format\._Marker.*--trust"):
        TrainedModel.load(path)
    assert not (tmp_path / "ran").exists()


def test_the_file_holds_no_pickle(saved):
    _, path = saved
    data = path.read_bytes()
    body = data[data.index(b"\n", len("touchbench-model\n")) + 1:]
    assert body[:2] == b"PK"  # a zip (skops), not a pickle stream (which starts with 0x80)
    with pytest.raises(pickle.UnpicklingError):
        pickle.loads(body)


def test_a_tree_pointing_outside_itself_is_refused():
    rng = np.random.default_rng(0)
    X, y = rng.normal(size=(40, 3)), rng.integers(0, 2, 40)
    tree = DecisionTreeClassifier(random_state=0).fit(X, y)
    assert check_trees(tree) == []
    state = tree.tree_.__getstate__()
    nodes = state["nodes"].copy()
    inner = np.flatnonzero(nodes["left_child"] != -1)
    nodes["left_child"][inner[0]] = 10_000  # a child far outside the tree's nodes
    tree.tree_.__setstate__({**state, "nodes": nodes})
    assert check_trees(tree) != []
    with pytest.raises(DataError, match="decision tree"):
        load_parts(dump_parts(tree), "t")
    tree.tree_.__setstate__({**state, "nodes": state["nodes"]})
    tree.n_features_in_ = 2  # the tree splits on 3 columns, its estimator takes 2
    assert check_trees(tree) != []


def _available(name: str) -> bool:
    """A classifier of touchbench's own (no plugin) whose optional installs are here."""
    entry = CLASSIFIERS.entry(name)
    modules = {"deep": "torch", "peers": "aeon", "xgboost": "xgboost"}
    extras = [e for e in (entry.tags.get("extra") or "").split(",") if e]
    return entry.plugin is None and all(importlib.util.find_spec(modules[e]) is not None for e in extras)


def _round_trip(tmp_path, data, spec):
    model = fit_model(data, spec)
    path = model.save(tmp_path / "m.joblib")
    loaded = TrainedModel.load(path)  # no trust: every type is on the list
    pd.testing.assert_frame_equal(predict_dataset(loaded, data), predict_dataset(model, data))
    if not model.adapts_to_session:  # a session-adapted model labels only after adapting (predict_dataset does)
        np.testing.assert_array_equal(loaded.predict_proba(data.captures, fast=False),
                                      model.predict_proba(data.captures, fast=False))


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in CLASSIFIERS.names() if _available(n)])
def test_every_classifier_round_trips(tmp_path, data, name):
    takes = CLASSIFIERS.entry(name).tags.get("input") == "captures"
    features = () if takes else (("flagg-stats", {}),)
    _round_trip(tmp_path, data, MethodSpec(name, features, name, dict(CLASSIFIERS.entry(name).tags.get("cheap_params") or {})))


FEATURE_PARAMS = {"bmh": {"preset": "haart"}, "raw-window": {"frames": 40, "shorter": "pad"}}


@pytest.mark.parametrize("name", [n for n in FEATURES.names() if FEATURES.entry(n).plugin is None])
def test_every_feature_set_round_trips(tmp_path, data, name):
    _round_trip(tmp_path, data, MethodSpec(name, ((name, FEATURE_PARAMS.get(name, {})),), "zhou-lda"))


_EVENTS: list[str] = []


class _Recorder:
    """Building it (skops gives it its attributes) records that it was built."""

    def __init__(self):
        self.n = 1

    def __setstate__(self, state):
        _EVENTS.append("built")
        self.__dict__.update(state)


class _Listener(logging.Handler):
    def emit(self, record):
        _EVENTS.append(record.getMessage())


def _untrusted_file(tmp_path, saved):
    model, _ = saved
    manifest = json.loads(json.dumps(model.manifest, default=str))
    body = dump_parts({"feature_sets": [_Recorder()], "estimator": None, "classes": ["a"]})
    path = tmp_path / "other.joblib"
    path.write_bytes(_file(body, manifest, 4))
    return path


def test_an_untrusted_file_without_trust_names_the_file_the_types_and_the_option(tmp_path, data, saved):
    path = _untrusted_file(tmp_path, saved)
    data.to_parquet(tmp_path / "d.parquet")
    _EVENTS.clear()
    res = CliRunner().invoke(cli, ["predict", str(path), str(tmp_path / "d.parquet")])
    assert res.exit_code == 3 and isinstance(res.exception, SystemExit), res.output
    assert res.output.startswith(f"error: {path}: the model file names 1 type(s) outside touchbench's trusted list: "
                                 "test_deploy_safe_format._Recorder; nothing was built")
    assert "read it with --trust" in res.output and _EVENTS == []


def test_trust_names_the_untrusted_types_before_building_them(tmp_path, saved):
    path = _untrusted_file(tmp_path, saved)
    listener = _Listener()
    logger = logging.getLogger("touchbench.deploy")
    logger.addHandler(listener)
    _EVENTS.clear()
    try:
        with pytest.raises(DataError, match="parts disagree"):  # a crafted file: its parts are not a model
            TrainedModel.load(path, trust=True)
    finally:
        logger.removeHandler(listener)
    assert _EVENTS == [f"{path}: --trust: building 1 type(s) outside touchbench's trusted list: "
                       "test_deploy_safe_format._Recorder", "built"]
