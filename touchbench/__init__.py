"""touchbench: benchmarking social touch gesture recognition.

The names a Python user needs are importable from here; each is loaded on
first use (PEP 562), so ``import touchbench`` itself imports neither NumPy
nor scikit-learn and the command line starts fast.

- Data: `load_dataset` (a registered name such as ``"haart-sample"``,
  ``"scene:NAME"`` or a Parquet file), `TouchDataset`, `SensorSpec`,
  `DATASETS`, `generate_scene`, `SCENES`.
- Components: `FEATURES`, `FeatureSet`, `make_feature_set`,
  `CLASSIFIERS`, `make_classifier`, `METHODS`, `method_spec`,
  `MethodSpec`, `FeaturePipeline`.
- Evaluation: `SPLITTERS`, `make_splitter`, `Fold`, `load_protocol`,
  `parse_protocol`, `find_protocol`, `Protocol`, `run_protocol`,
  `RunResult`.
- Reports: `leaderboard`, `load_results`, `build_leaderboards`,
  `compare_methods`, `Leaderboard`.
- Models: `fit_model`, `TrainedModel`.
- Errors: `TouchbenchError` (every error meant for the user),
  `DataError`, `SensorNeededError`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .core.version import __version__

# name -> the module that defines it; loaded on first attribute access.
_LAZY: dict[str, str] = {
    "load_dataset": "touchbench.catalog",
    "SensorSpec": "touchbench.datasets.model",
    "TouchDataset": "touchbench.datasets.model",
    "DATASETS": "touchbench.datasets.registry",
    "generate_scene": "touchbench.scenes",
    "SCENES": "touchbench.scenes",
    "FEATURES": "touchbench.features.base",
    "FeatureSet": "touchbench.features.base",
    "make_feature_set": "touchbench.features.base",
    "SensorNeededError": "touchbench.features.base",
    "CLASSIFIERS": "touchbench.classifiers.base",
    "make_classifier": "touchbench.classifiers.base",
    "METHODS": "touchbench.methods.base",
    "MethodSpec": "touchbench.methods.base",
    "method_spec": "touchbench.methods.base",
    "FeaturePipeline": "touchbench.methods.pipeline",
    "SPLITTERS": "touchbench.protocols.schemes",
    "Fold": "touchbench.protocols.schemes",
    "make_splitter": "touchbench.protocols.schemes",
    "Protocol": "touchbench.protocols.schema",
    "load_protocol": "touchbench.protocols.loading",
    "parse_protocol": "touchbench.protocols.loading",
    "find_protocol": "touchbench.protocols.library",
    "run_protocol": "touchbench.engine.runner",
    "RunResult": "touchbench.engine.runner",
    "load_results": "touchbench.reports.results",
    "Leaderboard": "touchbench.reports.leaderboard",
    "build_leaderboards": "touchbench.reports.leaderboard",
    "compare_methods": "touchbench.reports.compare",
    "leaderboard": "touchbench.reports.leaderboard",
    "TrainedModel": "touchbench.deploy.model",
    "fit_model": "touchbench.deploy.model",
    "TouchbenchError": "touchbench.core.errors",
    "DataError": "touchbench.core.errors",
}

__all__ = [
    "CLASSIFIERS",
    "DATASETS",
    "FEATURES",
    "METHODS",
    "SCENES",
    "SPLITTERS",
    "DataError",
    "FeaturePipeline",
    "FeatureSet",
    "Fold",
    "Leaderboard",
    "MethodSpec",
    "Protocol",
    "RunResult",
    "SensorNeededError",
    "SensorSpec",
    "TouchDataset",
    "TouchbenchError",
    "TrainedModel",
    "__version__",
    "build_leaderboards",
    "compare_methods",
    "find_protocol",
    "fit_model",
    "generate_scene",
    "leaderboard",
    "load_dataset",
    "load_protocol",
    "load_results",
    "make_classifier",
    "make_feature_set",
    "make_splitter",
    "method_spec",
    "parse_protocol",
    "run_protocol",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'touchbench' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; at run time the names come from __getattr__
    from .catalog import load_dataset
    from .classifiers.base import CLASSIFIERS, make_classifier
    from .core.errors import DataError, TouchbenchError
    from .datasets.model import SensorSpec, TouchDataset
    from .datasets.registry import DATASETS
    from .deploy.model import TrainedModel, fit_model
    from .engine.runner import RunResult, run_protocol
    from .features.base import FEATURES, FeatureSet, SensorNeededError, make_feature_set
    from .methods.base import METHODS, MethodSpec, method_spec
    from .methods.pipeline import FeaturePipeline
    from .protocols.library import find_protocol
    from .protocols.loading import load_protocol, parse_protocol
    from .protocols.schema import Protocol
    from .protocols.schemes import SPLITTERS, Fold, make_splitter
    from .reports.compare import compare_methods
    from .reports.leaderboard import Leaderboard, build_leaderboards, leaderboard
    from .reports.results import load_results
    from .scenes import SCENES, generate_scene
