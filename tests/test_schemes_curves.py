"""The data-curve schemes: ``learning-curve`` (n of a fold's training subjects) and ``calibration``
(k labelled captures per class of the test side in training).

The folds are checked against small metadata tables whose right answers are worked out by hand
(which subjects may be drawn, how many subsets exist, which captures may be scored); the engine
tests run tiny datasets built so that the accuracy of each point is known before the run.
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from pydantic import ValidationError

from touchbench.datasets.model import TouchDataset
from touchbench.engine import run_protocol
from touchbench.engine.testing import SENSOR
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol
from touchbench.protocols.schemes import Crop, CurvePoint, SplitError, make_splitter


def grid(subjects, gestures, per=1, **extra) -> pd.DataFrame:
    keys = ["subject", "gesture", *extra]
    rows = [dict(zip(keys, c)) for c in itertools.product(subjects, gestures, *extra.values()) for _ in range(per)]
    meta = pd.DataFrame(rows)
    meta.insert(0, "capture_id", [f"c{i}" for i in range(len(meta))])
    return meta


SIX = [f"s{i}" for i in range(1, 7)]


def subjects_of(meta, idx) -> set[str]:
    return set(meta["subject"].to_numpy()[idx].tolist())


def by_base(folds) -> dict[str, list]:
    out: dict[str, list] = {}
    for f in folds:
        out.setdefault(f.name.split("/", 1)[1], []).append(f)
    return out


# ----------------------------------------------------------------- learning curve
def test_learning_curve_draws_distinct_subsets_of_the_training_subjects_and_keeps_the_test():
    meta = grid(SIX, ["pat", "rub"], per=2)  # 4 captures per subject
    base = {f.name: f for f in make_splitter("loso").folds(meta)}
    folds = make_splitter("learning-curve", base="loso", subjects=[1, 2, 3], draws=4, random_state=3).folds(meta)
    # 5 training subjects: C(5,1) = 5, C(5,2) = C(5,3) = 10 subsets, all more than 4 draws; + the full point
    assert len(folds) == 6 * (3 * 4 + 1)
    for name, points in by_base(folds).items():
        b = base[name]
        held = subjects_of(meta, b.test)
        for n in (1, 2, 3):
            drawn = [f for f in points if f.extra(CurvePoint).size == n]
            assert [f.extra(CurvePoint) for f in drawn] == [CurvePoint("subjects", n, d) for d in range(4)]
            assert [f.name for f in drawn] == [f"n{n}#{d}/{name}" for d in range(4)]
            sets = [frozenset(subjects_of(meta, f.train)) for f in drawn]
            assert len(set(sets)) == 4 and all(len(s) == n and not s & held for s in sets)
            for f, s in zip(drawn, sets):
                assert len(f.train) == 4 * n  # every capture of the drawn subjects, nothing else
                assert np.array_equal(f.test, b.test) and f.group == b.group
        full = [f for f in points if f.extra(CurvePoint) == CurvePoint("subjects", 5, 0)]
        assert len(full) == 1 and np.array_equal(full[0].train, b.train) and np.array_equal(full[0].test, b.test)
        assert full[0].name == f"n5#0/{name}"


def test_learning_curve_draws_subjects_at_random_not_by_position():
    meta = grid(SIX, ["pat"], per=2)
    seen = set()
    for seed in range(40):
        sp = make_splitter("learning-curve", base={"name": "loso", "subjects": ["s1"]}, subjects=[1], draws=1,
                           random_state=seed)
        one = next(f for f in sp.folds(meta) if f.extra(CurvePoint).size == 1)
        seen |= subjects_of(meta, one.train)
    assert seen == {"s2", "s3", "s4", "s5", "s6"}  # the first subjects by position would give only s2


def test_learning_curve_with_fewer_subsets_than_draws_takes_each_once_and_says_so():
    meta = grid(["a", "b", "c", "d"], ["pat", "rub"])
    folds = make_splitter("learning-curve", base={"name": "loso", "subjects": ["a"]}, subjects=[1, 2],
                          draws=5).folds(meta)
    ones = [f for f in folds if f.extra(CurvePoint).size == 1]
    twos = [f for f in folds if f.extra(CurvePoint).size == 2]
    assert sorted(min(subjects_of(meta, f.train)) for f in ones) == ["b", "c", "d"]  # C(3,1) = 3 < 5
    assert sorted(tuple(sorted(subjects_of(meta, f.train))) for f in twos) == [("b", "c"), ("b", "d"), ("c", "d")]
    assert [f.extra(CurvePoint).draw for f in ones] == [0, 1, 2]
    assert all("only 3 distinct subset(s), fewer than draws=5: each is drawn once" in f.notes[0] for f in ones + twos)
    full = [f for f in folds if f.extra(CurvePoint).size == 3]
    assert len(full) == 1 and full[0].notes == ()


def test_learning_curve_fractions_round_half_up_and_end_at_one():
    meta = grid(SIX, ["pat"])  # loso: 5 training subjects
    folds = make_splitter("learning-curve", base="loso", fractions=[0.1, 0.5], draws=2).folds(meta)
    sizes = {(f.extra(CurvePoint).size, len(subjects_of(meta, f.train))) for f in folds}
    # 0.1 x 5 = 0.5 -> 1 (and at least 1), 0.5 x 5 = 2.5 -> 3, the full point 5
    assert sizes == {(0.1, 1), (0.5, 3), (1.0, 5)}
    assert {f.name.split("/")[0] for f in folds} == {"f0.1#0", "f0.1#1", "f0.5#0", "f0.5#1", "f1#0"}


def test_learning_curve_stratified_spreads_the_subjects_over_the_column():
    site = {"s1": "A", "s2": "A", "s3": "A", "s4": "A", "s5": "B", "s6": "B"}
    meta = grid(SIX, ["pat"])
    meta["site"] = meta["subject"].map(site)
    sp = make_splitter("learning-curve", base={"name": "loso", "subjects": ["s1"]}, subjects=[2, 3], draws=8,
                       stratify="site")
    folds = sp.folds(meta)
    # training: A = s2, s3, s4 and B = s5, s6. n = 2: one of each, 3 x 2 = 6 subsets (< 8 draws: each once)
    twos = [sorted(subjects_of(meta, f.train)) for f in folds if f.extra(CurvePoint).size == 2]
    assert sorted(map(tuple, twos)) == sorted((a, b) for a in ("s2", "s3", "s4") for b in ("s5", "s6"))
    # n = 3: 2 + 1 or 1 + 2: 3 x 2 + 3 x 1 = 9 subsets (> 8 draws: 8 distinct ones)
    threes = [subjects_of(meta, f.train) for f in folds if f.extra(CurvePoint).size == 3]
    assert len(threes) == 8 and len({frozenset(s) for s in threes}) == 8
    assert all({site[s] for s in t} == {"A", "B"} for t in threes)


def test_learning_curve_is_deterministic_and_seeded():
    meta = grid(SIX, ["pat", "rub"])

    def folds(seed):
        return make_splitter("learning-curve", base="loso", subjects=[2], draws=3, random_state=seed).folds(meta)

    a, b, c = folds(5), folds(5), folds(6)
    assert [(f.name, f.train.tolist(), f.test.tolist()) for f in a] == [(f.name, f.train.tolist(), f.test.tolist()) for f in b]
    assert [f.train.tolist() for f in a] != [f.train.tolist() for f in c]


@pytest.mark.parametrize("params,message", [
    ({"subjects": [0, 2]}, "at least 1"),
    ({"fractions": [0.0]}, r"in \(0, 1\]"),
    ({"fractions": [1.5]}, r"in \(0, 1\]"),
    ({"subjects": [1], "fractions": [0.5]}, "exactly one of 'subjects'"),
    ({}, "exactly one of 'subjects'"),
    ({"subjects": [1], "base": {"name": "kfold", "k": 3}}, "does not keep subjects apart"),
    ({"subjects": [1], "base": {"name": "calibration", "base": "loso", "per_class": [1]}}, "cannot be 'calibration'"),
])
def test_learning_curve_refuses_bad_parameters(params, message):
    with pytest.raises(ValidationError, match=message):
        make_splitter("learning-curve", **{"base": "loso", **params})


def test_learning_curve_refuses_more_subjects_than_a_fold_trains_on_and_a_varying_stratum():
    meta = grid(SIX, ["pat"])
    with pytest.raises(SplitError, match="subjects: 6 is more than the 5 training subjects of fold 'subject=s1'"):
        make_splitter("learning-curve", base="loso", subjects=[2, 6]).folds(meta)
    meta["session"] = [1, 2] * 3
    meta = pd.concat([meta, meta.assign(session=meta["session"] % 2 + 1)], ignore_index=True)
    with pytest.raises(SplitError, match="stratify: 'session' must give each subject one value"):
        make_splitter("learning-curve", base="loso", subjects=[2], stratify="session").folds(meta)


def test_learning_curve_over_grouped_kfold_keeps_each_folds_test():
    meta = grid(SIX, ["pat", "rub"])
    base = make_splitter("kfold", k=3, grouped=True, random_state=1).folds(meta)
    folds = make_splitter("learning-curve", base={"name": "kfold", "k": 3, "grouped": True}, subjects=[1],
                          draws=2, random_state=1).folds(meta)
    for b in base:
        mine = [f for f in folds if f.name.endswith("/" + b.name)]
        assert all(np.array_equal(f.test, b.test) for f in mine)
        assert all(subjects_of(meta, f.train) <= subjects_of(meta, b.train) for f in mine)


# ----------------------------------------------------------------- calibration
def test_calibration_scores_the_same_captures_for_every_k_and_never_the_calibration_ones():
    meta = grid(["s1", "s2", "s3", "s4"], ["pat", "rub"], per=4)  # 4 captures per subject and class
    base = {f.name: f for f in make_splitter("loso").folds(meta)}
    folds = make_splitter("calibration", base="loso", per_class=[3, 1], draws=2, random_state=2).folds(meta)
    assert len(folds) == 4 * 2 * 3  # 0 is added: k = 0, 1, 3
    y = meta["gesture"].to_numpy()
    for name, b in base.items():
        for d in range(2):
            points = {f.extra(CurvePoint).size: f for f in folds if f.name.endswith("/" + name) and f.extra(CurvePoint).draw == d}
            assert sorted(points) == [0, 1, 3]
            assert [points[k].name for k in (0, 1, 3)] == [f"k0#{d}/{name}", f"k1#{d}/{name}", f"k3#{d}/{name}"]
            scored = points[0].test
            # 4 per class in the held-out subject, the k = 3 pool takes 3 of each: 1 per class scored
            assert len(scored) == 2 and set(scored) <= set(b.test) and sorted(y[scored]) == ["pat", "rub"]
            calib = {}
            for k, f in points.items():
                assert np.array_equal(f.test, scored) and f.extra(CurvePoint) == CurvePoint("calibration", k, d)
                extra = np.setdiff1d(f.train, b.train)
                assert set(b.train) <= set(f.train) and len(f.train) == len(b.train) + 2 * k
                assert not set(extra) & set(scored) and set(extra) <= set(b.test)
                assert sorted(y[extra]) == ["pat"] * int(k) + ["rub"] * int(k)
                calib[k] = set(extra)
            assert np.array_equal(points[0].train, b.train) and not calib[0]
            assert calib[1] < calib[3]  # nested: k = 1 takes the first of the k = 3 pool
            assert len(b.test) - len(scored) == len(calib[3])  # what is not scored is exactly the largest pool


def test_calibration_draws_differ_and_are_seeded():
    meta = grid(["s1", "s2", "s3"], ["pat", "rub"], per=6)

    def pools(seed):
        folds = make_splitter("calibration", base="loso", per_class=[2], draws=3, random_state=seed).folds(meta)
        return [tuple(f.train.tolist()) for f in folds if f.extra(CurvePoint).size == 2]

    assert pools(1) == pools(1) and pools(1) != pools(2)
    assert len(set(pools(1))) == len(pools(1))  # 9 draws over 3 folds: C(6,2)^2 = 225 possible pools each


def test_calibration_short_class_gives_all_but_one_and_says_so():
    meta = grid(["s1", "s2"], ["pat", "rub"], per=3)
    meta = meta.drop(index=meta.index[(meta["subject"] == "s1") & (meta["gesture"] == "rub")][:1]).reset_index(drop=True)
    folds = make_splitter("calibration", base={"name": "loso", "subjects": ["s1"]}, per_class=[2]).folds(meta)
    f2 = next(f for f in folds if f.extra(CurvePoint).size == 2 and f.extra(CurvePoint).draw == 0)
    y = meta["gesture"].to_numpy()
    # s1 has 3 pat (2 go to training) and 2 rub (k = 2 would leave none: 1 goes): 1 pat and 1 rub scored
    assert sorted(y[f2.test]) == ["pat", "rub"]
    assert sorted(y[np.setdiff1d(f2.train, np.flatnonzero(meta["subject"] == "s2"))]) == ["pat", "pat", "rub"]
    assert any("s1/rub (2)" in n and "s1/pat" not in n and "all but one" in n for n in f2.notes)


def test_calibration_records_the_captures_a_capped_point_really_added():
    # s1: 3 pat (at most 2 can train), 2 rub (at most 1): k = 2 adds 2 pat and 1 rub, mean 1.5, least 1;
    # k = 1 adds one of each
    meta = grid(["s1", "s2"], ["pat", "rub"], per=3)
    meta = meta.drop(index=meta.index[(meta["subject"] == "s1") & (meta["gesture"] == "rub")][:1]).reset_index(drop=True)
    sp = make_splitter("calibration", base={"name": "loso", "subjects": ["s1"]}, per_class=[1, 2], draws=1)
    points = {f.extra(CurvePoint).size: f.extra(CurvePoint) for f in sp.folds(meta)}
    assert (points[0].added, points[0].added_min) == (0.0, 0.0)
    assert (points[1].added, points[1].added_min) == (1.0, 1.0)
    assert (points[2].added, points[2].added_min) == (1.5, 1.0)
    [capped] = [n for n in sp.notes_ if "capped" in n]
    assert "k = 2 is capped" in capped and "1 of 2 test subject/class pair(s)" in capped and "1.5" in capped


@pytest.mark.parametrize("per_class,unit,words", [
    ([5], "subject", ["per_class: k = 5", "unit: subject", "more than 2 capture(s)"]),  # 2 per subject and class
    ([1, 3], "subject", ["per_class: k = 3", "at most 1 per class"]),
    ([1], "capture_id", ["per_class: k = 1", "unit: capture_id"]),  # one capture per pool: none can train
])
def test_calibration_refuses_a_point_no_test_unit_can_give(per_class, unit, words):
    meta = grid(["s1", "s2", "s3"], ["pat", "rub"], per=2)
    with pytest.raises(SplitError) as e:
        make_splitter("calibration", base="loso", per_class=per_class, unit=unit).folds(meta)
    assert all(w in str(e.value) for w in words), str(e.value)


@pytest.mark.parametrize("value,message", [
    ("1e9", "whole number"), (1e9, "whole number"), (2.5, "whole number"), (True, "whole number"),
    (1_000_000_000, "at most 10000"),
])
def test_calibration_refuses_per_class_that_is_not_a_sensible_whole_number(value, message):
    with pytest.raises(ValidationError, match=message) as e:
        make_splitter("calibration", base="loso", per_class=[1, value])
    assert "per_class" in str(e.value)


def test_calibration_per_unit_column():
    meta = grid(["s1", "s2"], ["pat"], per=2, session=[1, 2])  # s1: 2 captures in each session
    folds = make_splitter("calibration", base={"name": "loso", "subjects": ["s1"]}, per_class=[1], unit="session",
                          draws=1).folds(meta)
    f1 = next(f for f in folds if f.extra(CurvePoint).size == 1)
    extra = np.setdiff1d(f1.train, np.flatnonzero(meta["subject"] == "s2"))
    assert sorted(meta["session"].to_numpy()[extra]) == [1, 2]  # one per session
    assert sorted(meta["session"].to_numpy()[f1.test]) == [1, 2]


def test_calibration_over_cross_dataset_draws_from_the_test_dataset():
    meta = grid(["a", "b", "x"], ["pat", "rub"], per=2)
    meta["origin"] = np.where(meta["subject"] == "x", "test", "train")
    meta["frames_sha256"] = [f"h{i}" for i in range(len(meta))]
    folds = make_splitter("calibration", base={"name": "cross-dataset", "test": "other"}, per_class=[1],
                          draws=1).folds(meta)
    f1 = next(f for f in folds if f.extra(CurvePoint).size == 1)
    extra = np.setdiff1d(f1.train, np.flatnonzero(meta["origin"] == "train"))
    assert subjects_of(meta, extra) == {"x"} and len(extra) == 2 and len(f1.test) == 2


def test_calibration_says_what_it_is():
    sp = make_splitter("calibration", base="loso", per_class=[2])
    assert not sp.keeps_subjects_apart() and sp.leakage() == "" and sp.params.per_class == [0, 2]
    leaky = make_splitter("calibration", base={"name": "kfold", "k": 3}, per_class=[2])
    assert leaky.leakage() == make_splitter("kfold", k=3).leakage() != ""


@pytest.mark.parametrize("params,message", [
    ({"per_class": [0]}, "at least one number of captures per class above 0"),
    ({"per_class": [-1, 2]}, "at least 0"),
    ({"per_class": [1], "base": {"name": "learning-curve", "base": "loso", "subjects": [1]}},
     "cannot be 'learning-curve'"),
    ({"per_class": [1], "base": {"name": "calibration", "base": "loso", "per_class": [1]}}, "cannot be 'calibration'"),
])
def test_calibration_refuses_bad_parameters(params, message):
    with pytest.raises(ValidationError, match=message):
        make_splitter("calibration", **{"base": "loso", **params})


# ----------------------------------------------------------------- protocol files
PROTOCOL = """\
name: curve
dataset: {data}
scheme:
{scheme}
features:
  - [test-mean]
classifiers:
  - test-interrupt
seed: 3
"""


@pytest.mark.parametrize("scheme,expected", [
    ("  name: learning-curve\n  base: loso\n  subjects: [0]", "curve.yaml:6: scheme.subjects: every number of subjects must be at least 1 (got 0)"),
    ("  name: learning-curve\n  base: {name: kfold, k: 3}\n  subjects: [1]",
     "curve.yaml:3: scheme: base: scheme 'kfold' with these parameters does not keep subjects apart"),
    ("  name: calibration\n  base: loso\n  per_class: [-2]", "curve.yaml:6: scheme.per_class: every number of captures per class must be at least 0 (got -2)"),
    ("  name: calibration\n  base: {name: loso, colum: session}\n  per_class: [1]",
     "curve.yaml:5: scheme.base.colum: unknown field"),
    ("  name: calibration\n  base: loso\n  per_class: [1e9]",
     "curve.yaml:6: scheme.per_class: every number of captures per class must be a whole number"),
])
def test_protocol_errors_name_the_field(tmp_path, engine_env, scheme, expected):
    ds = curve_dataset({"t": {"x": 2}, "a": {"x": 2}, "b": {"y": 2}})
    ds.to_parquet(tmp_path / "data.parquet")
    with pytest.raises(ProtocolError) as e:
        parse_protocol(PROTOCOL.format(data=tmp_path / "data.parquet", scheme=scheme), tmp_path / "curve.yaml")
    assert expected in str(e.value)


# ----------------------------------------------------------------- the engine
LEVEL = {"x": 20, "y": 120, "z": 220, "w": 70}


def curve_dataset(counts: dict[str, dict[str, int]]) -> TouchDataset:
    """Captures of constant value, one value per class (``LEVEL``): a nearest-centroid classifier
    labels a capture right exactly when its class is in the training data."""
    rows = [{"subject": s, "gesture": g} for s, per in counts.items() for g, n in per.items() for _ in range(n)]
    meta = pd.DataFrame(rows)
    meta.insert(0, "capture_id", [f"c{i:03d}" for i in range(len(meta))])
    caps = [np.full((10, *SENSOR.grid), LEVEL[g], dtype=np.uint8) for g in meta["gesture"]]
    return TouchDataset("curve-toy", caps, meta, SENSOR)


def run(tmp_path, ds, scheme: str, out: str) -> pd.DataFrame:
    data = tmp_path / "data.parquet"
    if not data.exists():
        ds.to_parquet(data)
    p = parse_protocol(PROTOCOL.format(data=data, scheme=scheme), tmp_path / f"{out}.yaml")
    res = run_protocol(p, out=tmp_path / out, progress=False)
    assert (res.scores["status"] == "ok").all()
    return res.scores


def test_learning_curve_accuracy_grows_with_the_subjects_and_ends_at_the_plain_scheme(tmp_path, engine_env):
    # t is tested: 2 captures of each of x, y, z, w. a, b, c each show one class (x, y, z); nobody shows w.
    # With n of a, b, c in training, exactly n of the 4 test classes are known: accuracy n / 4, whichever drawn
    ds = curve_dataset({"t": {"x": 2, "y": 2, "z": 2, "w": 2}, "a": {"x": 2}, "b": {"y": 2}, "c": {"z": 2}})
    held = "  name: loso\n  subjects: [t]"
    curve = run(tmp_path, ds, "  name: learning-curve\n  base: {name: loso, subjects: [t]}\n  subjects: [1, 2]\n"
                "  draws: 5", "curve")
    plain = run(tmp_path, ds, held, "plain")
    assert set(curve["curve"]) == {"subjects"} and set(plain["curve"]) == {""}
    # C(3,1) = C(3,2) = 3 distinct subsets, fewer than 5 draws: 3 draws each; the full point once
    assert sorted(zip(curve["curve_size"], curve["curve_draw"])) == [
        (1.0, 0), (1.0, 1), (1.0, 2), (2.0, 0), (2.0, 1), (2.0, 2), (3.0, 0)]
    by_n = curve.groupby("curve_size")["accuracy"]
    assert np.allclose(by_n.min(), [0.25, 0.5, 0.75]) and np.allclose(by_n.max(), [0.25, 0.5, 0.75])
    assert (curve["n_test"] == 8).all() and set(curve["fold_group"]) == {"t"}
    assert curve.loc[curve["curve_size"] == 3.0, "accuracy"].item() == plain["accuracy"].item() == 0.75


def test_calibration_accuracy_grows_with_k_on_the_same_scored_captures(tmp_path, engine_env):
    # t shows x, y, z, w (3 captures each); a, b, c show x, y, z: w is learned only from t's calibration
    # captures. k = 0: the 2 scored w captures are wrong, 6 / 8; k = 1: every scored capture is right
    ds = curve_dataset({"t": {"x": 3, "y": 3, "z": 3, "w": 3}, "a": {"x": 2}, "b": {"y": 2}, "c": {"z": 2}})
    scores = run(tmp_path, ds, "  name: calibration\n  base: {name: loso, subjects: [t]}\n  per_class: [1]\n"
                 "  draws: 2", "calib")
    assert sorted(zip(scores["curve_size"], scores["curve_draw"])) == [(0.0, 0), (0.0, 1), (1.0, 0), (1.0, 1)]
    assert set(scores["curve"]) == {"calibration"} and (scores["n_test"] == 8).all()
    acc = scores.set_index(["curve_size", "curve_draw"])["accuracy"]
    assert np.allclose(acc.loc[0.0], 0.75) and np.allclose(acc.loc[1.0], 1.0)
    assert (scores["leakage"] == "").all()
    preds = pd.read_parquet(tmp_path / "calib" / "predictions.parquet")
    for d in (0, 1):
        ids = [set(preds.loc[preds["fold"] == f"k{k}#{d}/subject=t", "capture_id"]) for k in (0, 1)]
        assert ids[0] == ids[1] and len(ids[0]) == 8


def test_a_capped_calibration_point_is_labelled_by_what_it_added(tmp_path, engine_env):
    # t holds 2 captures of x, y, z (1 can train each) and 4 of w (3 can): k = 3 adds 1, 1, 1, 3 captures,
    # 1.5 per class on average, at least 1
    from touchbench.reports.curve_table import size_label, size_words
    from touchbench.reports.leaderboard import build_leaderboards
    from touchbench.reports.results import load_results
    ds = curve_dataset({"t": {"x": 2, "y": 2, "z": 2, "w": 4}, "a": {"x": 2}, "b": {"y": 2}, "c": {"z": 2}})
    data = tmp_path / "data.parquet"
    ds.to_parquet(data)
    p = parse_protocol(PROTOCOL.format(data=data, scheme="  name: calibration\n  base: {name: loso, subjects: [t]}\n"
                                       "  per_class: [1, 3]\n  draws: 1"), tmp_path / "calib.yaml")
    res = run_protocol(p, out=tmp_path / "calib", progress=False)
    s = res.scores.set_index("curve_size")
    assert s.loc[3.0, "curve_added"] == 1.5 and s.loc[3.0, "curve_added_min"] == 1.0
    assert s.loc[1.0, "curve_added"] == 1.0 and s.loc[0.0, "curve_added"] == 0.0
    assert any("k = 3 is capped" in n for n in res.notes)  # what `touchbench run` prints
    [lb] = build_leaderboards(load_results([tmp_path / "calib"]))
    assert [size_label(lb.curve, k) for k in lb.curve.sizes] == ["k=0", "k=1", "k≈1.5 (3 asked)"]
    assert size_words(lb.curve, 3.0).startswith("1.5 labelled captures per class on average (at least 1)")
    assert any(n.startswith("calibration: k=3 asked") and "1.5" in n for n in lb.notes)


# ----------------------------------------------------------------- what the schemes declare
def test_curve_schemes_are_labelled_without_their_sweep_and_keep_a_wrapped_crop():
    from touchbench.reports.results import scheme_label

    assert scheme_label({"name": "learning-curve", "base": {"name": "loso"}, "subjects": [1, 2], "draws": 3,
                         "stratify": "site"}) == "learning-curve(base=loso,stratify=site)"
    assert scheme_label({"name": "calibration", "base": {"name": "loso"}, "per_class": [1, 2],
                         "draws": 2}) == "calibration(base=loso,per_class=[1,2])"
    meta = grid(["a", "b", "c"], ["pat", "rub"])
    folds = make_splitter("learning-curve", base={"name": "early", "base": "loso", "frames": [4]},
                          subjects=[1]).folds(meta)
    assert {f.extra(Crop).frames for f in folds} == {4}
    assert {f.name for f in folds if f.extra(CurvePoint).size == 2} == {"n2#0/first4f/subject=a", "n2#0/first4f/subject=b",
                                                            "n2#0/first4f/subject=c"}
