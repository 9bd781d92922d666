"""The classifier registry.

Each entry is a factory ``f(random_state=None, **params) -> estimator``
registered with ``description`` (one line), ``source`` (paper and section),
``defaults`` (the paper's settings, as a dict), ``extra`` (the optional
install it needs: None, ``"deep"`` or ``"peers"``) and, where the defaults
are slow, ``cheap_params`` (smaller settings that run the same code paths in
seconds: the tests' estimator checks use them). The estimators are plain
scikit-learn estimators (or follow that API), so users can use them in their
own pipelines.
"""

from __future__ import annotations

from typing import Any

from ..core.registry import Registry

# Filled by every module of touchbench.classifiers (imported on first use of the registry).
CLASSIFIERS: Registry = Registry("classifier", package="touchbench.classifiers")


def make_classifier(name: str, random_state: int | None = None, **params: Any):
    """Build the registered classifier ``name`` with ``params`` over its defaults."""
    return CLASSIFIERS.create(name, random_state=random_state, **params)
