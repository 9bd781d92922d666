"""Stale results are never reused: a task id covers the data and the code.

A user's components live in modules written into the test's folder (a
feature set, an estimator, a factory, and a chain of helpers the estimator
imports); each test edits one thing (the dataset file in place, a module's
source), reloads, runs again and checks which tasks were recomputed and
which were reused. Also: damaged feature-cache entries are rebuilt, and the
manifest lists the package versions that entered the task ids.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import sys
import textwrap
import types
from importlib import metadata
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import touchbench
from touchbench.classifiers import CLASSIFIERS
from touchbench.core.versions import package_versions
from touchbench.datasets.model import DatasetChangedWarning, TouchDataset
from touchbench.engine.cache import FeatureCache
from touchbench.engine.identity import classifier_identity, feature_set_identity
from touchbench.engine.planning import plan_run
from touchbench.engine.runner import run_plan
from touchbench.engine.testing import random_dataset
from touchbench.features import FEATURES
from touchbench.protocols.loading import parse_protocol

SOURCES = {
    "tb_user_deep": """
        OFFSET = 0.0
    """,
    "tb_user_helper": """
        from tb_user_deep import OFFSET


        def shift(X):
            return X + OFFSET
    """,
    "tb_user_estimators": """
        import numpy as np
        from sklearn.base import BaseEstimator, ClassifierMixin

        import tb_user_helper


        class Centroid(ClassifierMixin, BaseEstimator):
            def __init__(self, random_state=None):
                self.random_state = random_state

            def fit(self, X, y):
                self.classes_ = np.unique(y)
                self.centroids_ = np.vstack([X[y == c].mean(axis=0) for c in self.classes_])
                return self

            def predict(self, X):
                X = tb_user_helper.shift(np.asarray(X, dtype=np.float64))
                d = ((X[:, None, :] - self.centroids_[None]) ** 2).sum(axis=2)
                return self.classes_[np.argmin(d, axis=1)]
    """,
    "tb_user_models": """
        from tb_user_estimators import Centroid


        def make_centroid(random_state=None):
            return Centroid(random_state=random_state)
    """,
    "tb_user_features": """
        import numpy as np

        from touchbench.features.base import FeatureSet

        SCALE = 1.0


        class UserMean(FeatureSet):
            paper = "test only"
            cost = "cheap"
            fold_dependent = False

            def __init__(self, sensor=None):
                self.sensor = sensor

            def _transform_one(self, capture):
                return SCALE * capture.astype(np.float64).mean(axis=0).reshape(-1)

            def feature_names(self, grid):
                return [f"user_r{r}c{c}" for r in range(grid[0]) for c in range(grid[1])]
    """,
}
ORDER = ["tb_user_deep", "tb_user_helper", "tb_user_estimators", "tb_user_models", "tb_user_features"]

PROTOCOL = """\
name: identity
dataset: {data}
scheme: loso
features:
  - [user-mean]
  - [test-mean]
classifiers:
  - user-centroid
  - test-logreg
seed: 3
"""


class UserComponents:
    """The user's modules in ``folder``: written, imported, registered; edited and reloaded."""

    def __init__(self, folder: Path):
        self.folder = folder
        folder.mkdir()
        for name in ORDER:
            self.write(name, SOURCES[name])
        sys.path.insert(0, str(folder))
        self.modules = {name: importlib.import_module(name) for name in ORDER}
        self.register()

    def write(self, name: str, source: str) -> None:
        (self.folder / f"{name}.py").write_text(textwrap.dedent(source))

    def edit(self, name: str, old: str, new: str) -> None:
        path = self.folder / f"{name}.py"
        text = path.read_text()
        assert old in text
        path.write_text(text.replace(old, new))
        self.unregister()
        for n in ORDER:  # dependencies first, as a fresh process would import them
            self.modules[n] = importlib.reload(self.modules[n])
        self.register()

    def register(self) -> None:
        FEATURES.register("user-mean", description="a user's mean of every cell")(self.modules["tb_user_features"].UserMean)
        CLASSIFIERS.register("user-centroid", description="a user's nearest centroid")(self.modules["tb_user_models"].make_centroid)

    def unregister(self) -> None:
        FEATURES._entries.pop("user-mean", None)
        CLASSIFIERS._entries.pop("user-centroid", None)

    def close(self) -> None:
        self.unregister()
        sys.path.remove(str(self.folder))
        for name in ORDER:
            sys.modules.pop(name, None)


@pytest.fixture
def user(engine_env, tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "dont_write_bytecode", True)  # a reload must read the edited source
    comps = UserComponents(tmp_path / "user")
    yield comps
    comps.close()


def dataset() -> TouchDataset:
    return random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=5)


def make_protocol(tmp_path: Path, ds: TouchDataset | None = None):
    data = tmp_path / "data.parquet"
    if not data.exists():
        (ds or dataset()).to_parquet(data)
    return parse_protocol(PROTOCOL.format(data=data), tmp_path / "identity.yaml")


def run(tmp_path: Path, out: str = "out", **kw):
    """``(result, {task_id: (features, classifier, fold)}, plan)`` of one run."""
    plan = plan_run(make_protocol(tmp_path))
    res = run_plan(plan, tmp_path / out, progress=False, **kw)
    return res, {t.task_id: (t.method.features_label, t.method.label, t.fold.name) for t in plan.tasks}, plan


def finished_at(tmp_path: Path, out: str = "out") -> dict[str, str]:
    scores = pd.read_parquet(tmp_path / out / "scores.parquet")
    return dict(zip(scores["task_id"], scores["finished_at"]))


def cache_entries(tmp_path: Path) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted((tmp_path / "cache" / "features").glob("*.json"))]


def check_recomputed(tmp_path, before, after, res, affected) -> None:
    """Exactly the tasks ``affected(features, classifier)`` got new ids and ran; the others were reused."""
    old_ids, new_ids = set(before[1]), set(after[1])
    expected_new = {tid for tid, (f, c, _) in after[1].items() if affected(f, c)}
    assert new_ids - old_ids == expected_new and len(expected_new) == 6
    kept = new_ids & old_ids
    assert {after[1][t] for t in kept} == {v for v in before[1].values() if not affected(v[0], v[1])}
    assert res.n_ran == 6 and res.n_skipped == 6 and not res.noop
    stamps_before, stamps_after = before[2], finished_at(tmp_path)
    assert all(stamps_after[t] == stamps_before[t] for t in kept)  # reused, not recomputed
    assert all(t not in stamps_before for t in expected_new)


def first_run(tmp_path):
    res, ids, plan = run(tmp_path)
    assert res.n_tasks == 3 * 2 * 2 == res.n_ran and (res.scores["status"] == "ok").all()
    again, ids2, _ = run(tmp_path)
    assert again.noop and ids2 == ids  # nothing changed: nothing to do
    return res, ids, finished_at(tmp_path)


def test_editing_a_feature_sets_source_recomputes_its_tasks_only(user, tmp_path):
    before = first_run(tmp_path)
    n_entries = len(cache_entries(tmp_path))
    user.edit("tb_user_features", "SCALE = 1.0", "SCALE = 2.0")
    res, ids, _ = run(tmp_path)
    check_recomputed(tmp_path, before, (res, ids), res, lambda f, c: f == "user-mean")
    entries = cache_entries(tmp_path)
    assert len(entries) == n_entries + 1  # the new source's features, computed once
    assert run(tmp_path)[0].noop


def test_editing_an_estimators_source_recomputes_its_tasks_only(user, tmp_path):
    before = first_run(tmp_path)
    n_entries = len(cache_entries(tmp_path))
    user.edit("tb_user_estimators", "** 2).sum(axis=2)", "** 2).sum(axis=2) * 1.0")
    res, ids, _ = run(tmp_path)
    check_recomputed(tmp_path, before, (res, ids), res, lambda f, c: c == "user-centroid")
    assert len(cache_entries(tmp_path)) == n_entries  # the features did not change


def test_editing_a_helper_two_imports_down_recomputes_the_estimators_tasks(user, tmp_path):
    before = first_run(tmp_path)
    user.edit("tb_user_deep", "OFFSET = 0.0", "OFFSET = 0.5")
    res, ids, _ = run(tmp_path)
    check_recomputed(tmp_path, before, (res, ids), res, lambda f, c: c == "user-centroid")


def test_a_dataset_edited_in_place_is_new_data(user, tmp_path):
    old_ids = set(first_run(tmp_path)[1])
    data = tmp_path / "data.parquet"
    original = dataset()
    # edit one capture's frames in the file, keeping the hash stored when it was written
    table = pq.read_table(data)
    frames = table.column("frames").to_pylist()
    edited_first = np.frombuffer(frames[0], dtype=np.uint8).copy()
    edited_first[:] = 255 - edited_first
    frames[0] = edited_first.tobytes()
    table = table.set_column(table.column_names.index("frames"), "frames", pa.array(frames, type=pa.large_binary()))
    pq.write_table(table, data)
    edited = TouchDataset(original.name, [edited_first.reshape(original.captures[0].shape)] + original.captures[1:],
                          original.meta, original.sensor)
    assert edited.content_hash != original.content_hash

    with pytest.warns(DatasetChangedWarning, match="changed since"):
        assert TouchDataset.from_parquet(data).content_hash == edited.content_hash
    res, ids, plan = run(tmp_path)
    assert set(ids).isdisjoint(old_ids) and res.n_ran == 12 and res.n_skipped == 0  # every task reads the data
    assert plan.dataset.content_hash == edited.content_hash
    assert (res.scores["dataset_hash"] == edited.content_hash).all()
    assert any("changed since" in n for n in res.notes)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert any("changed since" in n for n in manifest["notes"])
    # the features were computed from the edited frames, not reused from the old content
    cache = FeatureCache(tmp_path / "cache" / "features")
    for info in cache_entries(tmp_path):
        if info["dataset_hash"] == edited.content_hash and info["name"] == "test-mean":
            key = FeatureCache.key(edited.content_hash, "test-mean", {}, feature_set_identity("test-mean").digest, None)
            X, _ = cache.load(key)
            np.testing.assert_allclose(X[0], edited_first.reshape(-1, 16).mean(axis=0))
            break
    else:
        pytest.fail("no feature-cache entry for the edited dataset")
    # --force on the edited file recomputes with the same (new) identities
    forced, ids_forced, _ = run(tmp_path, force=True)
    assert ids_forced == ids and forced.n_ran == 12


@pytest.mark.parametrize("damage", ["truncate", "flip"])
def test_a_damaged_feature_cache_entry_is_rebuilt(engine_env, tmp_path, damage):
    ds = dataset()
    ds.to_parquet(tmp_path / "data.parquet")
    protocol = parse_protocol(PROTOCOL.format(data=tmp_path / "data.parquet")
                              .replace("  - [user-mean]\n", "").replace("  - user-centroid\n", ""), tmp_path / "p.yaml")
    run_plan(plan_run(protocol), tmp_path / "a", progress=False)
    (npy,) = (tmp_path / "cache" / "features").glob("*.npy")
    data = npy.read_bytes()
    if damage == "truncate":
        npy.write_bytes(data[: len(data) // 2])
    else:  # same size, last value changed
        npy.write_bytes(data[:-8] + np.float64(-1.0).tobytes())
    key = npy.stem
    cache = FeatureCache(tmp_path / "cache" / "features")
    assert cache.load(key) is None and cache.problem(key) not in (None, "missing")
    res = run_plan(plan_run(protocol), tmp_path / "b", progress=False)  # a second results folder: tasks pending
    assert res.n_ran == 3 and (res.scores["status"] == "ok").all()
    assert any("cached features of test-mean were not used" in n for n in res.notes)
    X, _ = cache.load(key)
    expected = np.vstack([c.astype(np.float64).mean(axis=0).reshape(-1) for c in ds.captures])
    np.testing.assert_allclose(X, expected)
    assert npy.read_bytes() == data


def test_the_manifest_lists_the_versions_in_the_task_ids(user, tmp_path):
    run(tmp_path)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    packages = manifest["identity"]["packages"]
    # the components import numpy and scikit-learn (which requires SciPy); nothing imports torch or xgboost
    assert packages["numpy"] == metadata.version("numpy")
    assert packages["scikit-learn"] == metadata.version("scikit-learn")
    assert packages["scipy"] == metadata.version("scipy")
    assert packages["touchbench"] == touchbench.__version__
    assert packages["python"] == ".".join(map(str, sys.version_info[:3]))
    assert not {"torch", "xgboost", "xgboost-cpu", "aeon"} & set(packages)
    modules = manifest["identity"]["components"]
    assert {"tb_user_models", "tb_user_estimators", "tb_user_helper", "tb_user_deep"} <= set(modules["classifier user-centroid"]["modules"])
    assert "tb_user_features" in modules["feature set user-mean"]["modules"]
    assert "touchbench.features.base" in modules["feature set user-mean"]["modules"]


def test_package_versions_of_modules_follow_requirements():
    got = package_versions(modules=["sklearn", "no_such_module_anywhere"])
    assert got["scikit-learn"] == metadata.version("scikit-learn")
    assert got["scipy"] == metadata.version("scipy") and got["numpy"] == metadata.version("numpy")
    assert "pandas" not in got  # scikit-learn does not require it
    assert package_versions(modules=[]) == {"touchbench": touchbench.__version__, "python": got["python"]}


def test_a_classifier_identity_covers_the_estimator_its_factory_builds(user, tmp_path):
    # a factory that finds its estimator class by name, without an import statement
    user.write("tb_user_dynamic", """
        import importlib


        def make(random_state=None):
            return getattr(importlib.import_module("tb_user_hidden"), "Hidden")()
    """)
    user.write("tb_user_hidden", """
        from sklearn.base import BaseEstimator, ClassifierMixin


        class Hidden(ClassifierMixin, BaseEstimator):
            pass
    """)
    try:
        CLASSIFIERS.register("user-dynamic", description="built by name")(importlib.import_module("tb_user_dynamic").make)
        first = classifier_identity("user-dynamic")
        assert {"tb_user_dynamic", "tb_user_hidden"} <= set(first.modules)
        (user.folder / "tb_user_hidden.py").write_text((user.folder / "tb_user_hidden.py").read_text() + "# edited\n")
        assert classifier_identity("user-dynamic").digest != first.digest
    finally:
        CLASSIFIERS._entries.pop("user-dynamic", None)
        sys.modules.pop("tb_user_dynamic", None)
        sys.modules.pop("tb_user_hidden", None)


def test_a_classifier_identity_covers_the_feature_sets_it_names():
    # a classifier whose parameters name a registered feature set: that set's source counts too
    named = classifier_identity("gaus-rf", {"criterion": "touch-rhythm"})
    assert "touchbench.features.touch" in named.modules
    assert "touchbench.features.touch" not in classifier_identity("gaus-rf").modules


def test_a_component_defined_without_a_source_file_is_identified_by_its_code():
    # as in a notebook: the module lives in memory only
    source = textwrap.dedent("""
        from sklearn.base import BaseEstimator, ClassifierMixin

        K = 2


        class Scaled(ClassifierMixin, BaseEstimator):
            def __init__(self, random_state=None):
                self.random_state = random_state

            def predict(self, X):
                return X * K


        def make(random_state=None):
            return Scaled(random_state)
    """)

    def define(src: str):
        module = types.ModuleType("tb_notebook")
        sys.modules["tb_notebook"] = module
        exec(src, module.__dict__)
        CLASSIFIERS._entries.pop("user-notebook", None)
        CLASSIFIERS.register("user-notebook", description="defined in memory")(module.make)
        return classifier_identity("user-notebook")

    try:
        first = define(source)
        assert {"tb_notebook:Scaled", "tb_notebook:make"} <= set(first.modules)
        assert define(source).digest == first.digest  # the same code again
        assert define(source.replace("X * K", "X + K")).digest != first.digest
        assert define(source.replace("K = 2", "K = 3")).digest != first.digest
    finally:
        CLASSIFIERS._entries.pop("user-notebook", None)
        sys.modules.pop("tb_notebook", None)


def test_compiled_loops_imported_by_name_count_in_the_identity():
    # kernels("features.gaus_kernels") imports its module on first use, by name: the identity
    # follows it (and numba behind it) as it follows an import statement
    import ast

    from touchbench.engine.identity import _kernels_module

    call = ast.parse('kern = compiled.kernels("features.gaus_kernels")').body[0].value
    assert _kernels_module(call) == "touchbench.features.gaus_kernels"
    assert _kernels_module(ast.parse('kernels(name)').body[0].value) is None
    assert _kernels_module(ast.parse('other("features.gaus_kernels")').body[0].value) is None
    for name, module in [("msd", "gaus_kernels"), ("touch-rhythm", "touch_kernels"), ("touch-rhythm", "series_kernels"),
                         ("contact-motion", "motion_kernels"), ("contact-evidence", "evidence_kernels"),
                         ("cell-rhythm", "cell_kernels")]:
        ident = feature_set_identity(name)
        assert f"touchbench.features.{module}" in ident.modules, name
        assert ("numba" in ident.packages) == (importlib.util.find_spec("numba") is not None), name
