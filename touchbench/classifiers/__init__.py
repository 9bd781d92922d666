"""Classifiers: scikit-learn estimators built by name, defaults from the papers."""

from .base import CLASSIFIERS, ParamError, check_classifier_params, make_classifier

__all__ = ["CLASSIFIERS", "ParamError", "check_classifier_params", "make_classifier"]
