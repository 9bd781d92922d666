"""Feature sets: scikit-learn transformers over captures, in one registry."""

from .base import FEATURES, FeatureSet, check_captures

__all__ = ["FEATURES", "FeatureSet", "check_captures"]
