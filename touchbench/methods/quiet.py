"""Methods for recordings of another set-up of the same sensor: ``touch-et-quiet``, ``touch-et-quiet-win``.

Not from a paper: measured on HAART and the design half of the HAART
organisers' second study (docs/research/study-transfer.md). Trained on
HAART's 8-s captures and tested on the second study's 20-s recordings,
``touch-et-fast`` called almost every ``notouch`` a touch: the study's
noise floor is higher and slower than HAART's (read by the level-free
feature sets as a touch), and its long recordings hold start transients
and a level step that no 8-s training capture has.

- ``touch-et-quiet``: ``touch-et-fast``'s pipeline (touch-rhythm -> extra-trees of 100 trees) inside
  ``quiet-gated`` (:mod:`touchbench.classifiers.quiet`): a capture at least twice as long as every
  training capture is read as windows of the training length (probabilities averaged), and the training
  class without contact (found from ``contact-evidence``: HAART's ``notouch``) is decided by a logistic
  regression on contact above the capture's own noise floor where the pipeline is not sure of a touch;
  on captures of one length with no such class it is touch-et-fast.
- ``touch-et-quiet-win``: the same, its pipeline trained on the windows of the training captures at least
  twice the window long (``train_windows``): for training data that holds long recordings (HAART plus the
  second study's 20-s recordings); on captures of one length it is touch-et-quiet.

Parameters given to the method go to ``quiet-gated`` (``gate``, ``windows``, ``gate_c``, ``stride``...;
``params`` replaces the extra-trees' parameters).
"""

from __future__ import annotations

from .base import METHODS, pipeline_method

SOURCE = "touchbench (docs/research/study-transfer.md)"

_quiet = {"features": ["touch-rhythm"], "estimator": "touch-extra-trees", "params": {"n_estimators": 100}}
_QUIET = {
    "touch-et-quiet": ("touchbench: touch-et-fast read over windows of the training length, its no-contact class "
                       "decided by contact above the capture's noise floor", {}),
    "touch-et-quiet-win": ("touchbench: touch-et-quiet with its pipeline trained on windows of the long training "
                           "captures", {"train_windows": True}),
}
for _name, (_desc, _more) in _QUIET.items():
    _params = {**_quiet, **_more}
    METHODS.register(_name, description=_desc, source=SOURCE, feature_sets=(), estimator="quiet-gated",
                     defaults=dict(_params))(pipeline_method(_name, (), "quiet-gated", _params))
