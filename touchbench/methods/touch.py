"""touchbench's own methods, the ``touch-*`` family: touchbench's feature sets -> extra-trees or XGBoost.

Not from a paper: every choice was made by cross-validation inside the
HAART challenge's training subjects (docs/research/touch-methods.md). Each
method is feature sets of :mod:`touchbench.features.touch` (and
:mod:`touchbench.features.touch_windows`) followed by an estimator of
:mod:`touchbench.classifiers.touch` or the ``xgboost`` classifier, so the
run engine computes the features once per dataset (feature cache) and the
estimator sees the same matrix a user's own pipeline would.

- ``touch-et``: touch-rhythm + cell-rhythm + contact-motion -> extra-trees (500 trees, 30 % of features per split);
- ``touch-et-tuned``: the same with max_features and feature selection chosen by nested CV over the training subjects;
- ``touch-xgb``: the same sets -> XGBoost;
- ``touch-et-win``: the three sets plus touch-windows (their mean and sd over four 2-s windows) -> extra-trees;
- ``touch-et-fast``: touch-rhythm alone -> extra-trees of 100 trees (the latency-bound entry);
- ``touch-et-contact``: touch-et plus contact-evidence (level as a fraction of full scale and contact above
  the capture's noise floor, :mod:`touchbench.features.contact`: what the level-free sets remove) -> extra-trees;
- ``touch-et-adapt``: touch-et-contact's feature sets -> the same extra-trees inside ``session-centred``
  (:mod:`touchbench.classifiers.adapt`): each session (subject) centred by its own feature means, the test
  session's from its unlabelled captures -- a figure of another kind, kept apart from the plain ones;
- ``touch-et-shift``: touch-et-contact's feature sets -> the same extra-trees, trained on every training capture
  plus two copies changed by the sensor's effects (gain, offset, read noise white or wandering, dead cells, a
  window taken anywhere in the capture: ``shift-augmented``, :mod:`touchbench.classifiers.augment`, with its
  defaults); the features are computed inside each task, on the captures and their copies;
- ``touch-select``: the design itself as a method: touch-et, touch-xgb, touch-et-win and touch-et-fast
  scored by leaving one training subject out at a time, inside every outer fold, the best refitted
  (``nested-select``, :mod:`touchbench.classifiers.search`); a candidate the sensor refuses is left out;
- ``touch-rocket-fusion``: touch-et-contact and MiniRocket (aeon, ``peers`` extra) fused: the weighted sum of
  their probabilities, the weight chosen among 0, 0.25, 0.5, 0.75, 1 (on touch-et-contact) by the pooled
  accuracy of leaving one training subject out at a time, inside every outer fold, both parts refitted
  (``fusion``, :mod:`touchbench.classifiers.fusion`); a sensor either part cannot serve is refused.

Parameters given to a method go to its estimator (for ``touch-et-shift``: the augmentation's, e.g.
``copies``; ``params`` replaces the extra-trees' parameters).
"""

from __future__ import annotations

from .base import METHODS, expand_candidates, pipeline_method

SOURCE = "touchbench (docs/research/touch-methods.md)"
THREE = ("touch-rhythm", "cell-rhythm", "contact-motion")

_TOUCH = {
    "touch-et": ("touchbench: touch-rhythm + cell-rhythm + contact-motion -> extra-trees 500",
                 THREE, "touch-extra-trees", {}),
    "touch-et-tuned": ("touchbench: touch-et with max_features / feature selection by nested CV over training subjects",
                       THREE, "touch-extra-trees-tuned", {}),
    "touch-xgb": ("touchbench: touch-rhythm + cell-rhythm + contact-motion -> XGBoost",
                  THREE, "xgboost", {}),
    "touch-et-win": ("touchbench: touch-et plus touch-windows (the three sets' mean and sd over four 2-s windows)",
                     (*THREE, "touch-windows"), "touch-extra-trees", {}),
    "touch-et-fast": ("touchbench, latency-bound: touch-rhythm -> extra-trees 100",
                      ("touch-rhythm",), "touch-extra-trees", {"n_estimators": 100}),
    "touch-et-contact": ("touchbench: touch-et plus contact-evidence (level and contact above the noise floor)",
                         (*THREE, "contact-evidence"), "touch-extra-trees", {}),
    "touch-et-adapt": ("touchbench: touch-et-contact's feature sets -> its extra-trees on each session centred by its "
                       "own means (adapts to the test session's unlabelled captures)",
                       (*THREE, "contact-evidence"), "session-centred",
                       {"estimator": "touch-extra-trees", "params": {}, "scale": False}),
}

for _name, (_desc, _sets, _est, _params) in _TOUCH.items():
    METHODS.register(_name, description=_desc, source=SOURCE, feature_sets=_sets, estimator=_est,
                     defaults=dict(_params))(pipeline_method(_name, _sets, _est, _params))

_contact_sets = _TOUCH["touch-et-contact"][1]
_shift = {"features": list(_contact_sets), "estimator": "touch-extra-trees", "params": dict(_TOUCH["touch-et-contact"][3])}
METHODS.register("touch-et-shift", description="touchbench: touch-et-contact trained on the captures plus copies changed "
                 "by the sensor's effects (gain, offset, read noise, dead cells, a window anywhere)",
                 source=SOURCE, feature_sets=(), estimator="shift-augmented",
                 defaults=dict(_shift))(pipeline_method("touch-et-shift", (), "shift-augmented", _shift))

SELECT_FROM = ("touch-et", "touch-xgb", "touch-et-win", "touch-et-fast")
_select = expand_candidates("nested-select", {"candidates": list(SELECT_FROM)})
METHODS.register("touch-select", description="touchbench: the touch method with the best inner LOSO accuracy over the "
                 "training subjects (touch-et, touch-xgb, touch-et-win, touch-et-fast), refitted",
                 source=SOURCE, feature_sets=(), estimator="nested-select",
                 defaults=dict(_select))(pipeline_method("touch-select", (), "nested-select", _select))

FUSE = ("touch-et-contact", "minirocket")
_fuse = expand_candidates("fusion", {"parts": list(FUSE)})
METHODS.register("touch-rocket-fusion", description="touchbench: touch-et-contact and MiniRocket, their probabilities "
                 "summed with the weight of the best pooled inner LOSO accuracy over the training subjects, both refitted",
                 source=SOURCE, feature_sets=(), estimator="fusion",
                 defaults=dict(_fuse))(pipeline_method("touch-rocket-fusion", (), "fusion", _fuse))
