"""The CNN of Al-mashhadani et al. 2021: Table 1's shapes,
the sub-windows of Eq. 3, voting, the early-stopping split, determinism,
and scikit-learn's estimator checks (on a 1 x 1 "grid" so that the checks'
small 2-D data are valid frames)."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from sklearn.utils.estimator_checks import parametrize_with_checks  # noqa: E402

from touchbench.classifiers import make_classifier  # noqa: E402
from touchbench.classifiers.cnn import HaartCNNClassifier, build_network  # noqa: E402


def test_table1_shapes_and_parameter_count():
    net = build_network(torch, 14, (8, 8), 7)  # L = 30 -> F = 14, Table 1's "8 x 8 x 14"
    features = net[0]
    x = torch.zeros(2, 14, 8, 8)
    assert tuple(features(x).shape) == (2, 128 * 2 * 2)  # Table 1: FC input 128 x 2 x 2
    convs = [m for m in features if isinstance(m, torch.nn.Conv2d)]
    assert [(c.in_channels, c.out_channels, c.kernel_size, c.padding) for c in convs] == [
        (14, 32, (2, 2), (1, 1)), (32, 64, (2, 2), (1, 1)), (64, 128, (3, 3), (1, 1))]
    assert (net[1].in_features, net[1].out_features, net[3].out_features) == (512, 256, 7)
    # by hand: 14*32*4+32 + 32*64*4+64 + 64*128*9+128 + 512*256+256 + 256*7+7
    assert sum(p.numel() for p in net.parameters()) == 1824 + 8256 + 73856 + 131328 + 1799
    assert tuple(net(x).shape) == (2, 7)


def _frame_index_captures(n=2, frames=432, grid=(8, 8)):
    """Captures whose every cell holds its frame number."""
    f = np.arange(frames, dtype=np.float64)[None, :, None, None]
    return np.broadcast_to(f, (n, frames, *grid)).reshape(n, -1).copy()


@pytest.mark.parametrize("L, F", [(30, 14), (10, 43), (86, 5), (5, 86), (50, 8)])
def test_sub_windows_are_consecutive_frames(L, F):
    est = HaartCNNClassifier(L=L)
    est.grid_, est.n_frames_total_, est.frames_per_window_ = (8, 8), 432, 432 // L
    assert est.frames_per_window_ == F  # Eq. 3: F = floor(432 / L)
    w = est._windows(_frame_index_captures(), np.array([0, L - 1]))
    assert w.shape == (2, 2, F, 8, 8)
    assert w[0, 0, :, 0, 0].tolist() == list(range(F))  # the first window: frames 0..F-1
    assert w[1, 1, :, 3, 5].tolist() == list(range((L - 1) * F, L * F))  # the last: (L-1)F..LF-1


def _toy(n_per_class=20, frames=12, grid=(2, 2), seed=0):
    """Three classes that differ in which cell is pressed."""
    rng = np.random.default_rng(seed)
    X, y, g = [], [], []
    for k, name in enumerate(["pat", "rub", "stroke"]):
        for i in range(n_per_class):
            cap = rng.normal(0, 1, size=(frames, *grid))
            cap.reshape(frames, -1)[:, k] += 5.0
            X.append(cap.reshape(-1))
            y.append(name)
            g.append(f"s{i % 5}")
    return np.array(X), np.array(y), np.array(g)


SMALL = dict(grid=(2, 2), L=3, max_epochs=8, batch_size=8, learning_rate=1e-2, channels=(4, 8, 8), hidden_units=16)


def test_learns_and_returns_gesture_names():
    X, y, _ = _toy()
    est = make_classifier("cnn", random_state=0, **SMALL).fit(X, y)
    assert est.frames_per_window_ == 4
    assert set(est.predict(X)) <= {"pat", "rub", "stroke"}
    assert np.mean(est.predict(X) == y) > 0.9
    p = est.predict_proba(X)
    assert p.shape == (60, 3) and np.allclose(p.sum(1), 1.0)


def test_same_seed_bit_identical_other_seed_differs_global_state_restored():
    X, y, _ = _toy()
    threads, det = torch.get_num_threads(), torch.are_deterministic_algorithms_enabled()
    rng_state = torch.get_rng_state()
    a = make_classifier("cnn", random_state=11, **SMALL).fit(X, y)
    b = make_classifier("cnn", random_state=11, **SMALL).fit(X, y)
    c = make_classifier("cnn", random_state=12, **SMALL).fit(X, y)
    assert np.array_equal(a.predict_proba(X), b.predict_proba(X))
    assert all(torch.equal(u, v) for u, v in zip(a.net_.state_dict().values(), b.net_.state_dict().values()))
    assert not np.array_equal(a.predict_proba(X), c.predict_proba(X))
    assert torch.get_num_threads() == threads
    assert torch.are_deterministic_algorithms_enabled() == det
    assert torch.equal(torch.get_rng_state(), rng_state)


def test_soft_and_hard_votes_over_all_windows():
    X, y, _ = _toy()
    est = make_classifier("cnn", random_state=0, train_windows="all", test_windows="all", **SMALL).fit(X, y)
    w = est._window_proba(X)
    assert w.shape == (60, 3, 3)  # L = 3 windows per capture
    assert np.allclose(est.predict_proba(X), w.mean(axis=1))
    est.set_params(vote="hard")
    votes = np.stack([(w.argmax(2) == k).sum(1) for k in range(3)], axis=1) / 3
    assert np.allclose(est.predict_proba(X), votes)
    top = votes.max(1, keepdims=True)
    pred = est.predict(X)
    for i, label in enumerate(pred):  # the majority, ties broken by the mean probability
        k = list(est.classes_).index(label)
        assert votes[i, k] == top[i, 0]
        tied = np.flatnonzero(votes[i] == top[i, 0])
        assert k == tied[np.argmax(w[i].mean(0)[tied])]


def test_early_stopping_holds_out_training_groups_only():
    X, y, g = _toy()
    est = make_classifier("cnn", random_state=0, validation_fraction=0.2, patience=2, **SMALL)
    est.fit(X, y, groups=g)
    assert len(est.validation_groups_) == 1 and set(est.validation_groups_) <= set(g)
    assert est.validation_size_ == int(np.isin(g, est.validation_groups_).sum())
    assert all("val_loss" in h for h in est.history_)
    best = min(range(len(est.history_)), key=lambda i: est.history_[i]["val_loss"])
    assert est.best_epoch_ == best + 1
    strat = make_classifier("cnn", random_state=0, validation_fraction=0.2, **SMALL).fit(X, y)
    assert strat.validation_groups_ is None and strat.validation_size_ == 12  # 20% of 20 per class
    none = make_classifier("cnn", random_state=0, validation_fraction=0.0, **SMALL).fit(X, y)
    assert none.validation_size_ == 0 and none.n_epochs_ == SMALL["max_epochs"]
    # validation_by rows: the groups given are ignored, the split is drawn per class as without them
    rows = make_classifier("cnn", random_state=0, validation_fraction=0.2, validation_by="rows", **SMALL)
    rows.fit(X, y, groups=g)
    assert rows.validation_groups_ is None and rows.validation_size_ == 12
    with pytest.raises(ValueError, match=r"The 'validation_by' parameter of HaartCNNClassifier must be a str among "
                                         r"\{'groups', 'rows'\}\. Got 'subjects' instead\."):
        make_classifier("cnn", random_state=0, validation_by="subjects", **SMALL).fit(X, y)


def test_bad_shapes_and_parameters_are_refused():
    X, y, _ = _toy()
    with pytest.raises(ValueError, match="not a whole number of 8x8 frames"):
        HaartCNNClassifier(grid=(8, 8)).fit(X, y)
    with pytest.raises(ValueError, match="no frame per window"):
        HaartCNNClassifier(grid=(2, 2), L=13).fit(X, y)
    with pytest.raises(ValueError, match="window index out of range"):
        HaartCNNClassifier(grid=(2, 2), L=3, train_windows=[3]).fit(X, y)


CHECK_PARAMS = dict(grid=(1, 1), L=1, max_epochs=10, learning_rate=1e-2, validation_fraction=0, batch_size=32,
                    channels=(4, 4, 4), hidden_units=8)


@parametrize_with_checks([make_classifier("cnn", random_state=0, **CHECK_PARAMS)])
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


def test_soft_vote_is_the_mean_of_hand_made_window_probabilities(monkeypatch):
    est = HaartCNNClassifier(test_windows="all", vote="soft")
    est.classes_ = np.array(["pat", "rub", "stroke"])
    # 2 captures x 3 windows x 3 classes, each window's softmax made up
    p = np.array([[[0.6, 0.3, 0.1], [0.1, 0.5, 0.4], [0.2, 0.5, 0.3]],
                  [[0.4, 0.35, 0.25], [0.4, 0.35, 0.25], [0.0, 0.9, 0.1]]])
    monkeypatch.setattr(HaartCNNClassifier, "_window_proba", lambda self, X: p)
    # by hand: (0.6 + 0.1 + 0.2) / 3 = 0.3, (0.3 + 0.5 + 0.5) / 3 = 1.3 / 3, (0.1 + 0.4 + 0.3) / 3 = 0.8 / 3;
    # (0.4 + 0.4 + 0.0) / 3 = 0.8 / 3, (0.35 + 0.35 + 0.9) / 3 = 1.6 / 3, (0.25 + 0.25 + 0.1) / 3 = 0.2
    by_hand = np.array([[0.3, 1.3 / 3, 0.8 / 3], [0.8 / 3, 1.6 / 3, 0.2]])
    assert np.allclose(est.predict_proba(None), by_hand)
    # the argmax follows the mean: "rub" for both, though two of the second capture's windows say "pat"
    assert est.predict(None).tolist() == ["rub", "rub"]
    est.set_params(vote="hard")  # the majority of the windows' labels: "rub" (2 of 3), then "pat" (2 of 3)
    assert est.predict(None).tolist() == ["rub", "pat"]


def test_training_on_a_score_keeps_the_epoch_of_the_highest_one():
    from touchbench.classifiers.torch_fit import train

    torch.manual_seed(0)
    net = torch.nn.Linear(3, 2)
    opt = torch.optim.SGD(net.parameters(), lr=0.1)
    x, y = torch.randn(8, 3), torch.tensor([0, 1] * 4)
    made_up = iter([0.2, 0.5, 0.5, 0.4, 0.3, 0.9])  # a test accuracy per epoch
    weights = []

    def score(n):
        weights.append(n.weight.detach().clone())
        return next(made_up)

    history, best = train(torch, net, opt, x, y, np.random.default_rng(0), max_epochs=6, batch_size=4,
                          patience=2, score=score)
    # epoch 2 scores 0.5; epochs 3 (0.5, not higher) and 4 (0.4) make 2 without a higher one: stop after epoch 4
    assert [h["score"] for h in history] == [0.2, 0.5, 0.5, 0.4]
    assert best == 2
    assert torch.equal(net.weight, weights[1])  # epoch 2's weights restored


def test_stopped_on_test_keeps_the_epoch_of_the_best_test_accuracy():
    X, y, g = _toy(n_per_class=20, seed=1)
    rng = np.random.default_rng(3)
    X = X + rng.normal(0, 4.0, size=X.shape)  # a hard task: the test accuracy moves from epoch to epoch
    test = g == "s0"
    est = make_classifier("cnn", random_state=0, **{**SMALL, "max_epochs": 12, "learning_rate": 3e-3},
                          patience=100, validation_fraction=0.5)
    est.fit(X[~test], y[~test], groups=g[~test], test_set=(X[test], y[test]))
    scores = [h["score"] for h in est.history_]
    assert len(scores) == 12 and est.validation_size_ == 0  # no validation split: the test data stop it
    assert len(set(scores)) > 1
    assert est.best_epoch_ == 1 + int(np.argmax(scores))  # the first epoch of the highest test accuracy
    # the kept network labels the test captures with that accuracy (computed here from its labels)
    assert np.mean(est.predict(X[test]) == y[test]) == pytest.approx(max(scores))
