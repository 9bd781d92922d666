"""Trained models and live recognition: ``touchbench train``, ``predict`` and ``stream``.

- :mod:`.model`: :class:`TrainedModel` (fitted feature sets + classifier + manifest) and :func:`fit_model`;
- :mod:`.train`: a protocol's method -> a model (``touchbench train``);
- :mod:`.predict`: labels for the captures of any supported reader;
- :mod:`.stream`: sliding windows over a stream of frames, thresholded decisions, latency;
- :mod:`.windows`: the windowing shared by training and streaming (Flagg 2012, section 4.5);
- :mod:`touchbench.classifiers.fastforest`: forests' probabilities for a few rows (also inside a wrapping estimator), fast and identical.
"""

from .model import SensorMismatchError, TrainedModel, fit_model
from .stream import Decision, SlidingRecognizer, StreamSummary

__all__ = ["Decision", "SensorMismatchError", "SlidingRecognizer", "StreamSummary", "TrainedModel", "fit_model"]
