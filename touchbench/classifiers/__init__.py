"""Classifiers: scikit-learn estimators built by name, defaults from the papers."""

from .base import CLASSIFIERS, make_classifier

__all__ = ["CLASSIFIERS", "make_classifier"]
