"""The classifier registry.

Each entry is a factory ``f(random_state=None, **params) -> estimator``
(``f(random_state=None, sensor=None, **params)`` for a classifier that
needs the sensor: the run engine passes the dataset's)
registered with ``description`` (one line), ``source`` (paper and section),
``defaults`` (the paper's settings, as a dict), ``extra`` (the optional
install it needs: None, ``"deep"``, ``"peers"``, ``"xgboost"``, or several
joined by commas, ``"peers,deep"``) and, where the defaults
are slow, ``cheap_params`` (smaller settings that run the same code paths in
seconds: the tests' estimator checks use them). The estimators are plain
scikit-learn estimators (or follow that API), so users can use them in their
own pipelines.
"""

from __future__ import annotations

from typing import Any

from ..core.introspect import with_accepted
from ..core.registry import Registry

# Filled by every module of touchbench.classifiers (imported on first use of the registry).
CLASSIFIERS: Registry = Registry("classifier", package="touchbench.classifiers")


def make_classifier(name: str, random_state: int | None = None, sensor: Any = None, **params: Any):
    """Build the registered classifier ``name`` with ``params`` over its defaults.

    ``sensor`` (the dataset's :class:`touchbench.datasets.model.SensorSpec`)
    is passed when the factory takes it (the raw-frame classifiers take
    their grid and frame rate from it), by the same rule as
    :func:`touchbench.features.base.make_feature_set`.
    """
    factory = CLASSIFIERS.get(name)
    return CLASSIFIERS.create(name, random_state=random_state, **with_accepted(factory, params, sensor=sensor))
