"""Methods built for live recognition: ``touch-live``, ``touch-live-fast``.

Not from a paper: designed on three recorded sessions of a robot skin, on
spliced HAART streams and on the design half of the HAART organisers'
second study (docs/research/live-recognition.md). Each is the ``two-stage``
estimator (:mod:`touchbench.classifiers.two_stage`): a touch detector
(idle or not) and a gesture classifier trained on the touches alone, over
one feature matrix, whose probabilities the ``touch`` rule reads apart
(:mod:`touchbench.streams.hysteresis`: a touch begun and ended with
hysteresis, the gesture most probable over the touch so far). In a stream
evaluation they are best trained on windows cut from the training streams
(``train_on: streams``), so that the detector sees the sensor's real rest
and the frames around onsets and releases.

- ``touch-live``: touch-rhythm and contact-motion -> extra-trees of 100 trees, both stages;
- ``touch-live-fast``: live-summary (nine frame-level series of the window, summarised:
  :mod:`touchbench.features.live_summary`) -> extra-trees of 100 trees, both stages (the latency-bound
  entry: a few hundred microseconds of features a window where touch-rhythm takes milliseconds).

Parameters given to the method go to ``two-stage`` (``idle``, ``detector_params``; ``params``
replaces the extra-trees' parameters).
"""

from __future__ import annotations

from .base import METHODS, pipeline_method

SOURCE = "touchbench (docs/research/live-recognition.md)"

_LIVE = {
    "touch-live": ("touchbench, live: a touch detector and a gesture classifier (touch-rhythm + contact-motion -> "
                   "extra-trees 100 each)", ["touch-rhythm", "contact-motion"], 100),
    "touch-live-fast": ("touchbench, live and latency-bound: a touch detector and a gesture classifier "
                        "(live-summary -> extra-trees 100 each)", ["live-summary"], 100),
}
for _name, (_desc, _sets, _trees) in _LIVE.items():
    _params = {"features": _sets, "estimator": "touch-extra-trees", "params": {"n_estimators": _trees}, "idle": None}
    METHODS.register(_name, description=_desc, source=SOURCE, feature_sets=(), estimator="two-stage",
                     defaults=dict(_params))(pipeline_method(_name, (), "two-stage", _params))
