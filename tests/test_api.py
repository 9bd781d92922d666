"""The Python API: ``import touchbench`` holds the user-level names, each
loaded from its module on first use (PEP 562), so the import itself stays
cheap."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import touchbench
from touchbench.features.base import SensorNeededError

PACKAGE = Path(touchbench.__file__).resolve().parent

# Every user-level name and the module that defines it, written out here.
EXPECTED = {
    "load_dataset": "touchbench.catalog",
    "TouchDataset": "touchbench.datasets.model", "SensorSpec": "touchbench.datasets.model",
    "DATASETS": "touchbench.datasets.registry",
    "generate_scene": "touchbench.scenes", "SCENES": "touchbench.scenes",
    "FEATURES": "touchbench.features.base", "FeatureSet": "touchbench.features.base",
    "make_feature_set": "touchbench.features.base", "SensorNeededError": "touchbench.features.base",
    "CLASSIFIERS": "touchbench.classifiers.base", "make_classifier": "touchbench.classifiers.base",
    "METHODS": "touchbench.methods.base", "MethodSpec": "touchbench.methods.base",
    "method_spec": "touchbench.methods.base", "FeaturePipeline": "touchbench.methods.pipeline",
    "SPLITTERS": "touchbench.protocols.schemes", "make_splitter": "touchbench.protocols.schemes",
    "Fold": "touchbench.protocols.schemes",
    "Protocol": "touchbench.protocols.schema", "load_protocol": "touchbench.protocols.loading",
    "parse_protocol": "touchbench.protocols.loading", "find_protocol": "touchbench.protocols.library",
    "run_protocol": "touchbench.engine.runner", "RunResult": "touchbench.engine.runner",
    "leaderboard": "touchbench.reports.leaderboard", "Leaderboard": "touchbench.reports.leaderboard",
    "build_leaderboards": "touchbench.reports.leaderboard", "compare_methods": "touchbench.reports.compare",
    "load_results": "touchbench.reports.results",
    "fit_model": "touchbench.deploy.model", "TrainedModel": "touchbench.deploy.model",
    "TouchbenchError": "touchbench.core.errors", "DataError": "touchbench.core.errors",
}


def test_dir_and_all_list_the_user_level_names():
    assert sorted(dir(touchbench)) == sorted(touchbench.__all__) == sorted([*EXPECTED, "__version__"])


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_name_is_the_object_its_module_defines(name):
    assert getattr(touchbench, name) is getattr(importlib.import_module(EXPECTED[name]), name)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="module 'touchbench' has no attribute 'load_datasets'"):
        touchbench.load_datasets  # noqa: B018
    assert not hasattr(touchbench, "load_datasets")


def test_star_import_gives_every_name():
    ns: dict = {}
    exec("from touchbench import *", ns)  # noqa: S102
    assert set(EXPECTED) | {"__version__"} <= set(ns)


def test_type_checkers_see_the_same_names():
    """The ``if TYPE_CHECKING:`` imports of touchbench/__init__.py (what editors and type checkers
    read) name the same objects, from the same modules."""
    tree = ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    (block,) = [n for n in tree.body if isinstance(n, ast.If) and getattr(n.test, "id", "") == "TYPE_CHECKING"]
    seen = {a.name: f"touchbench.{node.module}" for node in block.body for a in node.names}
    assert seen == EXPECTED


def test_importing_touchbench_imports_no_numerical_library():
    code = ("import sys, touchbench; "
            "print(sorted(m for m in ('numpy', 'scipy', 'sklearn', 'pandas', 'pyarrow', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_py_typed_marks_the_package_typed():
    assert (PACKAGE / "py.typed").is_file()


@pytest.mark.parametrize("name", ["touch-rhythm", "cell-rhythm", "contact-motion"])
def test_a_rate_dependent_set_from_python_needs_the_sensor(name):
    """Frequencies in Hz need the frame rate: without a sensor (or frame_rate) the set refuses;
    with one it computes what the explicit frame rate gives, and not what another rate gives."""
    rng = np.random.default_rng(0)
    captures = [rng.integers(0, 256, size=(60, 4, 5)).astype(np.uint8) for _ in range(3)]
    with pytest.raises(SensorNeededError, match=r"pass sensor=SensorSpec\(\.\.\.\) or "):
        touchbench.make_feature_set(name).fit_transform(captures)
    with pytest.raises(SensorNeededError, match=r"frame rate.*pass sensor=SensorSpec\(\.\.\.\) or frame_rate="):
        touchbench.make_feature_set(name, {"value_range": (0, 255)}).fit_transform(captures)
    sensor = touchbench.SensorSpec("skin", grid=(4, 5), frame_rate=20.0, value_range=(0, 255))
    out = touchbench.make_feature_set(name, sensor=sensor).fit_transform(captures)
    same = touchbench.make_feature_set(name, {"frame_rate": 20.0, "value_range": (0, 255)}).fit_transform(captures)
    other = touchbench.make_feature_set(name, {"frame_rate": 54.0, "value_range": (0, 255)}).fit_transform(captures)
    assert np.array_equal(out, same) and not np.array_equal(out, other)
