"""A multilayer perceptron trained as Weka's ``MultilayerPerceptron`` trains
it (Flagg 2012, Appendix A: "hidden layers: 19 (option 'a' in
Weka); learning rate: 0.3; momentum: 0.2; normalize attributes: true;
seed: 0; number of training epochs: 500; validation set size: 0; decay
learning rate: false").

scikit-learn's ``MLPClassifier`` cannot be configured to be this network: it
uses a softmax output with cross-entropy loss and Glorot initialisation,
and with Weka's learning rate of 0.3 on a cross-entropy loss training is a
different (and less stable) optimisation problem. So the Weka procedure is
written out here in numpy:

- numeric attributes scaled to [-1, 1] with the training minimum and
  maximum (a constant attribute is only centred);
- one hidden layer of sigmoid units, ``"a"`` = (attributes + classes) / 2
  (integer division) by default; one sigmoid output unit per class, target
  1 for the true class and 0 otherwise;
- weights and biases drawn uniformly from [-0.05, 0.05];
- the training set shuffled once with the seed, then online
  back-propagation of the squared error, instance by instance, for
  ``max_epochs`` epochs: ``dw = learning_rate * delta * input + momentum *
  dw_previous``; no validation set, no learning-rate decay;
- if the error diverges (non-finite), training restarts with half the
  learning rate, as Weka does;
- ``predict_proba`` is the output vector normalised to sum to one (Weka's
  ``distributionForInstance``).

Not matched: Weka's ``java.util.Random`` stream (a seed gives other initial
weights here), and its per-epoch error bookkeeping (irrelevant without a
validation set).
"""

from __future__ import annotations

from numbers import Integral, Real
import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import check_random_state
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval


def _sigmoid(z: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.clip(z, -45.0, 45.0)))


def hidden_units(spec, n_attributes: int, n_classes: int) -> int:
    """Weka's hidden-layer wildcards: ``a`` = (attribs + classes) / 2,
    ``i`` = attribs, ``o`` = classes, ``t`` = attribs + classes; or an int."""
    if isinstance(spec, str):
        table = {
            "a": (n_attributes + n_classes) // 2,
            "i": n_attributes,
            "o": n_classes,
            "t": n_attributes + n_classes,
        }
        if spec not in table:
            raise ValueError(f"hidden_layers must be 'a', 'i', 'o', 't' or a positive int, got {spec!r}")
        return max(table[spec], 1)
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool) and spec >= 1:
        return int(spec)
    raise ValueError(f"hidden_layers must be 'a', 'i', 'o', 't' or a positive int, got {spec!r}")


class WekaMLPClassifier(ClassifierMixin, BaseEstimator):
    """Weka-style one-hidden-layer perceptron (see the module docstring).

    Parameters
    ----------
    hidden_layers : ``"a"`` (default), ``"i"``, ``"o"``, ``"t"`` or an int.
    learning_rate, momentum : Weka ``-L`` and ``-M`` (0.3, 0.2).
    max_epochs : Weka ``-N`` (500).
    normalize_attributes : scale inputs to [-1, 1] (Weka's default, on).
    random_state : seeds the initial weights and the one shuffle.
    """

    #: checked when a protocol is read: a positive learning rate, Weka's momentum in [0, 1], and
    #: max_epochs at most 100,000 (every epoch is a pass over the training set: beyond that a run
    #: does not end)
    _parameter_constraints = {"learning_rate": [Interval(Real, 0, None, closed="neither")],
                              "momentum": [Interval(Real, 0, 1, closed="both")],
                              "max_epochs": [Interval(Integral, 0, 100_000, closed="both")]}

    def __init__(self, hidden_layers="a", learning_rate=0.3, momentum=0.2, max_epochs=500,
                 normalize_attributes=True, random_state=None):
        self.hidden_layers = hidden_layers
        self.learning_rate = learning_rate
        self.momentum = momentum
        self.max_epochs = max_epochs
        self.normalize_attributes = normalize_attributes
        self.random_state = random_state

    def _scale(self, X):
        if not self.normalize_attributes:
            return X
        return (X - self.base_) / self.range_

    def fit(self, X, y):
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be positive, got {self.learning_rate!r}")
        if not (isinstance(self.max_epochs, (int, np.integer)) and self.max_epochs >= 0):
            raise ValueError(f"max_epochs must be a non-negative integer, got {self.max_epochs!r}")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        k = len(self.classes_)
        n, p = X.shape
        self.n_hidden_ = h = hidden_units(self.hidden_layers, p, k)
        lo, hi = X.min(axis=0), X.max(axis=0)
        self.base_ = (hi + lo) / 2.0
        rng_ = (hi - lo) / 2.0
        rng_[rng_ == 0] = 1.0
        self.range_ = rng_
        Xs = self._scale(X)
        T = np.zeros((n, k))
        T[np.arange(n), yi] = 1.0

        lr = float(self.learning_rate)
        for _attempt in range(60):
            rng = check_random_state(self.random_state)
            ok = self._train(Xs, T, h, lr, rng)
            if ok:
                break
            lr /= 2.0  # Weka: the network diverged, restart with half the rate
        else:  # pragma: no cover - needs a pathological input
            raise RuntimeError("WekaMLPClassifier: training diverged at every learning rate tried")
        self.learning_rate_ = lr
        return self

    def _train(self, Xs, T, h, lr, rng) -> bool:
        n, p = Xs.shape
        k = T.shape[1]
        W1 = rng.uniform(-0.05, 0.05, size=(h, p))
        b1 = rng.uniform(-0.05, 0.05, size=h)
        W2 = rng.uniform(-0.05, 0.05, size=(k, h))
        b2 = rng.uniform(-0.05, 0.05, size=k)
        dW1, db1 = np.zeros_like(W1), np.zeros_like(b1)
        dW2, db2 = np.zeros_like(W2), np.zeros_like(b2)
        order = rng.permutation(n)  # Weka randomises the instances once
        Xo, To = Xs[order], T[order]
        m = float(self.momentum)
        dot, outer, sig = np.dot, np.outer, _sigmoid
        for _epoch in range(self.max_epochs):
            for x, t in zip(Xo, To):
                hid = sig(dot(W1, x) + b1)
                out = sig(dot(W2, hid) + b2)
                d_out = out * (1.0 - out) * (t - out)
                d_hid = hid * (1.0 - hid) * dot(d_out, W2)
                d_out *= lr  # learning rate folded into the (short) error vectors
                d_hid *= lr
                dW2 *= m
                dW2 += outer(d_out, hid)
                db2 *= m
                db2 += d_out
                dW1 *= m
                dW1 += outer(d_hid, x)
                db1 *= m
                db1 += d_hid
                W2 += dW2
                b2 += db2
                W1 += dW1
                b1 += db1
            if not (np.isfinite(W1).all() and np.isfinite(W2).all()):
                return False
        self.coefs_ = [W1, W2]
        self.intercepts_ = [b1, b2]
        return True

    def _outputs(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        W1, W2 = self.coefs_
        b1, b2 = self.intercepts_
        hid = _sigmoid(self._scale(X) @ W1.T + b1)
        return _sigmoid(hid @ W2.T + b2)

    def predict_proba(self, X):
        out = self._outputs(X)
        s = out.sum(axis=1, keepdims=True)
        uniform = np.full_like(out, 1.0 / out.shape[1])
        return np.where(s > 0, out / np.where(s > 0, s, 1.0), uniform)

    def predict(self, X):
        out = self._outputs(X)
        return self.classes_[np.argmax(out, axis=1)]
