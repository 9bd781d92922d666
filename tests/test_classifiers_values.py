"""Values worked out by hand or by another library for the classifiers'
building blocks: Weka's feature rule and standardisation, MDL cuts, the K2
score and structure, the Weka MLP update, SAMME weights, MATLAB's KNN
weights and kernel scale, the logistic ridge mapping."""

from __future__ import annotations

import math
import statistics

import numpy as np
import pytest
from scipy.optimize import minimize
from sklearn.datasets import load_iris
from sklearn.ensemble import AdaBoostClassifier, RandomForestClassifier
from sklearn.naive_bayes import CategoricalNB
from sklearn.svm import SVC
from sklearn.tree import DecisionTreeClassifier

from touchbench.classifiers import make_classifier
from touchbench.classifiers._util import MAX_SEED, SampleStandardScaler, WekaRandomForestClassifier, weka_max_features
from touchbench.classifiers.bayesnet import K2BayesNetClassifier, _bd_score, mdl_cut_points
from touchbench.classifiers.boosting import SAMMEClassifier
from touchbench.classifiers.mlp import WekaMLPClassifier, hidden_units
from touchbench.classifiers.zhou import matlab_auto_kernel_scale, squared_inverse_weights


# -- Weka / MATLAB conventions --------------------------------------------------------------------

def test_weka_features_per_split():
    assert weka_max_features("weka", 192) == 8  # int(log2 192) = 7, + 1
    assert weka_max_features("weka", 29) == 5  # Flagg's "5 (option '0')": int(log2 29) + 1
    assert weka_max_features(5, 3) == 3  # capped at M, as Weka does
    assert weka_max_features("sqrt", 10) == "sqrt"
    X = np.random.default_rng(0).normal(size=(20, 3))
    rf = WekaRandomForestClassifier(n_estimators=3, max_features=5, random_state=0).fit(X, np.arange(20) % 2)
    assert rf.max_features == 5 and rf.estimators_[0].max_features_ == 3


def test_weka_forest_grows_scikit_learns_trees():
    rng = np.random.default_rng(1)
    X, y = rng.normal(size=(60, 20)), rng.integers(0, 4, 60)
    w = rng.random(60)
    for weights in (None, w):
        ours = WekaRandomForestClassifier(n_estimators=7, criterion="entropy", max_features="weka",
                                          random_state=5).fit(X, y, sample_weight=weights)
        # scikit-learn's own forest with Weka's int(log2 20) + 1 = 5 features per split
        theirs = RandomForestClassifier(n_estimators=7, criterion="entropy", max_features=5,
                                        random_state=5).fit(X, y, sample_weight=weights)
        assert [t.random_state for t in ours.estimators_] == [t.random_state for t in theirs.estimators_]
        for a, b in zip(ours.estimators_, theirs.estimators_):
            assert a.get_params() == b.get_params()
            assert np.array_equal(a.tree_.threshold, b.tree_.threshold) and np.array_equal(a.tree_.value, b.tree_.value)
        assert np.array_equal(ours.predict_proba(X), theirs.predict_proba(X))


def test_sample_standard_scaler_uses_the_sample_deviation():
    X = np.array([[1.0, 5.0], [2.0, 5.0], [4.0, 5.0]])
    Z = SampleStandardScaler().fit_transform(X)
    sd = statistics.stdev([1.0, 2.0, 4.0])  # n - 1 denominator
    assert np.allclose(Z[:, 0], (np.array([1.0, 2.0, 4.0]) - 7 / 3) / sd)
    assert np.allclose(Z[:, 1], 0.0)  # a constant column is only centred
    # frequency weights: weight 2 on a row is the row repeated
    Zw = SampleStandardScaler().fit(X, sample_weight=[2, 1, 1]).transform(X)
    Zr = SampleStandardScaler().fit(np.vstack([X, X[:1]])).transform(X)
    assert np.allclose(Zw, Zr)


# -- MDL discretisation and K2 --------------------------------------------------------------------

def test_mdl_cut_between_two_pure_blocks():
    v = np.arange(1.0, 13.0)
    y = np.array([0] * 6 + [1] * 6)
    # gain 1 bit > (log2 11 + log2 7 - 2) / 12 = 0.355: one cut at the midpoint, then pure halves
    assert mdl_cut_points(v, y, 2).tolist() == [6.5]


def test_mdl_rejects_a_weak_cut():
    # best cut 1.5 gains 0.311 bits < (log2 3 + log2 7 - (2 - 2 * 0.918)) / 4 = 1.06
    assert mdl_cut_points(np.array([1.0, 2.0, 3.0, 4.0]), np.array([0, 1, 0, 1]), 2).size == 0
    # no cut between equal values
    assert mdl_cut_points(np.array([1.0, 1.0, 1.0, 1.0]), np.array([0, 0, 1, 1]), 2).size == 0


def test_bd_score_by_hand():
    counts = np.array([[2.0, 0.0], [1.0, 1.0]])
    a = 0.5
    lg = math.lgamma
    expected = (lg(1) - lg(3) + lg(2.5) - lg(0.5) + lg(0.5) - lg(0.5)
                + lg(1) - lg(3) + lg(1.5) - lg(0.5) + lg(1.5) - lg(0.5))
    assert _bd_score(counts, a) == pytest.approx(expected)


def test_default_k2_network_is_naive_bayes_as_categorical_nb_computes_it():
    X, y = load_iris(return_X_y=True)
    bn = K2BayesNetClassifier().fit(X, y)
    assert bn.parents_ == [[-1]] * 4  # max_parents = 1 is used up by the class
    codes = bn._discretise(X)
    counts = np.bincount(y)
    prior = (counts + 0.5) / (counts.sum() + 0.5 * 3)  # SimpleEstimator on the class node
    nb = CategoricalNB(alpha=0.5, class_prior=prior, min_categories=bn.cardinality_).fit(codes, y)
    assert np.allclose(bn.predict_proba(X), nb.predict_proba(codes))
    assert np.array_equal(bn.predict(X), nb.predict(codes))


def test_k2_adds_the_parent_that_explains_an_attribute():
    rng = np.random.default_rng(0)
    c = rng.integers(0, 2, 400)
    a = np.where(rng.random(400) < 0.7, c, 1 - c)  # informative about the class
    b = np.where(rng.random(400) < 0.97, a, 1 - a)  # a near copy of a
    X = np.column_stack([a, b]).astype(float)
    assert K2BayesNetClassifier(max_parents=2).fit(X, c).parents_ == [[-1], [-1, 0]]
    assert K2BayesNetClassifier(max_parents=1).fit(X, c).parents_ == [[-1], [-1]]


# -- Weka MLP -----------------------------------------------------------------------------------

def test_hidden_layer_wildcards():
    assert hidden_units("a", 29, 9) == 19  # Flagg's 19 units: (29 + 9) / 2
    assert hidden_units("a", 192, 7) == 99
    assert (hidden_units("i", 4, 3), hidden_units("o", 4, 3), hidden_units("t", 4, 3)) == (4, 3, 7)
    with pytest.raises(ValueError):
        hidden_units("x", 4, 3)


def test_one_online_update_by_hand():
    X = np.array([[0.0, 2.0], [4.0, 6.0]])
    y = np.array(["p", "q"])
    m = WekaMLPClassifier(hidden_layers=1, max_epochs=1, random_state=3).fit(X, y)
    # replay: same initial draws (W1, b1, W2, b2, then the shuffle) and two online steps
    rng = np.random.RandomState(3)
    W1, b1 = rng.uniform(-0.05, 0.05, (1, 2)), rng.uniform(-0.05, 0.05, 1)
    W2, b2 = rng.uniform(-0.05, 0.05, (2, 1)), rng.uniform(-0.05, 0.05, 2)
    order = rng.permutation(2)
    Xs = (X - X.mean(0)) / 2.0  # [-1, 1] scaling: base (max+min)/2, range (max-min)/2
    T = np.eye(2)
    s = lambda z: 1 / (1 + math.exp(-z))  # noqa: E731
    mW1, mb1, mW2, mb2 = np.zeros((1, 2)), np.zeros(1), np.zeros((2, 1)), np.zeros(2)
    for i in order:
        x, t = Xs[i], T[i]
        h = s(W1[0] @ x + b1[0])
        o = np.array([s(W2[k, 0] * h + b2[k]) for k in range(2)])
        do = o * (1 - o) * (t - o)
        dh = h * (1 - h) * (do @ W2[:, 0])
        mW2 = 0.2 * mW2 + 0.3 * do[:, None] * h
        mb2 = 0.2 * mb2 + 0.3 * do
        mW1 = 0.2 * mW1 + 0.3 * dh * x[None, :]
        mb1 = 0.2 * mb1 + 0.3 * dh
        W2, b2, W1, b1 = W2 + mW2, b2 + mb2, W1 + mW1, b1 + mb1
    assert np.allclose(m.coefs_[0], W1) and np.allclose(m.coefs_[1], W2)
    assert np.allclose(m.intercepts_[0], b1) and np.allclose(m.intercepts_[1], b2)


def test_weka_mlp_learns_iris():
    X, y = load_iris(return_X_y=True)
    m = WekaMLPClassifier(max_epochs=100, random_state=0).fit(X, y)
    assert m.n_hidden_ == 3  # (4 + 3) // 2
    assert np.mean(m.predict(X) == y) > 0.95
    assert np.allclose(m.predict_proba(X).sum(1), 1.0)


# -- boosting -----------------------------------------------------------------------------------

def test_samme_weights_match_scikit_learn_adaboost():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(120, 1))
    y = np.digitize(X[:, 0] + rng.normal(scale=0.7, size=120), [-0.5, 0.5])
    stump = DecisionTreeClassifier(max_depth=1)
    ours = SAMMEClassifier(stump, n_estimators=6, random_state=0).fit(X, y)
    ref = AdaBoostClassifier(stump, n_estimators=6, random_state=0).fit(X, y)
    assert ours.n_iterations_ == 6
    assert np.allclose(ours.estimator_weights_, ref.estimator_weights_)
    assert np.allclose(ours.estimator_errors_, ref.estimator_errors_)
    # the first weight by hand: log((1 - err) / err) + log(K - 1)
    err = ours.estimator_errors_[0]
    assert ours.estimator_weights_[0] == pytest.approx(math.log((1 - err) / err) + math.log(2))


def test_perfectly_fitting_forest_stops_boosting_at_one_forest():
    X, y = load_iris(return_X_y=True)
    boost = make_classifier("gaus-boost", random_state=4, n_trees=30).fit(X, y)
    assert (boost.n_iterations_, boost.stop_reason_) == (1, "perfect_fit")
    # the model is exactly the first forest (Weka: "If we're the first we have to use it")
    seed = int(np.random.RandomState(4).randint(MAX_SEED))
    rf = WekaRandomForestClassifier(n_estimators=30, criterion="entropy", max_features="weka",
                                    random_state=seed).fit(X, y, sample_weight=np.full(150, 1 / 150) * 150)
    assert np.array_equal(boost.predict_proba(X), rf.predict_proba(X))
    # scikit-learn's AdaBoost (SAMME) stops there too
    ada = AdaBoostClassifier(RandomForestClassifier(n_estimators=30, random_state=0), n_estimators=50,
                             random_state=0).fit(X, y)
    assert len(ada.estimators_) == 1


def test_out_of_bag_error_keeps_boosting():
    X, y = load_iris(return_X_y=True)
    b = make_classifier("gaus-boost", random_state=0, n_trees=30, n_estimators=5, weak_error="oob").fit(X, y)
    assert b.n_iterations_ > 1
    assert np.all(b.estimator_errors_ > 0) and np.all(b.estimator_weights_ > 0)


# -- MATLAB presets -----------------------------------------------------------------------------

def test_squared_inverse_weights():
    w = squared_inverse_weights(np.array([[1.0, 2.0, 4.0], [0.0, 1.0, 0.0]]))
    assert np.allclose(w[0], [1.0, 0.25, 0.0625])
    assert np.allclose(w[1], [1.0, 0.0, 1.0])  # exact matches take all the weight


def test_weighted_knn_by_hand():
    # query at 0; neighbours a at 1, b at 2 and 2.5 (standardisation off): 1/1 = 1 vs 1/4 + 1/6.25 = 0.41
    X = np.array([[1.0], [2.0], [-2.5]])
    y = np.array(["a", "b", "b"])
    knn = make_classifier("zhou-weighted-knn", n_neighbors=3, standardize=False).fit(X, y)
    assert knn.predict([[0.0]])[0] == "a"
    assert np.allclose(knn.predict_proba([[0.0]]), [[1 / 1.41, 0.41 / 1.41]])
    eq = make_classifier("zhou-knn", n_neighbors=3, standardize=False).fit(X, y)
    assert eq.predict([[0.0]])[0] == "b"  # equal weights: 2 votes to 1


def test_matlab_auto_kernel_scale_by_hand():
    pos, neg = np.array([[0.0], [3.0]]), np.array([[1.0], [10.0]])
    # nearest negatives: 0 -> 1 (1), 3 -> 1 (2); median 1.5; all rows sampled, correction factor 1
    assert matlab_auto_kernel_scale(pos, neg, np.random.default_rng(0)) == pytest.approx(1.5)
    assert matlab_auto_kernel_scale(np.zeros((2, 1)), np.zeros((2, 1)), np.random.default_rng(0)) == 1.0


def test_matlab_ecoc_svm_agrees_with_libsvm_ovo_on_fixed_scale():
    X, y = load_iris(return_X_y=True)
    ours = make_classifier("zhou-linear-svm", kernel_scale=1.0, standardize=False).fit(X, y)
    ref = SVC(kernel="linear", C=1.0).fit(X, y)
    assert np.mean(ours.predict(X) == ref.predict(X)) > 0.97
    assert ours.decision_function(X).shape == (150, 3)
    auto = make_classifier("zhou-quadratic-svm", random_state=0).fit(X, y)
    assert len(auto.kernel_scales_) == 3 and np.mean(auto.predict(X) == y) > 0.95


# -- Weka logistic ------------------------------------------------------------------------------

def test_logistic_ridge_matches_wekas_objective():
    X, y = load_iris(return_X_y=True)
    keep = y > 0  # two classes: one weight vector in both Weka and scikit-learn
    X, y = X[keep], (y[keep] == 2).astype(int)
    ridge = 0.5
    lr = make_classifier("flagg-logistic", ridge=ridge).fit(X, y)
    Z = (X - X.mean(0)) / X.std(0, ddof=1)

    def weka_nll(b):  # -loglik + ridge * ||beta||^2, intercept unpenalised
        eta = b[0] + Z @ b[1:]
        return np.sum(np.logaddexp(0, eta) - y * eta) + ridge * np.sum(b[1:] ** 2)

    b = minimize(weka_nll, np.zeros(5), method="BFGS", options={"gtol": 1e-10}).x
    p_ref = 1 / (1 + np.exp(-(b[0] + Z @ b[1:])))
    assert np.allclose(lr.predict_proba(X)[:, 1], p_ref, atol=1e-5)
