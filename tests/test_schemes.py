"""The evaluation schemes: the folds themselves, checked against hand-built metadata.

Each test builds a small metadata table whose right folds can be worked out
by hand (which captures must be tested, which must never share a fold) and
checks the splitter's folds against that, not against its own output.
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snapshots.registries import builtin_names, snapshot

from touchbench.core.errors import UnknownNameError
from touchbench.protocols.schemes import SPLITTERS, Crop, Fold, SplitError, fold_notes, make_splitter


def table(rows: list[dict]) -> pd.DataFrame:
    meta = pd.DataFrame(rows)
    meta.insert(0, "capture_id", [f"c{i}" for i in range(len(meta))])
    return meta


def grid(subjects, gestures, per=1, **extra) -> pd.DataFrame:
    keys = ["subject", "gesture", *extra]
    rows = [dict(zip(keys, combo)) for combo in itertools.product(subjects, gestures, *extra.values()) for _ in range(per)]
    return table(rows)


def each_tested_once(folds: list[Fold], n: int) -> bool:
    counts = np.zeros(n, dtype=int)
    for f in folds:
        np.add.at(counts, f.test, 1)
    return bool((counts == 1).all())


def col(meta, name, idx):
    return set(meta[name].to_numpy()[idx].astype(str))


def no_leak(meta, folds, column="subject") -> bool:
    return all(not (col(meta, column, f.train) & col(meta, column, f.test)) for f in folds)


def disjoint(f: Fold) -> bool:
    return not set(f.train.tolist()) & set(f.test.tolist())


SUBJECTS = [f"s{i:02d}" for i in range(1, 7)]
GESTURES = ["pat", "rub", "stroke"]


def test_registry_holds_every_scheme_and_suggests():
    assert builtin_names(SPLITTERS) == snapshot()["evaluation schemes"]  # tests/snapshots/registry-names.json
    with pytest.raises(UnknownNameError, match="did you mean 'loso'"):
        SPLITTERS.get("loos")


# ----------------------------------------------------------------- loso
def test_loso_one_fold_per_subject_each_capture_once_no_leak():
    meta = grid(SUBJECTS, GESTURES, per=2)
    folds = make_splitter("loso").folds(meta)
    assert [f.name for f in folds] == [f"subject={s}" for s in SUBJECTS]
    for f, s in zip(folds, SUBJECTS):
        assert col(meta, "subject", f.test) == {s}
        assert len(f.test) == 6 and len(f.train) == 30
        assert f.group == s and disjoint(f)
    assert no_leak(meta, folds)
    assert each_tested_once(folds, len(meta))


def test_loso_restricted_subjects_train_on_all_others():
    meta = grid(SUBJECTS, GESTURES)
    folds = make_splitter("loso", subjects=["s01", "s03"]).folds(meta)
    assert [f.name for f in folds] == ["subject=s01", "subject=s03"]
    assert col(meta, "subject", folds[0].train) == set(SUBJECTS) - {"s01"}
    assert not make_splitter("loso", subjects=["s01"]).tests_each_capture_once()


def test_loso_refuses_one_subject_and_unknown_subjects():
    with pytest.raises(SplitError, match="at least 2"):
        make_splitter("loso").folds(grid(["s01"], GESTURES))
    with pytest.raises(SplitError, match="unknown subject"):
        make_splitter("loso", subjects=["s99"]).folds(grid(SUBJECTS, GESTURES))


def test_loso_subject_with_one_capture_is_a_fold_of_one():
    meta = table([{"subject": "s1", "gesture": "pat"}, {"subject": "s2", "gesture": "pat"},
                  {"subject": "s2", "gesture": "rub"}, {"subject": "s1", "gesture": "rub"},
                  {"subject": "s3", "gesture": "rub"}])
    sp = make_splitter("loso")
    folds = sp.folds(meta)
    assert [len(f.test) for f in folds] == [2, 2, 1]
    assert any("single capture" in n for n in sp.notes_)


# ----------------------------------------------------------------- kfold
def test_kfold_stratified_partition_and_balance():
    # 3 classes x 10 captures, k = 5: every fold tests exactly 2 of each class.
    meta = grid(SUBJECTS[:5], GESTURES, per=2)
    folds = make_splitter("kfold", k=5, random_state=3).folds(meta)
    assert len(folds) == 5 and each_tested_once(folds, len(meta))
    for f in folds:
        assert disjoint(f) and len(f.test) + len(f.train) == len(meta)
        counts = meta["gesture"].to_numpy()[f.test]
        assert sorted(np.unique(counts, return_counts=True)[1].tolist()) == [2, 2, 2]


def test_kfold_repeats_each_a_partition_and_seeded():
    meta = grid(SUBJECTS, GESTURES, per=2)
    folds = make_splitter("kfold", k=4, repeats=3, random_state=1).folds(meta)
    assert len(folds) == 12
    for r in range(3):
        rep = [f for f in folds if f.group == f"r{r}"]
        assert len(rep) == 4 and each_tested_once(rep, len(meta))
    again = make_splitter("kfold", k=4, repeats=3, random_state=1).folds(meta)
    assert all(np.array_equal(a.test, b.test) for a, b in zip(folds, again))
    other = make_splitter("kfold", k=4, repeats=3, random_state=2).folds(meta)
    assert not all(np.array_equal(a.test, b.test) for a, b in zip(folds, other))
    # the repeats differ from each other
    assert not np.array_equal(folds[0].test, folds[4].test)


def test_kfold_grouped_keeps_subjects_apart():
    meta = grid(SUBJECTS, GESTURES, per=2)
    sp = make_splitter("kfold", k=3, grouped=True, random_state=0)
    folds = sp.folds(meta)
    assert sp.keeps_subjects_apart()
    assert no_leak(meta, folds) and each_tested_once(folds, len(meta))
    # without grouping subjects do appear on both sides
    assert not no_leak(meta, make_splitter("kfold", k=3).folds(meta))


def test_kfold_refuses_more_folds_than_captures_or_groups():
    meta = grid(SUBJECTS[:2], GESTURES)  # 6 captures, 2 subjects
    with pytest.raises(SplitError, match="k=10 folds but only 6 captures"):
        make_splitter("kfold", k=10).folds(meta)
    with pytest.raises(SplitError, match="only 2 groups"):
        make_splitter("kfold", k=3, grouped=True).folds(meta)


def test_kfold_class_smaller_than_k_is_handled_and_noted():
    rows = [{"subject": "s1", "gesture": "pat"}] * 10 + [{"subject": "s1", "gesture": "rub"}] * 10
    rows += [{"subject": "s2", "gesture": "tickle"}] * 2
    meta = table(rows)
    sp = make_splitter("kfold", k=5, random_state=0)
    folds = sp.folds(meta)
    assert each_tested_once(folds, len(meta))
    tickle_folds = [f for f in folds if "tickle" in col(meta, "gesture", f.test)]
    assert len(tickle_folds) == 2  # two captures, two different test folds
    assert any("'tickle' has 2 captures, fewer than k=5" in n for n in sp.notes_)


def test_kfold_every_class_smaller_than_k_still_splits():
    # Flagg's 100-fold CV on a small set: scikit-learn's StratifiedKFold refuses this.
    meta = grid(["s1"], GESTURES, per=4)  # 12 captures, 4 per class, k = 12
    folds = make_splitter("kfold", k=12).folds(meta)
    assert all(len(f.test) == 1 for f in folds) and each_tested_once(folds, 12)


@settings(max_examples=40, deadline=None)
@given(n_per=st.lists(st.integers(1, 9), min_size=2, max_size=5), k=st.integers(2, 6), seed=st.integers(0, 1000))
def test_kfold_property_partition_and_stratified(n_per, k, seed):
    rows = [{"subject": f"s{i % 3}", "gesture": f"g{c}"} for c, n in enumerate(n_per) for i in range(n)]
    meta = table(rows)
    if len(meta) < k:
        with pytest.raises(SplitError):
            make_splitter("kfold", k=k, random_state=seed).folds(meta)
        return
    folds = make_splitter("kfold", k=k, random_state=seed).folds(meta)
    assert each_tested_once(folds, len(meta))
    sizes = [len(f.test) for f in folds]
    assert max(sizes) - min(sizes) <= 1
    y = meta["gesture"].to_numpy()
    for c in np.unique(y):
        per_fold = [int((y[f.test] == c).sum()) for f in folds]
        assert max(per_fold) - min(per_fold) <= 1  # each class spread as evenly as possible


# ----------------------------------------------------------------- within-subject
def test_within_subject_models_see_one_subject_and_test_each_capture_once():
    meta = grid(SUBJECTS[:3], GESTURES, per=3)  # 9 captures per subject
    folds = make_splitter("within-subject", k=3, random_state=0).folds(meta)
    assert len(folds) == 9
    for f in folds:
        assert col(meta, "subject", f.train) == col(meta, "subject", f.test) == {f.group}
        assert disjoint(f)
        assert sorted(np.unique(meta["gesture"].to_numpy()[f.test], return_counts=True)[1].tolist()) == [1, 1, 1]
    assert each_tested_once(folds, len(meta))


def test_within_subject_small_subjects_capped_or_left_out():
    rows = [{"subject": "a", "gesture": g} for g in ["pat", "rub"] * 5]  # 10 captures
    rows += [{"subject": "b", "gesture": g} for g in ["pat", "rub", "pat"]]  # 3 < k
    rows += [{"subject": "c", "gesture": "pat"}]  # 1 capture: cannot cross-validate
    meta = table(rows)
    sp = make_splitter("within-subject", k=5)
    folds = sp.folds(meta)
    assert sum(f.group == "a" for f in folds) == 5
    assert sum(f.group == "b" for f in folds) == 3  # leave-one-out for b
    assert not any(f.group == "c" for f in folds)
    tested = np.concatenate([f.test for f in folds])
    assert sorted(tested.tolist()) == list(range(13))  # all but c's capture, once
    assert any("'c'" in n and "left out" in n for n in sp.notes_)
    assert any("subject 'b' has 3 captures < k=5" in n for n in sp.notes_)


def test_within_subject_refuses_subject_target():
    with pytest.raises(SplitError, match="one model per subject"):
        make_splitter("within-subject", target="subject").folds(grid(SUBJECTS, GESTURES, per=3))


# ----------------------------------------------------------------- leave-recording-out
def test_leave_recording_out_trains_on_one_session_tests_on_the_other():
    meta = grid(SUBJECTS[:4], GESTURES, per=2, session=["r1", "r2"])
    folds = make_splitter("leave-recording-out").folds(meta)
    assert [f.name for f in folds] == ["test=recording1", "test=recording2"]
    a, b = folds
    assert col(meta, "session", a.test) == {"r1"} and col(meta, "session", a.train) == {"r2"}
    assert col(meta, "session", b.test) == {"r2"} and col(meta, "session", b.train) == {"r1"}
    # every person is on both sides (one session each)
    assert col(meta, "subject", a.train) == col(meta, "subject", a.test) == set(SUBJECTS[:4])
    assert each_tested_once(folds, len(meta))


def test_leave_recording_out_orders_sessions_naturally_per_subject():
    rows = [{"subject": "p1", "gesture": "pat", "session": s} for s in ["r10", "r2"]]
    rows += [{"subject": "p2", "gesture": "pat", "session": s} for s in ["day2", "day1"]]
    meta = table(rows)
    first = make_splitter("leave-recording-out").folds(meta)[0]
    assert set(meta["session"].to_numpy()[first.test]) == {"r2", "day1"}


def test_leave_recording_out_drops_subjects_with_one_recording():
    rows = [{"subject": "p1", "gesture": g, "session": s} for g in GESTURES for s in (1, 2)]
    rows += [{"subject": "p2", "gesture": g, "session": 1} for g in GESTURES]
    meta = table(rows)
    sp = make_splitter("leave-recording-out")
    folds = sp.folds(meta)
    assert all(col(meta, "subject", np.concatenate([f.train, f.test])) == {"p1"} for f in folds)
    assert any("['p2']" in n and "left out" in n for n in sp.notes_)


def test_leave_recording_out_needs_the_column():
    with pytest.raises(SplitError, match="needs the metadata column 'session'"):
        make_splitter("leave-recording-out").folds(grid(SUBJECTS, GESTURES))


# ----------------------------------------------------------------- person-independent
def test_person_independent_four_parties_of_six():
    subjects = [f"p{i:02d}" for i in range(24)]
    meta = grid(subjects, GESTURES)
    sp = make_splitter("person-independent", k=4, random_state=7)
    folds = sp.folds(meta)
    assert len(folds) == 4 and sp.keeps_subjects_apart()
    parties = [col(meta, "subject", f.test) for f in folds]
    assert [len(p) for p in parties] == [6, 6, 6, 6]
    assert set().union(*parties) == set(subjects)
    assert all(not (p & q) for p, q in itertools.combinations(parties, 2))
    assert no_leak(meta, folds) and each_tested_once(folds, len(meta))
    # seeded: same seed, same parties; another seed, other parties
    again = [col(meta, "subject", f.test) for f in make_splitter("person-independent", k=4, random_state=7).folds(meta)]
    other = [col(meta, "subject", f.test) for f in make_splitter("person-independent", k=4, random_state=8).folds(meta)]
    assert again == parties and other != parties


def test_person_independent_uneven_and_too_few():
    meta = grid(SUBJECTS[:5], GESTURES)
    sp = make_splitter("person-independent", k=2)
    assert sorted(len(col(meta, "subject", f.test)) for f in sp.folds(meta)) == [2, 3]
    assert sp.notes_
    with pytest.raises(SplitError, match="k=6 parties but only 5"):
        make_splitter("person-independent", k=6).folds(meta)


# ----------------------------------------------------------------- transfer
def test_transfer_both_directions():
    rows = [{"subject": f"a{i}", "gesture": g, "group": "A"} for i in range(3) for g in GESTURES]
    rows += [{"subject": f"b{i}", "gesture": g, "group": "B"} for i in range(2) for g in GESTURES]
    meta = table(rows)
    is_a = np.flatnonzero(meta["group"] == "A")
    is_b = np.flatnonzero(meta["group"] == "B")
    folds = make_splitter("transfer").folds(meta)
    assert [f.name for f in folds] == ["A->B", "B->A"]
    assert np.array_equal(folds[0].train, is_a) and np.array_equal(folds[0].test, is_b)
    assert np.array_equal(folds[1].train, is_b) and np.array_equal(folds[1].test, is_a)
    one_way = make_splitter("transfer", groups=["B", "A"], both_directions=False).folds(meta)
    assert [f.name for f in one_way] == ["B->A"]


def test_transfer_three_groups_and_errors():
    meta = grid(SUBJECTS[:3], GESTURES, group=["A", "B", "C"])
    assert len(make_splitter("transfer").folds(meta)) == 6
    with pytest.raises(SplitError, match="unknown group value"):
        make_splitter("transfer", groups=["A", "Z"]).folds(meta)
    sp = make_splitter("transfer", groups=["A", "B"])
    sp.folds(meta)
    assert any("in both groups" in n for n in sp.notes_)  # same people in A and B


# ----------------------------------------------------------------- challenge
def test_challenge_split_column_and_subject_lists():
    rows = [{"subject": s, "gesture": g, "split": ("test" if s in ("s01", "s02") else "train")} for s in SUBJECTS for g in GESTURES]
    rows.append({"subject": "s09", "gesture": "pat", "split": "none"})
    meta = table(rows)
    sp = make_splitter("challenge")
    (f,) = sp.folds(meta)
    assert col(meta, "subject", f.test) == {"s01", "s02"} and len(f.train) == 12
    assert any("1 captures are in neither" in n for n in sp.notes_)
    (g,) = make_splitter("challenge", test_subjects=["s03"]).folds(meta)
    assert col(meta, "subject", g.test) == {"s03"} and "s03" not in col(meta, "subject", g.train)


# ----------------------------------------------------------------- early
def test_early_repeats_base_folds_per_length_with_crop():
    meta = grid(SUBJECTS[:3], GESTURES)
    sp = make_splitter("early", base={"name": "loso"}, frames=[5, 20])
    folds = sp.folds(meta)
    assert [f.name for f in folds] == [f"first{n}f/subject={s}" for n in (5, 20) for s in SUBJECTS[:3]]
    assert all(f.extra(Crop) == Crop(frames=n, train=False) for f, n in zip(folds, [5] * 3 + [20] * 3))
    assert no_leak(meta, folds)
    s = make_splitter("early", base={"name": "kfold", "k": 3}, seconds=[0.5], crop_train=True).folds(meta)
    assert len(s) == 3 and s[0].extra(Crop).train and s[0].extra(Crop).n_frames(54.0) == 27


def test_early_validates_its_parameters():
    with pytest.raises(ValueError, match="exactly one of"):
        make_splitter("early", base={"name": "loso"})
    with pytest.raises(ValueError, match="cannot be 'early'"):
        make_splitter("early", base={"name": "early"}, frames=[3])


# ----------------------------------------------------------------- targets and fold notes
@pytest.mark.parametrize("name,params", [("loso", {}), ("person-independent", {"k": 2}), ("kfold", {"grouped": True, "k": 2})])
def test_person_identification_refused_where_subjects_are_kept_apart(name, params):
    with pytest.raises(SplitError, match="person identification"):
        make_splitter(name, target="subject", **params).folds(grid(SUBJECTS, GESTURES, per=2))


def test_person_identification_with_kfold_stratifies_on_subject():
    meta = grid(SUBJECTS[:3], GESTURES, per=2)
    folds = make_splitter("kfold", target="subject", k=2).folds(meta)
    for f in folds:
        assert sorted(np.unique(meta["subject"].to_numpy()[f.test], return_counts=True)[1].tolist()) == [3, 3, 3]


def test_fold_notes_describe_extremes():
    y = np.array(["pat", "pat", "rub", "tickle", "tickle"])
    notes = fold_notes(Fold("f", [0, 1], [2, 3, 4]), y)
    assert "classes absent from training: 'rub' (1 test captures), 'tickle' (2 test captures)" in notes[0]
    assert any("single class 'pat'" in n and "constant prediction" in n for n in notes)
    assert fold_notes(Fold("g", [0, 2], [3, 4]), y)[-1] == "test fold has a single class 'tickle'"
    assert fold_notes(Fold("h", [0, 2, 3], [1, 4]), y) == []


# ----------------------------------------------------------------- the registry finds its package's modules
def test_every_scheme_module_registers_and_the_registry_finds_it_by_itself():
    """Each module of the package (other than ``base``) holds a scheme, and the registry imports
    them all on first use: nothing imports a scheme module by hand."""
    import importlib
    import pkgutil

    import touchbench.protocols.schemes as package

    modules = sorted(f"{package.__name__}.{m.name}" for m in pkgutil.iter_modules(package.__path__)
                     if not m.name.startswith("_") and m.name != "base")
    registered = {e.obj.__module__ for e in SPLITTERS.entries() if e.plugin is None}
    assert registered == set(modules)
    assert builtin_names(SPLITTERS) == snapshot()["evaluation schemes"]
    for e in SPLITTERS.entries():  # a module is named for its scheme
        if e.plugin is None:
            assert e.obj.__module__.rpartition(".")[2] == e.name.replace("-", "_")
    assert importlib.import_module("touchbench.protocols.schemes.base").SPLITTERS is SPLITTERS


# ----------------------------------------------------------------- scikit-learn's interface
def _features(meta, seed=0):
    """Features that tell the gestures apart (a little), one row per capture."""
    rng = np.random.default_rng(seed)
    codes = pd.factorize(meta["gesture"])[0]
    return codes[:, None] + rng.normal(0, 0.8, (len(meta), 3))


def test_loso_split_matches_leave_one_group_out():
    from sklearn.model_selection import LeaveOneGroupOut

    meta = grid(SUBJECTS, GESTURES, per=2)
    X, y, groups = _features(meta), meta["gesture"].to_numpy(), meta["subject"].to_numpy()
    sp = make_splitter("loso")
    ours = list(sp.split(X, y, groups))
    theirs = list(LeaveOneGroupOut().split(X, y, groups))
    assert sp.get_n_splits(X, y, groups) == LeaveOneGroupOut().get_n_splits(X, y, groups) == len(ours) == 6
    assert [(a.tolist(), b.tolist()) for a, b in ours] == [(a.tolist(), b.tolist()) for a, b in theirs]
    from_meta = [(f.train.tolist(), f.test.tolist()) for f in sp.folds(meta)]
    assert [(a.tolist(), b.tolist()) for a, b in sp.split(meta)] == from_meta


def test_cross_val_score_takes_a_scheme_as_cv():
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import LeaveOneGroupOut, cross_val_score

    meta = grid(SUBJECTS, GESTURES, per=3)
    X, y, groups = _features(meta), meta["gesture"].to_numpy(), meta["subject"].to_numpy()
    ours = cross_val_score(LogisticRegression(), X, y, groups=groups, cv=make_splitter("loso"))
    theirs = cross_val_score(LogisticRegression(), X, y, groups=groups, cv=LeaveOneGroupOut())
    assert len(ours) == 6 and np.array_equal(ours, theirs)


def test_split_of_the_metadata_table_is_folds():
    from sklearn.model_selection import GridSearchCV
    from sklearn.neighbors import KNeighborsClassifier

    meta = grid(SUBJECTS, GESTURES, per=2, session=["r1", "r2"])
    sp = make_splitter("leave-recording-out")
    assert [(a.tolist(), b.tolist()) for a, b in sp.split(meta)] == [(f.train.tolist(), f.test.tolist())
                                                                      for f in sp.folds(meta)]
    assert sp.get_n_splits(meta) == 2
    search = GridSearchCV(KNeighborsClassifier(), {"n_neighbors": [1, 3]}, cv=make_splitter("kfold", k=4))
    search.fit(_features(meta), meta["gesture"].to_numpy())
    assert sorted(k for k in search.cv_results_ if k.startswith("split")) == [f"split{i}_test_score" for i in range(4)]


def test_split_refuses_what_index_splits_cannot_say():
    meta = grid(SUBJECTS, GESTURES, per=2)
    y, groups = meta["gesture"].to_numpy(), meta["subject"].to_numpy()
    with pytest.raises(SplitError, match="needs the metadata column 'session'.*pass the metadata table as X"):
        list(make_splitter("leave-recording-out").split(np.zeros((len(y), 2)), y, groups))
    with pytest.raises(SplitError, match="needs the metadata column 'gesture'"):
        list(make_splitter("loso").split(np.zeros((len(y), 2)), groups=groups))
    with pytest.raises(SplitError, match="cuts captures"):
        list(make_splitter("early", base="loso", frames=[3]).split(meta))
    with pytest.raises(SplitError, match="depends on the data"):
        make_splitter("loso").get_n_splits()
    assert make_splitter("kfold", k=5, repeats=2).get_n_splits() == 10


# ----------------------------------------------------------------- what a scheme declares to the others
def test_a_wrapping_scheme_declares_its_base_and_its_sweep():
    from touchbench.reports.results import scheme_label

    early = SPLITTERS.get("early")
    assert early.base_param == "base" and early.swept_params == ("frames", "seconds")
    assert SPLITTERS.get("stream").base_param == "base" and SPLITTERS.get("stream").swept_params == ("rules",)
    assert SPLITTERS.get("learning-curve").swept_params == ("subjects", "fractions", "draws")
    assert SPLITTERS.get("calibration").swept_params == ("draws",)  # per_class sets the scored captures
    wrapping = ("early", "stream", "learning-curve", "calibration")
    assert all(SPLITTERS.get(n).base_param == "base" for n in wrapping)
    assert all(SPLITTERS.get(n).base_param is None and not SPLITTERS.get(n).swept_params
               for n in SPLITTERS.names() if n not in wrapping)
    entry = {"name": "early", "base": {"name": "kfold", "k": 5}, "frames": [1, 5], "crop_train": True}
    assert scheme_label(entry) == "early(base=kfold(k=5),crop_train=true)"
    assert scheme_label({"name": "no-such-scheme", "frames": [1]}) == "no-such-scheme(frames=[1])"


def test_prepare_leaves_the_data_of_most_schemes_alone():
    from touchbench.protocols.schemes import DataContext

    def refuse(*a):
        raise AssertionError("loads nothing")

    context = DataContext(dataset_name="d", notes=[], load=refuse, error_at=refuse)
    ds = object()
    for name, params in [("loso", {}), ("kfold", {}), ("early", {"base": "loso", "frames": [3]})]:
        assert make_splitter(name, **params).prepare(ds, context) is ds
    assert context.notes == []
