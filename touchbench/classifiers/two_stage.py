"""Two stages for live recognition: is something touching, and which gesture is it.

``two-stage`` takes the captures (registry tag ``input="captures"``) and one
pipeline, ``features`` -> ``estimator`` (with ``params``, spelled as
``quiet-gated``'s), and fits it twice on the same feature matrix (the
features are computed once):

1. **A touch detector**: the estimator (with ``detector_params`` over
   ``params``) trained on every sample as ``idle`` or a touch (any other
   class), so it learns the sensor's real rest, noise and drift from the
   idle samples it is given. Trained on windows cut from recorded or
   spliced streams (the ``stream`` scheme's ``train_on: streams``), the idle
   samples are the stretches of rest between touches and the frames after a
   release, the touch samples include the first frames of each touch.
2. **A gesture classifier**: the estimator trained on the touch samples
   alone, so its probabilities are over the gestures only and are never
   spent on telling rest from touch.

``predict_proba`` gives ``P(idle) = 1 - P(touch)`` and ``P(g) = P(touch) *
P(g | touch)`` for every gesture ``g``: one probability row over every
class, as any method gives, so every decision rule and every scheme takes
it. The ``touch`` rule (:mod:`touchbench.streams.hysteresis`) reads the two
stages apart: a touch begins and ends with hysteresis on ``P(touch)``, and
the gesture is the one most probable over the touch so far.

Why (docs/research/live-recognition.md): one classifier over idle and
gestures spends its capacity on the gestures and takes a drifting, noisy
rest for a light touch; on recordings of a robot skin made frame by frame,
the product's methods misread one idle frame in four. The factorisation is
the usual one of activity spotting (a detector of "something happens", then
a classifier of what: Ward, Lukowicz & Gellersen 2011's segment and event
view of continuous recognition; an interpretation, not their method).

``idle`` names the idle class; the ``stream`` scheme gives its own when the
method's entry does not (``touchbench.engine.live.with_idle``). Without
one, the class without contact is found from the data as ``quiet-gated``
finds it (:func:`touchbench.classifiers.quiet.quiet_class`: the one class
whose median ``above10_frames`` of ``contact-evidence`` is at most 0.05;
HAART's ``notouch``); with no such class (every class a touch) it is the
pipeline alone, and ``selection_note_`` (a task's notes) says which. Refused:
an idle class named that the training samples lack, and what the pipeline's
parts refuse.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted

from ..core.errors import TouchbenchError
from ..features.base import check_captures, feature_set_refusal
from ..features.contact import ContactEvidence
from ._util import build, seed_int
from .base import CLASSIFIERS, ParamError, check_declared, check_nested_params
from .quiet import GATE_SET, QUIET_COLUMN, quiet_class
from .fitting import FittedMethod, capture_labels, feature_specs, fit_features, fit_on_codes, pipeline_refusal

NAME = "two-stage"
SOURCE = "touchbench (docs/research/live-recognition.md): a touch detector and a gesture classifier on one feature matrix"
#: the detector's label for every class other than idle
TOUCH = "touch"
#: the most a class's median ``above10_frames`` may be for it to be the class without contact (quiet-gated's)
QUIET_FRAMES = 0.05


def check_params(params: dict[str, Any]) -> None:
    """``idle`` not empty (its type is declared), and the estimator's own checks of ``params`` and of
    ``params`` with ``detector_params`` over them."""
    if params.get("idle") == "":
        raise ParamError(("idle",), "idle must name the idle class, got ''")
    det = params.get("detector_params") or {}
    check_nested_params(params.get("estimator"), dict(params.get("params") or {}), ("params",))
    check_nested_params(params.get("estimator"), {**dict(params.get("params") or {}), **det}, ("detector_params",))


class TwoStage(ClassifierMixin, BaseEstimator):
    """A touch detector and a gesture classifier over one feature matrix (module docstring).

    Parameters
    ----------
    features, estimator, params : the pipeline (feature sets -> registered estimator with its parameters).
    idle : the idle class (no touch); required when fitting.
    detector_params : the detector's estimator parameters, over ``params``.
    sensor : the data's SensorSpec (the run engine passes it).
    random_state : seeds both estimators.

    Examples
    --------
    >>> import numpy as np
    >>> from touchbench.datasets.model import SensorSpec
    >>> rng = np.random.default_rng(0)
    >>> rest = [rng.integers(0, 3, (20, 4, 4)).astype(np.uint8) for _ in range(6)]
    >>> ramp = np.minimum(np.arange(20) * 25, 200).astype(np.uint8)  # a press: up, then held
    >>> press = [ramp[:, None, None] * np.ones((1, 4, 4), np.uint8) for _ in range(6)]
    >>> pats = [np.tile(np.array([0, 200], np.uint8).repeat(2), 5)[:, None, None] * np.ones((1, 4, 4), np.uint8)
    ...         for _ in range(6)]
    >>> clf = TwoStage(features=["touch-rhythm"], estimator="touch-extra-trees", params={"n_estimators": 10},
    ...                idle="rest", sensor=SensorSpec("toy", (4, 4), 20.0, (0, 255)), random_state=0)
    >>> clf = clf.fit(rest + press + pats, ["rest"] * 6 + ["press"] * 6 + ["pat"] * 6)
    >>> clf.classes_.tolist()
    ['pat', 'press', 'rest']
    >>> clf.predict([rest[0], press[0]]).tolist()
    ['rest', 'press']
    """

    #: ``predict`` is ``classes_`` at the argmax of ``predict_proba`` (the run engine asks once for both)
    labels_are_argmax_proba = True

    #: the estimator's own parameters are its (``check_params``: with and without ``detector_params``)
    _parameter_constraints = {"features": [list, tuple], "estimator": [str], "params": [dict, None],
                              "idle": [str, None], "detector_params": [dict, None],
                              "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, features=("touch-rhythm",), estimator="touch-extra-trees", params=None, idle=None,
                 detector_params=None, sensor=None, random_state=None):
        self.features = features
        self.estimator = estimator
        self.params = params
        self.idle = idle
        self.detector_params = detector_params
        self.sensor = sensor
        self.random_state = random_state

    def check_sensor(self, sensor: Any, min_frames: int | None = None) -> str | None:
        """Why the pipeline cannot serve ``sensor``, or, with no idle class named, why contact-evidence (which
        finds it) cannot; None when both serve."""
        found = None if self.idle is not None else feature_set_refusal(GATE_SET, {}, sensor, min_frames)
        return found or pipeline_refusal(feature_specs(self.features), str(self.estimator), dict(self.params or {}),
                                         sensor, min_frames)

    def fit(self, X: Sequence[np.ndarray], y: Any, groups: Any = None, class_names: Any = None) -> "TwoStage":
        """Fit the feature sets once, the detector on every sample (idle or touch) and the gesture
        classifier on the touch samples. ``class_names``: the name of each code of ``y`` when ``y``
        holds codes (the run engine's fit path gives them), so that ``idle`` names a class."""
        check_declared(self)
        check_params(self.get_params(deep=False))
        captures = check_captures(X, name=NAME)
        y = capture_labels(y, captures, NAME)
        self.classes_ = np.unique(y)
        touch = self._touches(captures, y, class_names)
        sets, F = fit_features(feature_specs(self.features), captures, y, self.sensor)
        g = None if groups is None else np.asarray(groups)
        params, seed = dict(self.params or {}), seed_int(self.random_state)
        det = None if touch is None else fit_on_codes(
            str(self.estimator), {**params, **dict(self.detector_params or {})}, seed, F,
            np.where(touch, TOUCH, "~idle"), g, sensor=self.sensor)
        keep = np.ones(len(y), dtype=bool) if touch is None else touch
        gest = fit_on_codes(str(self.estimator), params, seed, F[keep] if isinstance(F, np.ndarray) else
                            [F[i] for i in np.flatnonzero(keep)], y[keep], None if g is None else g[keep],
                            sensor=self.sensor)
        self.detector_ = None if det is None else FittedMethod(sets, det)
        self.method_ = FittedMethod(sets, gest)
        return self

    def _touches(self, captures: list[np.ndarray], y: np.ndarray, class_names: Any) -> np.ndarray | None:
        """Which samples are touches (None: no idle class, the pipeline alone); sets ``idle_`` (the idle
        class as ``y`` writes it) and ``selection_note_``."""
        names = np.asarray(class_names).astype(str) if class_names is not None else y.astype(str)
        as_named = names[y.astype(np.int64)] if class_names is not None else names
        if self.idle is not None:
            if not (as_named == self.idle).any():
                raise TouchbenchError(f"{NAME}: the idle class {self.idle!r} is not among the training samples' "
                                      f"classes ({', '.join(sorted(set(as_named)))})")
            idle = self.idle
            how = "named"
        else:
            codes = np.searchsorted(self.classes_, y)
            G = np.asarray(ContactEvidence(sensor=self.sensor).transform(captures), dtype=np.float64)
            column = ContactEvidence(sensor=self.sensor).feature_names(tuple(self.sensor.grid)).index(QUIET_COLUMN)
            q = quiet_class(codes, G[:, column], QUIET_FRAMES)
            idle = None if q is None else str(np.unique(as_named)[q]) if class_names is None else str(names[self.classes_[q]])
            how = "found from the data (the one class without contact)"
        self.idle_ = None if idle is None else y[as_named == idle][0]
        self.selection_note_ = (f"{NAME}: idle class {idle!r} {how}" if idle is not None else
                                f"{NAME}: no class without contact in the training samples: the pipeline alone")
        return None if idle is None else as_named != idle

    def touch_proba(self, F: Any) -> np.ndarray:
        """``P(touch)`` of feature rows ``F`` (the detector's; 1 without an idle class)."""
        if self.detector_ is None:
            return np.ones(len(F))
        P = self.detector_.proba_rows(F)
        return P[:, list(self.detector_.classes).index(TOUCH)] if TOUCH in self.detector_.classes else \
            np.zeros(len(P))

    def predict_proba(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """Rows over ``classes_``: ``1 - P(touch)`` for idle, ``P(touch) P(g | touch)`` for each gesture."""
        check_is_fitted(self)
        F = self.method_.transform(check_captures(X, name=NAME))
        t = self.touch_proba(F)
        out = np.zeros((len(t), len(self.classes_)))
        if self.idle_ is not None:
            out[:, int(np.searchsorted(self.classes_, self.idle_))] = 1.0 - t
        G = self.method_.proba_rows(F)
        cols = np.searchsorted(self.classes_, self.method_.classes)
        out[:, cols] = t[:, None] * G
        return out

    def predict(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """The argmax of :meth:`predict_proba`."""
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]


DEFAULTS = {"features": ("touch-rhythm",), "estimator": "touch-extra-trees", "params": {}, "idle": None,
            "detector_params": {}}


@CLASSIFIERS.register(
    NAME,
    description="a touch detector (idle or not) and a gesture classifier trained on the touches alone, over one "
                "feature matrix; P(g) = P(touch) P(g | touch)",
    source=SOURCE, defaults=DEFAULTS, extra=None, input="captures", check_params=check_params,
    cheap_params=dict(estimator="zhou-tree"),
)
def two_stage(random_state=None, sensor=None, **params):
    return build(TwoStage, DEFAULTS, random_state, {**params, "sensor": sensor}, name=NAME)
