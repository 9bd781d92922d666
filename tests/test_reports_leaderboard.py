"""Leaderboard and compare on hand-built results: values worked out by hand or by scipy."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from touchbench.core.errors import TouchbenchError
from touchbench.reports.compare import compare_methods
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import to_csv, to_json, to_markdown
from touchbench.reports.results import load_results
from touchbench.reports.stats import wilson_interval
from touchbench.reports.testing import FakeMethod, write_fake_run

SUBJECTS = [f"s{i}" for i in range(1, 7)]
GESTURES = ["pat", "rub", "stroke"]


def _captures() -> pd.DataFrame:
    rows = [(f"{s}-{g}-{r}", s, g) for s in SUBJECTS for g in GESTURES for r in range(2)]
    return pd.DataFrame(rows, columns=["capture_id", "subject", "gesture"])


CAPS = _captures()
FOLDS = {f"subject={s}": CAPS[CAPS["subject"] == s]["capture_id"].tolist() for s in SUBJECTS}


def _wrong(counts):
    """The first ``counts[i]`` captures of fold i are predicted wrongly."""
    return {f: ids[:c] for (f, ids), c in zip(FOLDS.items(), counts)}


A_WRONG = [0, 1, 0, 1, 0, 0]  # fold accuracies 1, 5/6, 1, 5/6, 1, 1
B_WRONG = [1, 2, 1, 2, 1, 1]  # 5/6, 4/6, ...: 1/6 below A on every fold
C_WRONG = [2, 1, 3, 2, 0, 1]  # differences to A: 2, 0, 3, 1, 0, 1 (sixths)


def _run1(tmp_path, **kw):
    methods = [
        FakeMethod("msd", "rf", classifier_name="gaus-rf", wrong=_wrong(A_WRONG), latency_ms=5.0),
        FakeMethod("sd", "rf", classifier_name="gaus-rf", wrong=_wrong(B_WRONG), latency_ms=1.0),
        FakeMethod("bmh", "rf", classifier_name="gaus-rf", wrong=_wrong(C_WRONG), latency_ms=2.0),
    ]
    return write_fake_run(tmp_path / "run1", CAPS, FOLDS, methods, scheme={"name": "loso"}, **kw)


def _row(lb, features, classifier="rf"):
    r = lb.rows[(lb.rows["features"] == features) & (lb.rows["classifier"] == classifier)]
    assert len(r) == 1, lb.rows[["features", "classifier", "method_id"]]
    return r.iloc[0]


def test_accuracy_interval_and_tests_by_hand(tmp_path):
    d = _run1(tmp_path)
    [lb] = build_leaderboards(load_results([d]))
    a, b, c = _row(lb, "msd"), _row(lb, "sd"), _row(lb, "bmh")
    assert list(lb.rows["features"]) == ["msd", "sd", "bmh"]
    assert list(lb.rows["rank"]) == [1, 2, 3]
    acc_a = np.array([6, 5, 6, 5, 6, 6]) / 6
    assert a["accuracy"] == pytest.approx(34 / 36)
    assert a["accuracy_sd"] == pytest.approx(np.std(acc_a, ddof=1))
    half = stats.t.ppf(0.975, 5) * np.std(acc_a, ddof=1) / np.sqrt(6)
    assert 34 / 36 + half > 1  # the t interval runs past 100 %: an accuracy cannot, so it is clipped
    assert a["ci_low"] == pytest.approx(34 / 36 - half) and a["ci_high"] == 1.0
    assert b["accuracy"] == pytest.approx(28 / 36) and c["accuracy"] == pytest.approx(27 / 36)
    # over folds: Nadeau & Bengio's corrected resampled t-test; each fold tests 6 captures and trains on 30
    # B vs A: six differences of -1/6, no spread: t = mean / 0 is undefined, so there is no p (never 0)
    assert b["test"] == "corrected-t" and b["n_pairs"] == 6 and b["paired_by"] == "fold"
    assert math.isnan(b["p_value"])
    assert b["diff_vs_best"] == pytest.approx(-1 / 6)
    # each fold tests one subject (leave-one-subject-out): the interval resamples subjects, and every
    # subject's difference is -1 of 6 captures, so every resample's difference is -1/6
    assert b["diff_ci_method"] == "subject-bootstrap" and b["n_subjects"] == 6
    assert (b["diff_ci_low"], b["diff_ci_high"]) == (pytest.approx(-1 / 6), pytest.approx(-1 / 6))
    # C vs A: differences -2, 0, -3, -1, 0, -1 sixths: mean -7/36; sum of squared deviations from the
    # mean -7/6 (in sixths) 246/36, so var = 246 / 36 / 5 / 36; variance factor 1/6 + 6/30
    t = (-7 / 36) / math.sqrt((1 / 6 + 6 / 30) * 246 / 36 / 5 / 36)
    assert c["test"] == "corrected-t"
    assert c["p_value"] == pytest.approx(2 * stats.t.sf(abs(t), 5))
    assert 0.05 < c["p_value"] < 0.2
    # Holm over the family of defined p-values, {p_C} alone: 1 * p_C
    assert math.isnan(b["p_holm"]) and c["p_holm"] == pytest.approx(c["p_value"])
    assert not b["differs"] and not c["differs"]
    assert any("1 method(s) differ from the best by the same amount in every fold" in n for n in lb.notes)
    assert math.isnan(a["p_value"]) and a["test"] == "best"
    # Pareto on accuracy vs latency: A (best), B (fastest) on it; C (slower and worse than B) not
    assert bool(a["pareto"]) and bool(b["pareto"]) and not bool(c["pareto"])
    assert a["latency_ms"] == pytest.approx(5.0)
    # macro F1 is the mean of per-fold macro F1 (sklearn computes each fold's)
    from sklearn.metrics import f1_score

    f = FOLDS["subject=s2"]
    true = CAPS.set_index("capture_id").loc[f, "gesture"].tolist()
    pred = ["rub"] + true[1:]  # the first capture (a pat) predicted as the next class
    f1_s2 = f1_score(true, pred, average="macro")
    assert a["macro_f1"] == pytest.approx((4 * 1.0 + 2 * f1_s2) / 6)


def test_same_run_twice_is_one_row(tmp_path):
    d = _run1(tmp_path)
    [lb] = build_leaderboards(load_results([d, d, tmp_path]))
    assert len(lb.rows) == 3
    assert (lb.rows["n_folds"] == 6).all() and (lb.rows["runs"] == 1).all()
    # a copy of the directory (same tasks, same seeds) is also counted once
    import shutil

    shutil.copytree(d, tmp_path / "copy")
    [lb2] = build_leaderboards(load_results([tmp_path / "run1", tmp_path / "copy"]))
    assert len(lb2.rows) == 3
    assert _row(lb2, "msd")["accuracy"] == pytest.approx(34 / 36)


def test_runs_combine_by_parameter_hash_not_label(tmp_path):
    _run1(tmp_path)
    m2 = [
        # the same method as "msd/rf" under another label, another run and machine, other seeds
        FakeMethod("msd", "rf-1000", classifier_name="gaus-rf", wrong=_wrong([1, 1, 0, 1, 0, 0]), latency_ms=100.0),
        # same label as run1's "msd/rf", different parameters: another method
        FakeMethod("msd", "rf", classifier_name="gaus-rf", classifier_params={"n_estimators": 10},
                   wrong=_wrong([3, 3, 3, 3, 3, 3]), latency_ms=50.0),
    ]
    other = {"platform": "Linux-other", "machine": "aarch64", "processor": "", "cpu_count": 64}
    write_fake_run(tmp_path / "run2", CAPS, FOLDS, m2, scheme={"name": "loso"}, run_id="run2", platform=other)
    rs = load_results([tmp_path])
    [lb] = build_leaderboards(rs)
    assert len(lb.rows) == 4  # msd/rf (combined), sd, bmh, msd/rf(n_estimators=10)
    msd = lb.rows[(lb.rows["features"] == "msd") & (lb.rows["classifier_params"] == "{}")].iloc[0]
    assert msd["runs"] == 2 and msd["n_folds"] == 6
    # fold s1: mean of the two replicates (1 and 5/6); the other folds agree
    assert msd["accuracy"] == pytest.approx(((1 + 5 / 6) / 2 + 5 / 6 + 1 + 5 / 6 + 1 + 1) / 6)
    # timings: the reference machine (3 methods measured) is run1's; its latency 5 ms, not 100
    assert msd["latency_ms"] == pytest.approx(5.0)
    ten = lb.rows[lb.rows["classifier_params"] == '{"n_estimators":10}'].iloc[0]
    assert ten["timing_machine"] != msd["timing_machine"]
    # alone on its machine: on that machine's front even though it is slow and inaccurate
    assert bool(ten["pareto"])
    assert any("several machines" in n for n in lb.notes)
    # pooled on request: one front; the 50 ms method is dominated
    [pooled] = build_leaderboards(rs, pool_machines=True)
    ten_p = pooled.rows[pooled.rows["classifier_params"] == '{"n_estimators":10}'].iloc[0]
    assert not bool(ten_p["pareto"])
    assert pooled.rows.loc[pooled.rows["method_id"] == msd["method_id"], "latency_ms"].iloc[0] == pytest.approx(
        np.median([5.0] * 6 + [100.0] * 6))


def test_tables_per_dataset_and_scheme(tmp_path):
    _run1(tmp_path)
    write_fake_run(tmp_path / "kfold", CAPS, FOLDS, [FakeMethod("msd", "rf", classifier_name="gaus-rf")],
                   scheme={"name": "kfold", "k": 6}, run_id="k")
    write_fake_run(tmp_path / "other-data", CAPS, FOLDS, [FakeMethod("msd", "rf", classifier_name="gaus-rf")],
                   scheme={"name": "loso"}, dataset_hash="e" * 64, run_id="o")
    lbs = build_leaderboards(load_results([tmp_path]))
    assert sorted(lb.scheme for lb in lbs) == ["kfold(k=6)", "loso", "loso"]
    assert len({lb.key for lb in lbs}) == 3


def test_single_fold_wilson_and_subject_pairing(tmp_path):
    caps = CAPS
    fold = {"challenge": caps["capture_id"].tolist()}
    by_subj = {s: caps[caps["subject"] == s]["capture_id"].tolist() for s in SUBJECTS}
    x_wrong = by_subj["s1"][:2] + by_subj["s2"][:1]
    y_wrong = by_subj["s1"][:2] + by_subj["s2"][:2] + by_subj["s3"][:2]
    d = write_fake_run(tmp_path / "ch", caps, fold, [
        FakeMethod("all", "x", wrong={"challenge": x_wrong}), FakeMethod("all", "y", wrong={"challenge": y_wrong})],
        scheme={"name": "challenge"})
    [lb] = build_leaderboards(load_results([d]))
    x, y = _row(lb, "all", "x"), _row(lb, "all", "y")
    assert x["accuracy"] == pytest.approx(33 / 36)
    lo, hi = wilson_interval(33, 36)
    assert (x["ci_low"], x["ci_high"]) == (pytest.approx(lo), pytest.approx(hi))
    assert x["ci_method"] == "wilson" and math.isnan(x["accuracy_sd"])
    # one test set: McNemar's exact test on the 36 paired captures; x is right and y wrong on 3 (s2's
    # second capture, s3's first two), never the reverse: p = 2 * (1/2)**3 = 0.25
    assert y["test"] == "mcnemar-exact" and y["paired_by"] == "capture" and y["n_pairs"] == 36
    assert y["p_value"] == pytest.approx(stats.binomtest(0, 3, 0.5).pvalue) == pytest.approx(0.25)
    assert y["diff_vs_best"] == pytest.approx(-3 / 36)
    # the interval of the difference resamples the 6 subjects (per subject y - x: 0, -1, -2, 0, 0, 0 of 6):
    # a resample of none of s2, s3 (probability (4/6)**6 = 0.088 > 2.5 %) differs by 0; none by less than -2/6
    assert y["diff_ci_method"] == "subject-bootstrap" and y["n_subjects"] == 6
    assert y["diff_ci_high"] == 0.0 and -2 / 6 <= y["diff_ci_low"] < -3 / 36


def _one_test_set(n_right_only_a: int, n_captures: int = 251):
    """Captures of 5 subjects for one test set; method a right on all, b wrong on the first ``n_right_only_a``."""
    subjects = [f"s{i % 5}" for i in range(n_captures)]
    caps = pd.DataFrame({"capture_id": [f"c{i:03d}" for i in range(n_captures)], "subject": subjects,
                         "gesture": [GESTURES[i % 3] for i in range(n_captures)]})
    fold = {"challenge": caps["capture_id"].tolist()}
    return caps, fold, caps["capture_id"].tolist()[:n_right_only_a]


def test_one_test_set_of_251_captures_tells_40_discordant_captures_apart(tmp_path):
    caps, fold, wrong = _one_test_set(40)
    d = write_fake_run(tmp_path / "ch", caps, fold, [FakeMethod("all", "right"),
                                                     FakeMethod("all", "wrong", wrong={"challenge": wrong})],
                       scheme={"name": "challenge"})
    [lb] = build_leaderboards(load_results([d]))
    worse = _row(lb, "all", "wrong")
    # b = 0 captures only the worse method gets right, c = 40 the reverse: p = 2 * (1/2)**40
    assert worse["test"] == "mcnemar-exact" and worse["n_pairs"] == 251
    assert worse["p_value"] == pytest.approx(stats.binomtest(0, 40, 0.5).pvalue, rel=1e-12)
    assert worse["p_value"] == pytest.approx(2 * 0.5 ** 40, rel=1e-12)
    assert worse["differs"] and worse["diff_vs_best"] == pytest.approx(-40 / 251)
    # the interval resamples the 5 subjects (8 wrong captures each of about 50): it excludes 0
    assert worse["diff_ci_high"] < 0 and worse["n_subjects"] == 5


def test_failed_folds_are_counted_not_scored(tmp_path):
    d = write_fake_run(tmp_path / "f", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong(A_WRONG), failed_folds=["subject=s1"])], scheme={"name": "loso"})
    [lb] = build_leaderboards(load_results([d]))
    r = lb.rows.iloc[0]
    assert r["n_folds"] == 5 and r["n_failed"] == 1
    assert r["accuracy"] == pytest.approx((5 / 6 + 1 + 5 / 6 + 1 + 1) / 5)


def test_compare_per_fold_and_per_class(tmp_path):
    d = _run1(tmp_path)
    rs = load_results([d])
    [lb] = build_leaderboards(rs)
    cmp = compare_methods(rs, lb, "msd/rf", "sd/rf")
    # six fold differences of +1/6, no spread: the corrected t is undefined, no p
    assert cmp.test.test == "corrected-t" and cmp.test.n == 6 and math.isnan(cmp.test.pvalue)
    assert cmp.test.note == "no variance: every fold differs by the same amount"
    np.testing.assert_allclose(cmp.pairs["diff"].to_numpy(), np.full(6, 1 / 6))
    pc = cmp.per_class.set_index("class")
    # A misses 2 captures (first of folds s2 and s4: both 'pat'); B misses 8: in each fold 'pat' first,
    # then a second 'pat' in folds s2 and s4 -> B's pat recall = (12 - 8) / 12
    assert pc.loc["pat", "support"] == 12
    assert pc.loc["pat", "recall_a"] == pytest.approx(10 / 12)
    assert pc.loc["pat", "recall_b"] == pytest.approx(4 / 12)
    assert pc.loc["pat", "recall_diff"] == pytest.approx(6 / 12)
    assert pc.loc["stroke", "recall_diff"] == pytest.approx(0.0)
    # a method id prefix works as well as a label
    mid = lb.rows.iloc[0]["method_id"]
    assert compare_methods(rs, lb, mid[:6], "bmh/rf").a["method_id"] == mid


def test_ambiguous_label_needs_the_hash(tmp_path):
    _run1(tmp_path)
    write_fake_run(tmp_path / "run2", CAPS, FOLDS, [
        FakeMethod("msd", "rf", classifier_name="gaus-rf", classifier_params={"n_estimators": 10})],
        scheme={"name": "loso"}, run_id="run2")
    rs = load_results([tmp_path])
    [lb] = build_leaderboards(rs)
    with pytest.raises(TouchbenchError, match="names 2 methods"):
        compare_methods(rs, lb, "msd/rf", "sd/rf")
    with pytest.raises(TouchbenchError, match="no method"):
        compare_methods(rs, lb, "nope/rf", "sd/rf")


def test_outputs_markdown_csv_json(tmp_path):
    d = _run1(tmp_path)
    lbs = build_leaderboards(load_results([d]))
    md = to_markdown(lbs)
    assert "| # | method |" in md and "94.4" in md and "★" in md
    csv = pd.read_csv(__import__("io").StringIO(to_csv(lbs)))
    assert len(csv) == 3 and {"accuracy", "p_holm", "pareto", "method", "scheme"} <= set(csv.columns)
    assert "method_id" not in csv.columns and set(csv["method"]) == {"msd / rf", "sd / rf", "bmh / rf"}
    js = json.loads(to_json(lbs))
    assert js["tables"][0]["scheme"] == "loso" and len(js["tables"][0]["rows"]) == 3
    assert js["tables"][0]["rows"][0]["p_value"] is None


def test_missing_results_are_refused(tmp_path):
    with pytest.raises(TouchbenchError, match="no scores.parquet"):
        load_results([tmp_path])
    with pytest.raises(TouchbenchError, match="no such results directory"):
        load_results([tmp_path / "nope"])


def test_interrupted_run_is_read_from_its_fragments(tmp_path):
    from touchbench.results.store import ResultStore

    d = _run1(tmp_path)
    scores = pd.read_parquet(d / "scores.parquet")
    preds = pd.read_parquet(d / "predictions.parquet")
    store = ResultStore(tmp_path / "interrupted")
    for t in scores["task_id"][:12]:  # two of the three methods finished
        store.write_task(t, scores[scores["task_id"] == t].iloc[0].to_dict(), preds[preds["task_id"] == t])
    [lb] = build_leaderboards(load_results([tmp_path / "interrupted"]))
    assert list(lb.rows["features"]) == ["msd", "sd"]
    assert lb.rows.iloc[0]["accuracy"] == pytest.approx(34 / 36)


def test_single_fold_with_several_seeds_reports_their_spread(tmp_path):
    fold = {"challenge": CAPS["capture_id"].tolist()}
    wrong = CAPS["capture_id"].tolist()[:3]
    d = write_fake_run(tmp_path / "ch", CAPS, fold, [FakeMethod("all", "x", wrong={"challenge": wrong})],
                       scheme={"name": "challenge"})
    # a second repetition of the same split with another seed: 30 of 36 right instead of 33
    s = pd.read_parquet(d / "scores.parquet")
    rep = s.copy()
    rep["repetition"] = 1
    rep["seed"] = s["seed"] + 1
    rep["task_id"] = s["task_id"] + "-rep1"
    rep["accuracy"] = 30 / 36
    pd.concat([s, rep], ignore_index=True).to_parquet(d / "scores.parquet")
    p = pd.read_parquet(d / "predictions.parquet")  # the same test captures: the same fold
    p1 = p.assign(repetition=1, task_id=p["task_id"] + "-rep1")
    pd.concat([p, p1], ignore_index=True).to_parquet(d / "predictions.parquet")
    [lb] = build_leaderboards(load_results([d]))
    x = _row(lb, "all", "x")
    assert x["accuracy"] == pytest.approx((33 / 36 + 30 / 36) / 2)
    assert x["accuracy_sd"] == pytest.approx((3 / 36) / math.sqrt(2))  # sample sd of two values: |a - b| / sqrt(2)
    assert x["n_seeds"] == 2 and x["n_folds"] == 1
    assert "± 5.9 (2 seeds, 83.3–91.7)" in to_markdown([lb])  # the seeds: 30 and 33 of 36


def test_compare_across_evaluations_combines_them_by_stouffer(tmp_path):
    from click.testing import CliRunner

    from touchbench.cli.main import cli

    _run1(tmp_path)
    write_fake_run(tmp_path / "run2", CAPS, FOLDS, [
        FakeMethod("msd", "rf", classifier_name="gaus-rf", wrong=_wrong([0, 0, 1, 0, 0, 0])),
        FakeMethod("bmh", "rf", classifier_name="gaus-rf", wrong=_wrong([1, 0, 1, 2, 0, 1])),
    ], dataset="other", dataset_hash="e" * 64, scheme={"name": "loso"}, run_id="run2")
    # fold differences msd - bmh in sixths: 2, 0, 3, 1, 0, 1 (mean 7/6, squared deviations 246/36) and
    # 1, 0, 0, 2, 0, 1 (mean 4/6, squared deviations 120/36); corrected t with 1/6 + 6/30, 5 df
    t1 = (7 / 36) / math.sqrt((1 / 6 + 6 / 30) * 246 / 36 / 5 / 36)
    t2 = (4 / 36) / math.sqrt((1 / 6 + 6 / 30) * 120 / 36 / 5 / 36)
    z = (math.sqrt(6) * stats.norm.isf(stats.t.sf(t1, 5)) + math.sqrt(6) * stats.norm.isf(stats.t.sf(t2, 5))) / math.sqrt(12)
    res = CliRunner().invoke(cli, ["compare", str(tmp_path), "--a", "msd/rf", "--b", "bmh/rf"])
    assert res.exit_code == 0, res.output
    assert "across 2 evaluations" in res.output
    assert f"combined: z = {z:+.2f} (positive: A better), two-sided p = {2 * stats.norm.sf(z):.4g}" in res.output
    res = CliRunner().invoke(cli, ["compare", str(tmp_path), "--a", "msd/rf", "--b", "bmh/rf", "--json"])
    doc = json.loads(res.stdout)
    assert len(doc["comparisons"]) == 2 and doc["meta_analysis"]["z"] == pytest.approx(z)
    assert doc["meta_analysis"]["n"] == [6, 6]


# ----------------------------------------------------------------- terminal width
def test_fitting_columns_adds_columns_in_priority_order_while_they_fit():
    from touchbench.reports.rendering import fitting_columns

    widths = {"#": 1, "method": 10, "accuracy": 5, "macro": 4, "latency": 6, "fit": 2}
    essential = ("#", "method", "accuracy")
    # a rich table: 1 for its left edge, then 3 per column around its width
    base = 1 + (1 + 3) + (10 + 3) + (5 + 3)  # 26
    assert fitting_columns(widths, 20, essential) == ["#", "method", "accuracy"]  # never fewer
    assert fitting_columns(widths, base, essential) == ["#", "method", "accuracy"]
    assert fitting_columns(widths, base + 7, essential) == ["#", "method", "accuracy", "macro"]
    # latency (9) does not fit in 8 more: fit (5) is not taken past it, the order holds
    assert fitting_columns(widths, base + 7 + 8, essential) == ["#", "method", "accuracy", "macro"]
    assert fitting_columns(widths, base + 7 + 9 + 5, essential) == list(widths)


def test_an_80_column_terminal_shows_every_method_by_name_with_its_accuracy(tmp_path, monkeypatch):
    import re

    from click.testing import CliRunner
    from rich.cells import cell_len

    from touchbench.cli.main import cli

    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["run", "tiny", "--out", str(out), "--jobs", "1", "--no-progress"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(cli, ["leaderboard", str(out)], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert max(cell_len(line) for line in lines) <= 80
    # tiny: features sd, msd, sd+msd x classifiers gaus-rf, zhou-lda; accuracy: mean over the 4 folds
    scores = pd.read_parquet(out / "scores.parquet")
    acc = scores.groupby(["features", "classifier"])["accuracy"].mean()
    assert len(acc) == 6
    for (feats, clf), a in acc.items():
        name = f"{feats} / {clf}"
        row = [line for line in lines if re.search(rf"│ {re.escape(name)} +│", line)]
        assert len(row) == 1, (name, r.output)
        assert f"│ {100 * a:.1f} ± " in row[0]
    header = "\n".join(lines[:6])
    assert "accuracy" in header and "interval" in header and "vs best" in header
    # method ids: in the JSON document only
    ids = [row["method_id"] for row in json.loads(to_json(build_leaderboards(load_results([out]))))["tables"][0]["rows"]]
    for fmt in ("terminal", "md", "csv"):
        text = CliRunner().invoke(cli, ["leaderboard", str(out), "-f", fmt], env={"COLUMNS": "80"}).output
        assert not any(mid in text for mid in ids), fmt


def test_a_single_fold_table_keeps_names_and_wilson_intervals_whole_at_80_columns(tmp_path):
    from rich.console import Console

    from touchbench.reports.rendering import print_terminal

    one = {"challenge": CAPS["capture_id"].tolist()}  # 36 test captures
    write_fake_run(tmp_path / "r", CAPS, one, [
        FakeMethod("sd+bmh+msd", "gaus-rf", wrong={"challenge": CAPS["capture_id"].tolist()[:6]}),
        FakeMethod("bmh", "gaus-rf", wrong={"challenge": CAPS["capture_id"].tolist()[:12]}),
    ], scheme={"name": "challenge"})
    console = Console(record=True, width=80)
    print_terminal(build_leaderboards(load_results([tmp_path / "r"])), console)
    text = console.export_text()
    assert max(len(line) for line in text.splitlines()) <= 80
    # 30/36 and 24/36 right; Wilson intervals by scipy's binomtest
    for name, k in (("sd+bmh+msd / gaus-rf", 30), ("bmh / gaus-rf", 24)):
        ci = stats.binomtest(k, 36).proportion_ci(method="wilson")
        line = next(x for x in text.splitlines() if f"│ {name} " in x)
        assert f"{100 * k / 36:.1f}" in line and f"{100 * ci.low:.1f}–{100 * ci.high:.1f}" in line


def test_a_terminal_legend_explains_the_columns_it_shows_and_what_the_pareto_mark_is_on(tmp_path):
    from rich.console import Console

    from touchbench.reports.rendering import print_terminal

    one = {"challenge": CAPS["capture_id"].tolist()}
    write_fake_run(tmp_path / "r", CAPS, one, [
        FakeMethod("sd+bmh+msd", "gaus-rf", wrong={"challenge": CAPS["capture_id"].tolist()[:6]}, latency_ms=9.0),
        FakeMethod("bmh", "gaus-rf", wrong={"challenge": CAPS["capture_id"].tolist()[:12]}, latency_ms=1.0),
    ], scheme={"name": "challenge"})
    lbs = build_leaderboards(load_results([tmp_path / "r"]))
    texts = {}
    for width in (80, 250):
        console = Console(record=True, width=width)
        print_terminal(lbs, console)
        texts[width] = " ".join(console.export_text().split())
    # 80 columns: no latency nor Pareto column, so no sentence on them
    assert "★" not in texts[80] and "latency" not in texts[80].split("Note:")[0].lower()
    # wide: both columns, and the mark says the time it is computed on, and the column that shows it
    assert "★ = on the Pareto front of accuracy against the CPU time of labelling one capture" in texts[250]
    assert "(the CPU ms column)" in texts[250]
    assert "Latency: median over folds of the wall-clock time" in texts[250]


LONG_LABEL = "head" + "x" * 242 + "tail"  # 250 characters


@pytest.mark.parametrize("width", [20, 40, 80, 120])
def test_a_terminal_of_any_width_shows_every_number_whole_and_shortens_a_long_label(tmp_path, width):
    """Numbers are never cut nor wrapped: a long label is shortened to "…" first (its start and its
    end kept), and where even the numbers do not fit the table is printed wider than the terminal."""
    from rich.console import Console

    from touchbench.reports.rendering import display_rows, print_terminal

    write_fake_run(tmp_path / "r", CAPS, FOLDS, [
        FakeMethod("msd", LONG_LABEL, classifier_name="gaus-rf", wrong=_wrong(A_WRONG)),
        FakeMethod("sd", "rf", wrong=_wrong(B_WRONG)),
    ])
    [lb] = build_leaderboards(load_results([tmp_path / "r"]))
    console = Console(record=True, width=width)
    print_terminal([lb], console)
    lines = console.export_text().splitlines()
    table = [x for x in lines if x.startswith("│")]
    # fold accuracies: A 1, 5/6, 1, 5/6, 1, 1; B 1/6 below on every fold; Student t interval, clipped at 100 %
    for name, accs in (("1", [1, 5 / 6, 1, 5 / 6, 1, 1]), ("2", [5 / 6, 4 / 6, 5 / 6, 4 / 6, 5 / 6, 5 / 6])):
        m, sd = np.mean(accs), np.std(accs, ddof=1)
        half = stats.t.ppf(0.975, 5) * sd / math.sqrt(6)
        rows = [x for x in table if x.startswith(f"│ {name} ")]
        assert len(rows) == 1, "\n".join(lines)
        row = rows[0]
        assert f"│ {100 * m:.1f} ± {100 * sd:.1f} │" in row
        assert f"│ {100 * (m - half):.1f}–{100 * min(m + half, 1):.1f} " in row
    # B against A: -1/6 on every fold: no variance, so the corrected t-test gives no p ("—")
    assert any("│ -16.7, p=—" in x for x in table) and any("(corrected t, n=6 folds)" in x for x in table)
    # every piece of text in a cell is its whole cell, or a number or its note in parentheses (a line
    # each), or the long label shortened
    cells = [cell for c in display_rows(lb)[1] for cell in c]
    whole = set(cells) | {x for cell in cells if " (" in cell for x in (cell.split(" (")[0], "(" + cell.split(" (", 1)[1])}
    label = f"msd / {LONG_LABEL}"
    for x in table:
        for piece in (p.strip() for p in x.strip("│").split("│")):
            if piece and piece not in whole:
                head, _, tail = piece.partition("…")
                assert head and tail and label.startswith(head) and label.endswith(tail), piece
    assert sum("…" in x for x in table) == 1  # the long label, on one line
    if width >= 80:
        assert max(len(x) for x in lines) <= width
    else:  # the numbers alone are wider: the table is, and the terminal wraps its lines
        assert max(len(x) for x in table) > width


MANY = 60


@pytest.fixture(scope="module")
def many_methods_board(tmp_path_factory):
    """One leaderboard of 60 methods whose labels differ only in a number (its tests only print it)."""
    folder = tmp_path_factory.mktemp("many") / "r"
    write_fake_run(folder, CAPS, FOLDS, [
        FakeMethod("msd", f"touch-extra-trees-variant-{k:03d} with the paper's settings", classifier_name="gaus-rf",
                   classifier_params={"variant": k}, wrong=_wrong(A_WRONG)) for k in range(MANY)])
    [lb] = build_leaderboards(load_results([folder]))
    return lb


@pytest.mark.parametrize("width", [20, 30, 40])
def test_many_methods_at_a_narrow_terminal_keep_what_tells_them_apart(many_methods_board, width):
    from rich.console import Console

    from touchbench.reports.rendering import print_terminal

    n, lb = MANY, many_methods_board
    console = Console(record=True, width=width)
    print_terminal([lb], console)
    text = console.export_text()
    table = [x for x in text.splitlines() if x.startswith("│")]
    method_cells = [x.strip("│").split("│")[1].strip() for x in table]
    shown = [c for c in method_cells if c]
    # the labels differ only in their number: the start "msd / touch-extra-trees-variant-" and the
    # end " with the paper's settings" they all share go (said once above the table), the numbers stay
    assert sorted(shown) == [f"{k:03d}" for k in range(n)], "\n".join(table)
    said = "".join(text.split("┏")[0].split())  # a narrow terminal breaks the line inside words
    assert "leaveoutthestart“msd/touch-extra-trees-variant-”andtheend“withthepaper'ssettings”" in said


def test_a_method_that_brings_its_own_input_is_named_by_its_label_everywhere():
    from touchbench.reports.figures.base import short_label
    from touchbench.reports.labels import method_label

    registered = {"features": "touch-rhythm+cell-rhythm+contact-motion", "classifier": "touch-et",
                  "classifier_name": "touch-et", "early_frames": math.nan}
    on_captures = {"features": "captures(frames=64)", "classifier": "minirocket", "classifier_name": "minirocket",
                   "early_frames": math.nan}
    pair = {"features": "msd", "classifier": "rf100", "classifier_name": "gaus-rf", "early_frames": math.nan}
    assert [method_label(r) for r in (registered, on_captures, pair)] == ["touch-et", "minirocket", "msd / rf100"]
    assert [short_label(r) for r in (registered, on_captures, pair)] == ["touch-et", "minirocket", "msd/rf100"]


def test_an_adapted_method_gets_a_table_of_its_own(tmp_path):
    """A method adapted to the test subjects' unlabelled captures (its rows' ``adaptation``) is never
    ranked, tested or put on a Pareto front with the plain methods, even when it is more accurate and
    faster than all of them; its own table says what it used."""
    from touchbench.methods.base import ADAPTED

    adapted = FakeMethod("touch-rhythm", "touch-et-adapt", classifier_name="touch-et-adapt", latency_ms=0.5,
                         adaptation=ADAPTED)  # every capture right
    path = _run1(tmp_path)
    write_fake_run(tmp_path / "adapted", CAPS, FOLDS, [adapted], scheme={"name": "loso"})
    lbs = build_leaderboards(load_results([path, tmp_path / "adapted"]))
    plain, own = sorted(lbs, key=lambda lb: lb.adaptation)
    assert plain.adaptation == "" and set(plain.rows["features"]) == {"msd", "sd", "bmh"}
    assert plain.rows.iloc[0]["features"] == "msd" and plain.rows.iloc[0]["test"] == "best"  # A: 34/36
    assert plain.rows["pareto"].tolist() == [True, True, False]  # msd (5 ms), sd (1 ms): as without it
    assert own.adaptation == ADAPTED and own.rows["classifier"].tolist() == ["touch-et-adapt"]
    assert own.rows.iloc[0]["accuracy"] == 1.0 and own.rows.iloc[0]["test"] == "best"
    assert own.title.endswith("loso — adapted to each test session") and not plain.title.endswith("session")
    md = to_markdown(lbs)
    assert "ADAPTED: every method of this table adapted to each test session using that session's unlabelled " \
           f"captures ({ADAPTED}; never their labels)" in md
    assert md.count("ADAPTED:") == 1 and "Mean rank across" not in md  # one plain table: nothing across tables
    assert [t["adaptation"] for t in json.loads(to_json(lbs))["tables"]] == [lb.adaptation for lb in lbs]


def test_results_written_before_the_adaptation_column_read_as_plain(tmp_path):
    import pyarrow.parquet as pq

    path = _run1(tmp_path)
    table = pq.read_table(path / "scores.parquet")
    pq.write_table(table.drop_columns(["adaptation"]), path / "scores.parquet")  # keeps the schema version
    (lb,) = build_leaderboards(load_results([path]))
    assert lb.adaptation == "" and len(lb.rows) == 3 and lb.rows.iloc[0]["features"] == "msd"


# ----------------------------------------------------------------- ties, tests, and what compare says
def test_equal_accuracies_summed_in_another_order_share_one_rank(tmp_path):
    # both 35 of 36 right, one wrong capture in the first fold or the last: the mean of the six fold
    # accuracies in fold order differs in its last bit
    x, y = [1, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1]
    assert np.mean((6 - np.array(x)) / 6) != np.mean((6 - np.array(y)) / 6)
    for name, data in (("run1", "fake"), ("run2", "other")):
        write_fake_run(tmp_path / name, CAPS, FOLDS, [
            FakeMethod("msd", "x", wrong=_wrong(x)), FakeMethod("msd", "y", wrong=_wrong(y)),
            FakeMethod("msd", "z", wrong=_wrong([1, 1, 0, 0, 0, 0]))],
            dataset=data, dataset_hash=data[0] * 64, scheme={"name": "loso"}, run_id=name)
    lbs = build_leaderboards(load_results([tmp_path]))
    for lb in lbs:
        assert lb.rows.set_index("classifier")["rank"].to_dict() == {"x": 1, "y": 1, "z": 3}
    from touchbench.reports.across import mean_ranks

    # one rank in each of the two tables: (1 + 2) / 2 for both, 3 for z
    mr = mean_ranks(lbs).set_index("method")["mean_rank"]
    assert mr.to_dict() == {"msd / x": 1.5, "msd / y": 1.5, "msd / z": 3.0}


def _cli(*args):
    from click.testing import CliRunner

    from touchbench.cli.main import cli

    res = CliRunner().invoke(cli, ["compare", *map(str, args)])
    assert res.exit_code == 0, res.output
    return res


def test_compare_gives_the_interval_that_inverts_mcnemars_test_and_explains_the_leaderboards_p(tmp_path):
    # one test set of 250 captures of 5 subjects; A wrong on one capture of each of s1-s4, B wrong on 14
    # of s0: b = 14 captures only A gets right, c = 4 only B; C wrong on A's 4 and 3 more
    caps, fold, ids = _one_test_set(0, 250)
    s0 = caps[caps["subject"] == "s0"]["capture_id"].tolist()
    a_wrong = [caps[caps["subject"] == s]["capture_id"].iloc[0] for s in ("s1", "s2", "s3", "s4")]
    c_wrong = a_wrong + [caps[caps["subject"] == "s1"]["capture_id"].iloc[k] for k in (1, 2, 3)]
    d = write_fake_run(tmp_path / "ch", caps, fold, [
        FakeMethod("all", "a", wrong={"challenge": a_wrong}), FakeMethod("all", "b", wrong={"challenge": s0[:14]}),
        FakeMethod("all", "c", wrong={"challenge": c_wrong})], scheme={"name": "challenge"})
    # McNemar: p = 2 * P(X >= 14), X ~ Bin(18, 1/2); C against A: 3 discordant, all for A: p = 2 / 8
    p = 2 * (3060 + 816 + 153 + 18 + 1) / 2 ** 18
    # Holm over {p, 0.25}: 2 p = 0.0618, then max(0.0618, 0.25): the leaderboard's p for B is 2 p
    lo, hi = (18 / 250 * (2 * stats.beta.ppf(q, k, 19 - k) - 1) for q, k in ((0.025, 14), (0.975, 15)))
    assert 0 < lo  # the test rejects at 0.05, and so does its interval
    out = _cli(d, "--a", "all/a", "--b", "all/b").output
    assert f"McNemar's exact test, two-sided p = {p:.4g} (this comparison alone, no multiple-comparison correction)" in out
    assert f"95 % interval of A-B {100 * lo:+.2f} to {100 * hi:+.2f} points (exact" in out
    assert (f"the leaderboard's p for B against the best is {2 * p:.4g}: the same test (p = {p:.4g}), "
            "Holm-adjusted over the table's 2 comparisons with the best") in out
    # the bootstrap over subjects is said to be another thing: without s0 (a resample in (4/5)**5 = 33 %)
    # B is the better, so it straddles 0
    boot = next(line for line in out.splitlines() if line.startswith("between subjects: A-B "))
    assert float(boot.split()[3]) < 0 < float(boot.split()[5])
    doc = json.loads(_cli(d, "--a", "all/a", "--b", "all/b", "--json").stdout)["comparisons"][0]
    assert doc["p_correction"] == "none" and doc["leaderboard"]["correction"] == "holm"
    assert doc["leaderboard"]["p_holm"] == pytest.approx(2 * p) and doc["test"]["test_ci_low"] == pytest.approx(lo)
    # neither method the best: the leaderboard has no p for the pair
    assert "it has no p for A against B" in _cli(d, "--a", "all/b", "--b", "all/c").output


def test_compare_across_evaluations_leaves_out_a_table_with_no_variance_in_either_order(tmp_path):
    _run1(tmp_path)  # msd better than sd by 1/6 in every fold: no variance
    write_fake_run(tmp_path / "run2", CAPS, FOLDS, [
        FakeMethod("msd", "rf", classifier_name="gaus-rf", wrong=_wrong([0, 0, 1, 0, 0, 0])),
        FakeMethod("sd", "rf", classifier_name="gaus-rf", wrong=_wrong([1, 0, 1, 2, 0, 1])),
    ], dataset="other", dataset_hash="e" * 64, scheme={"name": "loso"}, run_id="run2")
    # the other table, msd - sd in sixths 1, 0, 0, 2, 0, 1 (by hand in the test above): its z alone
    t2 = (4 / 36) / math.sqrt((1 / 6 + 6 / 30) * 120 / 36 / 5 / 36)
    z = stats.norm.isf(stats.t.sf(t2, 5))
    for a, b, sign in (("msd/rf", "sd/rf", 1), ("sd/rf", "msd/rf", -1)):
        out = _cli(tmp_path, "--a", a, "--b", b).output
        assert (f"left out (no variance: every fold differs by the same amount: A-B {sign * 100 / 6:+.2f} points in "
                f"every fold, {'A' if sign > 0 else 'B'} better; no p-value to combine)") in out
        assert f"combined: z = {sign * z:+.2f} (positive: A better), two-sided p = {2 * stats.norm.sf(z):.4g}" in out
        assert "p = 0 " not in out and "inf" not in out
