"""The classifier registry.

Each entry is a factory ``f(random_state=None, **params) -> estimator``
registered with ``description`` (one line), ``source`` (paper and section)
and ``defaults`` (the paper's settings, as a dict). The estimators are plain
scikit-learn estimators (or follow that API), so users can use them in their
own pipelines.
"""

from __future__ import annotations

import importlib
from typing import Any

from ..core.registry import Registry

_MODULES: list[str] = [
    "touchbench.classifiers.gaus",
    "touchbench.classifiers.flagg",
    "touchbench.classifiers.zhou",
    "touchbench.classifiers.jung",
    "touchbench.classifiers.xgb",
    "touchbench.classifiers.cnn",  # imports torch only when the CNN is fitted
    "touchbench.classifiers.sota",
    "touchbench.classifiers.peers",  # imports aeon only when a peer is fitted
]


def _load() -> None:
    for m in _MODULES:
        importlib.import_module(m)


CLASSIFIERS: Registry = Registry("classifier", loader=_load)


def make_classifier(name: str, random_state: int | None = None, **params: Any):
    """Build the registered classifier ``name`` with ``params`` over its defaults."""
    return CLASSIFIERS.create(name, random_state=random_state, **params)
