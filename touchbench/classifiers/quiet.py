"""A pipeline read over windows of its training length, with a no-contact class decided by the noise floor.

``quiet-gated`` takes the captures as recorded (registry tag
``input="captures"``) with a pipeline, ``features`` -> ``estimator`` (with
``params``, written as ``shift-augmented``'s), and changes how that
pipeline meets captures of another recording set-up
(docs/research/study-transfer.md has the measurements behind each part):

1. **Windows of the training length.** A test capture at least twice as
   long as the longest training capture is cut into windows of the
   training captures' median length ``L`` (starts ``0, s, 2 s, ...`` with
   ``s = max(1, round(stride * L))``, and a last window ending at the
   capture's last frame); the pipeline's probabilities are averaged over
   its windows. A shorter capture is read whole by the pipeline, as the
   plain pipeline reads it, so a benchmark whose captures share one
   length, or vary less than twofold between training and test
   (SocialTouch's longest test captures against its training ones), is
   unchanged by this step. The gate (below) reads every capture longer
   than ``L`` as such windows, in training and in test, so it always
   judges stretches of one length. Why: features summarising a capture
   (spectra, order statistics, a 5 % baseline) change with its length and
   with what a long recording holds besides the gesture (start
   transients, a level step), the way time-series classifiers trained on
   fixed-length series are applied to longer ones by sliding windows and
   pooled decisions (e.g. Bagnall et al. 2017, "The great time series
   classification bake off", the interval methods; an interpretation, not
   their procedure).

2. **A no-contact gate.** The training class with no contact is found
   from the data: the one class whose median ``above10_frames`` of
   ``contact-evidence`` (the fraction of frames with a reading more than 10
   noise floors above the capture's rest level,
   :mod:`touchbench.features.contact`) is at most ``quiet_frames``
   (default 0.05; HAART's ``notouch``: 0.00, its other classes 0.26 and
   above). When exactly one class qualifies, a logistic regression
   (standardised ``sign(v) log(1 + |v|)`` of the 19 ``contact-evidence``
   features, balanced class weights, ``C = gate_c``) is trained to tell it
   from the rest, on the training captures' windows (each window labelled
   as its capture); a capture's gate probability ``g`` is the median over
   its windows. The gate decides when ``g > 0.5`` and the pipeline is not
   sure of a touch: its most probable other class has a probability below
   ``sure`` (default 0.5). Then the capture is the no-contact class, with
   probability ``g``, and each other class gets ``(1 - g)`` times the
   pipeline's probability renormalised over the other classes
   (:func:`gated_proba`); otherwise it is the pipeline's most probable
   other class, with the pipeline's probabilities renormalised over the
   other classes. ``predict`` is the argmax of ``predict_proba``. With no
   such class (SocialTouch, CoST: every gesture is a touch), or
   ``gate=False``, the probabilities are the pipeline's. ``sure`` keeps the
   gate from overruling a confident pipeline: on HAART (leave one subject
   out) the gate alone took 30 of 711 touches for no touch, 2 points of
   accuracy; with ``sure = 0.5`` the loss is 0.1 point and the second
   study's ``notouch`` recall is unchanged (docs/research/study-transfer.md).
   Why a gate: contact measured against the capture's own noise floor
   transfers between set-ups where the pipeline's level-free sets, which
   read the shape of the noise, do not (Gaus et al. 2015, Sec. 3.2.1,
   separate "no touch" by level; contact-evidence's docstring).

3. **Training on windows** (``train_windows``, off by default): training
   captures at least ``2 L`` long are cut into the same windows, each a
   training capture of its own (its label and subject repeated), so the
   pipeline learns from stretches of the length it reads; the longest
   training capture is then the longest the pipeline was trained on. Off
   by default because it changes what the pipeline is trained on wherever
   lengths vary (90 % of SocialTouch's captures last 10 to 87 frames, the
   longest 239).

Parameters ``gate`` and ``windows`` switch each part off (the ablations of
the research note). Refused: no sensor (contact-evidence needs the value
range), a channel sensor (no rest level of cells), and what the pipeline's
parts refuse.
"""

from __future__ import annotations

from numbers import Real
from typing import Any, Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted

from ..core.errors import TouchbenchError
from ..features.base import check_captures, feature_set_refusal
from ..features.contact import ContactEvidence
from ._util import build, seed_int
from .base import CLASSIFIERS, check_declared, check_nested_params
from .fitting import capture_labels, feature_specs, fit_pipeline, pipeline_refusal, proba_over

NAME = "quiet-gated"
SOURCE = ("touchbench (docs/research/study-transfer.md): windows of the training length and a no-contact gate "
          "on contact above the capture's noise floor (touchbench.features.contact)")
GATE_SET = "contact-evidence"
#: the contact-evidence column the no-contact class is found by
QUIET_COLUMN = "above10_frames"


def window_starts(frames: int, length: int, step: int) -> list[int]:
    """First frames of the windows of ``length`` frames over a capture of ``frames`` frames, ``step``
    apart, the last ending at the capture's last frame; ``[0]`` when the capture is no longer than one."""
    if frames <= length:
        return [0]
    starts = list(range(0, frames - length + 1, max(1, int(step))))
    if starts[-1] != frames - length:
        starts.append(frames - length)
    return starts


def quiet_class(codes: np.ndarray, contact_frames: np.ndarray, most: float) -> int | None:
    """The one class (a value of ``codes``) whose captures' median ``contact_frames`` is at most
    ``most``; None when no class or more than one qualifies, or only one class is present."""
    classes = np.unique(codes)
    if len(classes) < 2:
        return None
    quiet = [c for c in classes if float(np.median(contact_frames[codes == c])) <= most]
    return quiet[0].item() if len(quiet) == 1 else None


def log_signed(X: np.ndarray) -> np.ndarray:
    """``sign(v) log(1 + |v|)`` of every value: ratios of many noise floors brought to one scale."""
    X = np.asarray(X, dtype=np.float64)
    return np.sign(X) * np.log1p(np.abs(X))


def gated_proba(base: np.ndarray, gate: np.ndarray, column: int) -> np.ndarray:
    """Rows of ``base`` (probabilities over classes) with the class ``column`` given the gate's
    probability ``gate`` and every other class ``1 - gate`` times its share of the others (an even
    share when the pipeline gives the others nothing)."""
    base = np.asarray(base, dtype=np.float64)
    g = np.asarray(gate, dtype=np.float64)
    others = base.copy()
    others[:, column] = 0.0
    total = others.sum(axis=1, keepdims=True)
    even = np.full_like(others, 1.0 / max(base.shape[1] - 1, 1))
    even[:, column] = 0.0
    share = np.where(total > 0, others / np.where(total > 0, total, 1.0), even)
    out = (1.0 - g)[:, None] * share
    out[:, column] = g
    return out


def gate_decides(base: np.ndarray, gate: np.ndarray, column: int, sure: float) -> np.ndarray:
    """Rows where the gate's probability is above 0.5 and no other class than ``column`` has a
    probability of ``sure`` or more in ``base``."""
    others = np.asarray(base, dtype=np.float64).copy()
    others[:, column] = 0.0
    return (np.asarray(gate) > 0.5) & (others.max(axis=1) < sure)


def check_params(params: dict[str, Any]) -> None:
    """The pipeline's estimator's own checks of its ``params`` (the gate's numbers are declared:
    :attr:`QuietGated._parameter_constraints`)."""
    check_nested_params(params.get("estimator"), dict(params.get("params") or {}), ("params",))


class QuietGated(ClassifierMixin, BaseEstimator):
    """A pipeline over windows of its training length with a no-contact gate (module docstring).

    Parameters
    ----------
    features, estimator, params : the pipeline (feature sets -> registered estimator with its parameters).
    gate : train and use the no-contact gate when the training data has a no-contact class.
    windows : cut captures at least twice the longest training capture into windows of the training length.
    train_windows : train the pipeline on windows of the training captures at least twice the window long.
    gate_c : the gate's inverse L2 penalty.
    quiet_frames : the most a class's median ``above10_frames`` may be for it to be the no-contact class.
    stride : the step between windows, as a fraction of the window.
    sure : the probability of a touch class from which the pipeline overrules the gate.
    sensor : the data's SensorSpec (the run engine passes it); required.
    random_state : seeds the pipeline's estimator.
    """

    #: ``predict`` is ``classes_`` at the argmax of ``predict_proba`` (the run engine asks once for both)
    labels_are_argmax_proba = True

    #: ``gate_c`` above 0 (an inverse penalty), ``quiet_frames`` a fraction in [0, 1) (1 would take
    #: every class for the quiet one), ``stride`` a fraction of the window in (0, 1], ``sure`` a
    #: probability in (0, 1]; the estimator's parameters are its own (``check_params``)
    _parameter_constraints = {"features": [list, tuple], "estimator": [str], "params": [dict, None],
                              "gate": ["boolean"], "windows": ["boolean"], "train_windows": ["boolean"],
                              "gate_c": [Interval(Real, 0, None, closed="neither")],
                              "quiet_frames": [Interval(Real, 0, 1, closed="left")],
                              "stride": [Interval(Real, 0, 1, closed="right")],
                              "sure": [Interval(Real, 0, 1, closed="right")],
                              "sensor": "no_validation", "random_state": ["random_state"]}

    def __init__(self, features=("touch-rhythm",), estimator="touch-extra-trees", params=None, gate=True,
                 windows=True, train_windows=False, gate_c=0.1, quiet_frames=0.05, stride=0.25, sure=0.5,
                 sensor=None, random_state=None):
        self.features = features
        self.estimator = estimator
        self.params = params
        self.gate = gate
        self.windows = windows
        self.train_windows = train_windows
        self.gate_c = gate_c
        self.quiet_frames = quiet_frames
        self.stride = stride
        self.sure = sure
        self.sensor = sensor
        self.random_state = random_state

    def _pipeline(self) -> tuple[list[tuple[str, dict[str, Any]]], str, dict[str, Any]]:
        return feature_specs(self.features), str(self.estimator), dict(self.params or {})

    def check_sensor(self, sensor: Any, min_frames: int | None = None) -> str | None:
        """Why the gate's contact-evidence or the pipeline cannot serve ``sensor``, or None."""
        return (feature_set_refusal(GATE_SET, {}, sensor, min_frames)
                or pipeline_refusal(*self._pipeline(), sensor, min_frames))

    def _checked(self, X: Any) -> list[np.ndarray]:
        captures = check_captures(X, name=NAME)
        if self.sensor is None:
            raise TouchbenchError(f"{NAME}: needs the sensor (the gate's contact-evidence reads levels on its "
                                  "value range): pass sensor=SensorSpec(...)")
        problem = self.check_sensor(self.sensor, min(len(c) for c in captures) if captures else None)
        if problem:
            raise TouchbenchError(f"{NAME} cannot serve sensor {self.sensor.describe()}: {problem}")
        return captures

    def _evidence(self, captures: list[np.ndarray]) -> np.ndarray:
        return np.asarray(ContactEvidence(sensor=self.sensor).transform(captures), dtype=np.float64)

    def fit(self, X: Sequence[np.ndarray], y: Any, groups: Any = None) -> "QuietGated":
        """Fit the pipeline on the captures as given; find the no-contact class and fit its gate."""
        check_declared(self)
        check_params(self.get_params(deep=False))
        captures = self._checked(X)
        y = capture_labels(y, captures, NAME)
        self.classes_ = np.unique(y)
        self.window_ = int(np.median([len(c) for c in captures]))
        train, owner = self._windows(captures, 2 * self.window_ - 1) if self.train_windows else (
            captures, np.arange(len(captures)))
        self.longest_, self.n_training_ = int(max(len(c) for c in train)), len(train)
        sets, est, params = self._pipeline()
        self.method_ = fit_pipeline(sets, est, params, seed_int(self.random_state), train, y[owner],
                                    None if groups is None else np.asarray(groups)[owner], sensor=self.sensor)
        self.quiet_, self.gate_ = None, None
        if self.gate:
            self._fit_gate(captures, np.searchsorted(self.classes_, y))
        return self

    def _fit_gate(self, captures: list[np.ndarray], codes: np.ndarray) -> None:
        """Find the class without contact and fit its gate on the training captures' windows."""
        G = self._evidence(captures)
        column = ContactEvidence(sensor=self.sensor).feature_names(tuple(self.sensor.grid)).index(QUIET_COLUMN)
        q = quiet_class(codes, G[:, column], float(self.quiet_frames))
        if q is None:
            return
        wins, owner = self._windows(captures, self.window_)
        self.quiet_ = self.classes_[q]
        self.gate_ = make_pipeline(StandardScaler(), LogisticRegression(
            C=float(self.gate_c), class_weight="balanced", max_iter=5000)).fit(
                log_signed(self._evidence(wins)), codes[owner] == q)

    def _windows(self, captures: list[np.ndarray], beyond: int) -> tuple[list[np.ndarray], np.ndarray]:
        """Every capture's windows (module docstring), cutting those longer than ``beyond`` frames,
        and the capture each comes from."""
        out, owner = [], []
        step = max(1, round(float(self.stride) * self.window_))
        for i, c in enumerate(captures):
            if not self.windows or len(c) <= beyond:
                out.append(c)
                owner.append(i)
                continue
            for a in window_starts(len(c), self.window_, step):
                out.append(c[a:a + self.window_])
                owner.append(i)
        return out, np.asarray(owner, dtype=np.intp)

    def _parts(self, X: Any) -> tuple[np.ndarray, np.ndarray | None]:
        """The pipeline's probabilities averaged over each capture's windows, and the gate's median."""
        check_is_fitted(self)
        captures = check_captures(X, name=NAME)
        wins, owner = self._windows(captures, 2 * self.longest_ - 1)
        pw = proba_over(self.method_.fitted, self.method_.transform(wins), self.classes_)
        counts = np.bincount(owner, minlength=len(captures)).astype(np.float64)
        base = np.zeros((len(captures), len(self.classes_)))
        np.add.at(base, owner, pw)
        base /= counts[:, None]
        if self.gate_ is None:
            return base, None
        wins, owner = self._windows(captures, self.window_)
        gw = self.gate_.predict_proba(log_signed(self._evidence(wins)))[:, 1]
        gate = np.array([np.median(gw[owner == i]) for i in range(len(captures))])
        return base, gate

    def predict_proba(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """Probabilities over ``classes_`` (module docstring): the gated ones where the gate decides,
        else the pipeline's over the other classes; the pipeline's when there is no gate."""
        base, gate = self._parts(X)
        if gate is None:
            return base
        column = int(np.searchsorted(self.classes_, self.quiet_))
        return np.where(gate_decides(base, gate, column, float(self.sure))[:, None],
                        gated_proba(base, gate, column), gated_proba(base, np.zeros_like(gate), column))

    def predict(self, X: Sequence[np.ndarray]) -> np.ndarray:
        """The argmax of :meth:`predict_proba`."""
        return self.classes_[np.argmax(self.predict_proba(X), axis=1)]


DEFAULTS = {"features": ("touch-rhythm",), "estimator": "touch-extra-trees", "params": {}, "gate": True,
            "windows": True, "train_windows": False, "gate_c": 0.1, "quiet_frames": 0.05, "stride": 0.25,
            "sure": 0.5}


@CLASSIFIERS.register(
    NAME,
    description="a pipeline read over windows of its training length, with the class of no contact decided by a "
                "gate on contact above the capture's noise floor (contact-evidence)",
    source=SOURCE, defaults=DEFAULTS, extra=None, input="captures", check_params=check_params,
    cheap_params=dict(features=["contact-evidence"], estimator="zhou-tree"),
)
def quiet_gated(random_state=None, sensor=None, **params):
    return build(QuietGated, DEFAULTS, random_state, {**params, "sensor": sensor}, name=NAME)
