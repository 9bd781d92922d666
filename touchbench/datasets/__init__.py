"""Datasets: the model, the real-data readers and the registry of named datasets."""

from .model import SensorSpec, TouchDataset, concat
from .registry import DATASETS

__all__ = ["DATASETS", "SensorSpec", "TouchDataset", "concat"]
