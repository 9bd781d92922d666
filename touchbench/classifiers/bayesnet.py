"""A discrete Bayesian network classifier learned with K2, as Weka's
``BayesNet`` builds it (Flagg 2012, Appendix A: "conditional
probabilities estimator algorithm: simple estimator; network search
algorithm: K2").

No well-kept Python library reproduces Weka's ``BayesNet`` classifier (pgmpy
has the K2 *score* but not Weka's K2 *search* with a class node, its
discretisation and its estimator), so this module implements the three
documented steps with numpy:

1. **Discretisation.** Weka's ``BayesNet`` discretises numeric attributes
   with the supervised ``Discretize`` filter: Fayyad & Irani's (1993) MDL
   method, recursive binary cuts at midpoints between distinct values,
   a cut kept while ``gain > (log2(N - 1) + delta) / N``. Weka's defaults
   (``useBetterEncoding=false``, ``useKononenko=false``) are followed.
2. **Structure: K2** (Cooper & Herskovits 1992) with Weka's defaults: the
   class is the first node and, with ``init_as_naive_bayes`` (Weka's
   default), parent of every attribute; attributes are visited in column
   order and greedily given the predecessor parent that most increases the
   Bayesian (BDeu-style, pseudo-count ``alpha`` per cell) local score, until
   no parent helps or ``max_parents`` (which counts the class) is reached.
3. **Parameters: SimpleEstimator** with ``alpha = 0.5``:
   ``P(x = v | parents = j) = (N_jv + alpha) / (N_j + alpha * r)``, the
   class prior likewise.

Interpretation. Flagg names only K2 and the simple estimator, so the other
K2 settings are Weka's defaults, in particular ``maxNrOfParents = 1``. With
the naive-Bayes initial structure the class already uses that one parent
slot, so K2 adds no arcs: **Weka's default K2 network is a naive Bayes over
the MDL-discretised attributes**, and so is this classifier by default.
``max_parents=2`` or more lets K2 add attribute-to-attribute arcs (a genuine
search). Not matched: Weka's exact score constants (we use the standard
Bayesian-Dirichlet local score with pseudo-count ``alpha``) and its handling
of missing values (touchbench features have none).
"""

from __future__ import annotations

from numbers import Integral, Real
import numpy as np
from scipy.special import gammaln
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils import check_random_state
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from sklearn.utils._param_validation import Interval


def _xlogx(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, dtype=np.float64)
    out = np.zeros_like(c)
    pos = c > 0
    out[pos] = c[pos] * np.log2(c[pos])
    return out


def _entropy(counts: np.ndarray) -> float:
    """Entropy (bits) of one class-count vector, as Weka's ContingencyTables."""
    n = counts.sum()
    if n <= 0:
        return 0.0
    return float((_xlogx(n) - _xlogx(counts).sum()) / n)


def mdl_cut_points(values: np.ndarray, y: np.ndarray, n_classes: int) -> np.ndarray:
    """Fayyad & Irani MDL cut points of one attribute (Weka's supervised
    ``Discretize``, default options). ``y`` holds class indices."""
    order = np.argsort(values, kind="mergesort")
    v = np.asarray(values, dtype=np.float64)[order]
    yc = np.asarray(y)[order]
    cuts: list[float] = []
    _cuts_for_subset(v, yc, n_classes, 0, len(v), cuts)
    return np.array(sorted(cuts), dtype=np.float64)


def _cuts_for_subset(v, y, k, lo, hi, out) -> None:
    n = hi - lo
    if n < 2:
        return
    onehot = np.zeros((n, k))
    onehot[np.arange(n), y[lo:hi]] = 1.0
    cum = np.cumsum(onehot, axis=0)
    total = cum[-1]
    prior_entropy = _entropy(total)
    left = cum[:-1]
    right = total - left
    nl = np.arange(1, n, dtype=np.float64)
    nr = n - nl
    # conditional entropy, Weka's entropyConditionedOnRows
    ent = ((_xlogx(nl) - _xlogx(left).sum(1)) + (_xlogx(nr) - _xlogx(right).sum(1))) / n
    valid = v[lo:hi - 1] < v[lo + 1:hi]
    if not valid.any():
        return
    ent_valid = np.where(valid, ent, np.inf)
    best = int(np.argmin(ent_valid))  # first minimum, as Weka's strict "<"
    best_entropy = ent_valid[best]
    gain = prior_entropy - best_entropy
    if not best_entropy < prior_entropy or gain <= 0:
        return
    # Fayyad & Irani's MDL criterion (Weka: FayyadAndIranisMDL, numCutPoints = n - 1)
    lc, rc = left[best], right[best]
    k_all = int((total > 0).sum())
    k_l, k_r = int((lc > 0).sum()), int((rc > 0).sum())
    delta = np.log2(3.0**k_all - 2.0) - (k_all * prior_entropy - k_r * _entropy(rc) - k_l * _entropy(lc))
    if not gain > (np.log2(n - 1) + delta) / n:
        return
    out.append((v[lo + best] + v[lo + best + 1]) / 2.0)
    _cuts_for_subset(v, y, k, lo, lo + best + 1, out)
    _cuts_for_subset(v, y, k, lo + best + 1, hi, out)


def _bd_score(counts: np.ndarray, alpha: float) -> float:
    """Bayesian-Dirichlet local score of a (configs x values) count table."""
    r = counts.shape[1]
    n_j = counts.sum(axis=1)
    return float(
        np.sum(gammaln(alpha * r) - gammaln(alpha * r + n_j))
        + np.sum(gammaln(alpha + counts) - gammaln(alpha))
    )


class K2BayesNetClassifier(ClassifierMixin, BaseEstimator):
    """Weka-style ``BayesNet`` (K2 search, SimpleEstimator) over MDL-discretised
    attributes. See the module docstring for the steps and interpretations.

    Parameters
    ----------
    max_parents : maximum parents per attribute, the class included (Weka
        K2 ``-P``, default 1: naive Bayes structure).
    alpha : SimpleEstimator pseudo-count (Weka ``-A``, default 0.5), also
        the score's pseudo-count.
    init_as_naive_bayes : start from the class as parent of every attribute
        (Weka's default; ``-N`` turns it off).
    random_order : visit attributes in a random order (Weka ``-R``), seeded
        by ``random_state``.

    Attributes
    ----------
    cut_points_ : list of arrays, the MDL cut points of each attribute.
    parents_ : list of lists, each attribute's parents (``-1`` is the class).
    """

    #: checked when a protocol is read: a positive Dirichlet alpha, max_parents at least 0 (the
    #: search stops at the attributes there are, so no upper bound)
    _parameter_constraints = {"alpha": [Interval(Real, 0, None, closed="neither")],
                              "max_parents": [Interval(Integral, 0, None, closed="left")]}

    def __init__(self, max_parents=1, alpha=0.5, init_as_naive_bayes=True, random_order=False,
                 random_state=None):
        self.max_parents = max_parents
        self.alpha = alpha
        self.init_as_naive_bayes = init_as_naive_bayes
        self.random_order = random_order
        self.random_state = random_state

    # -- helpers -------------------------------------------------------------
    def _discretise(self, X):
        codes = np.empty(X.shape, dtype=np.int64)
        for j, cuts in enumerate(self.cut_points_):
            codes[:, j] = np.searchsorted(cuts, X[:, j], side="left")
        return codes

    def _config(self, parents, codes, yc):
        """Parent-configuration index of each row (mixed radix over parents)."""
        idx = np.zeros(codes.shape[0], dtype=np.int64)
        for p in parents:
            if p == -1:
                idx = idx * self.n_classes_ + yc
            else:
                idx = idx * self.cardinality_[p] + codes[:, p]
        return idx

    def _n_configs(self, parents):
        q = 1
        for p in parents:
            q *= self.n_classes_ if p == -1 else int(self.cardinality_[p])
        return q

    def _counts(self, i, parents, codes, yc):
        r = int(self.cardinality_[i])
        q = self._n_configs(parents)
        cfg = self._config(parents, codes, yc)
        return np.bincount(cfg * r + codes[:, i], minlength=q * r).reshape(q, r).astype(np.float64)

    # -- fit / predict ---------------------------------------------------------
    def fit(self, X, y):
        if not (isinstance(self.max_parents, (int, np.integer)) and self.max_parents >= 0):
            raise ValueError(f"max_parents must be a non-negative integer, got {self.max_parents!r}")
        if not self.alpha > 0:
            raise ValueError(f"alpha must be positive, got {self.alpha!r}")
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_, yc = np.unique(y, return_inverse=True)
        self.n_classes_ = k = len(self.classes_)
        p = X.shape[1]
        self.cut_points_ = [mdl_cut_points(X[:, j], yc, k) for j in range(p)]
        self.cardinality_ = np.array([len(c) + 1 for c in self.cut_points_], dtype=np.int64)
        codes = self._discretise(X)

        order = np.arange(p)
        if self.random_order:
            order = check_random_state(self.random_state).permutation(p)
        parents: list[list[int]] = [[-1] if self.init_as_naive_bayes else [] for _ in range(p)]
        for pos, i in enumerate(order):
            candidates = ([] if self.init_as_naive_bayes else [-1]) + [int(j) for j in order[:pos]]
            score = _bd_score(self._counts(i, parents[i], codes, yc), self.alpha)
            while len(parents[i]) < self.max_parents:
                best, best_score = None, score
                for j in candidates:
                    if j in parents[i]:
                        continue
                    s = _bd_score(self._counts(i, parents[i] + [j], codes, yc), self.alpha)
                    if s > best_score:
                        best, best_score = j, s
                if best is None:
                    break
                parents[i].append(best)
                score = best_score
        self.parents_ = parents

        a = self.alpha
        class_counts = np.bincount(yc, minlength=k).astype(np.float64)
        self.class_log_prior_ = np.log((class_counts + a) / (class_counts.sum() + a * k))
        self.log_cpt_ = []
        for i in range(p):
            c = self._counts(i, parents[i], codes, yc)
            self.log_cpt_.append(np.log((c + a) / (c.sum(axis=1, keepdims=True) + a * c.shape[1])))
        return self

    def _joint_log(self, X):
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        codes = self._discretise(X)
        n = X.shape[0]
        out = np.tile(self.class_log_prior_, (n, 1))
        for c in range(self.n_classes_):
            yc = np.full(n, c, dtype=np.int64)
            for i, par in enumerate(self.parents_):
                cfg = self._config(par, codes, yc)
                out[:, c] += self.log_cpt_[i][cfg, codes[:, i]]
        return out

    def predict_log_proba(self, X):
        jl = self._joint_log(X)
        m = jl.max(axis=1, keepdims=True)
        return jl - (m + np.log(np.exp(jl - m).sum(axis=1, keepdims=True)))

    def predict_proba(self, X):
        return np.exp(self.predict_log_proba(X))

    def predict(self, X):
        jl = self._joint_log(X)
        return self.classes_[np.argmax(jl, axis=1)]
