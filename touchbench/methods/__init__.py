"""Methods: what a protocol evaluates and a model file holds.

A method is feature sets -> an estimator on the feature matrix
(:class:`touchbench.methods.pipeline.FeaturePipeline`). The protocol
shorthand ``features`` x ``classifiers`` expands to methods; a named method
(:data:`METHODS`, e.g. touchbench's ``touch-*`` family) declares its own
feature sets and estimator, so the run engine computes its fold-independent
features once per dataset in the feature cache instead of inside every task.

:mod:`touchbench.methods.fitting` fits a method's estimator through the one
fit path (:mod:`touchbench.classifiers.fitting`: labels into codes, training
subjects to estimators that take ``groups``, a training set of one class):
the engine's tasks, ``touchbench train`` and the nested search all fit there.
"""

from .base import (CAPTURES, METHODS, Method, MethodSpec, expand_candidates, features_label, method_name, method_spec,
                   named_methods, resolve_entry, stops_on_test)
from .fitting import FittedEstimator, FittedMethod, fit_estimator, fit_method
from .pipeline import FeaturePipeline

__all__ = ["CAPTURES", "METHODS", "FeaturePipeline", "FittedEstimator", "FittedMethod", "Method", "MethodSpec", "expand_candidates",
           "features_label", "fit_estimator", "fit_method", "method_name", "method_spec", "named_methods", "resolve_entry",
           "stops_on_test"]
