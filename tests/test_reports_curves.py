"""Data curves in the reports (learning curve over training subjects, calibration over labelled captures
of the test subject), on fake results whose every point's accuracy is known by construction."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from rich.console import Console
from scipy import stats

from touchbench.cli.main import cli
from touchbench.reports.curve_table import size_label, size_words
from touchbench.reports.curves import Curve
from touchbench.reports.figures import plot_table
from touchbench.reports.figures import learning_curve
from touchbench.reports.figures.confusion import confusion_matrix
from touchbench.reports.html import write_report
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import print_terminal, to_json, to_markdown
from touchbench.reports.results import load_results
from touchbench.reports.testing import FakeMethod, write_fake_run

SUBJECTS = ["s1", "s2", "s3", "s4"]
CAPS = pd.DataFrame([(f"{s}-{g}-{r}", s, g) for s in SUBJECTS for g in ("pat", "rub") for r in range(5)],
                    columns=["capture_id", "subject", "gesture"])
BASE = {f"subject={s}": CAPS[CAPS["subject"] == s]["capture_id"].tolist() for s in SUBJECTS}  # 10 captures each

# wrong captures (of 10) per point (size, draw) and base fold s1..s4
LEARN = {(1, 0): [6, 4, 5, 5], (1, 1): [4, 4, 3, 5], (2, 0): [2, 3, 2, 3], (2, 1): [2, 1, 2, 3], (3, 0): [1, 2, 1, 2]}
CALIB = {(0, 0): [5, 4, 5, 4], (1, 0): [3, 3, 4, 2], (1, 1): [3, 4, 4, 2], (3, 0): [1, 2, 2, 1], (3, 1): [1, 2, 1, 1]}


def _folds(points, letter):
    return {f"{letter}{n}#{d}/{b}": ids for n, d in points for b, ids in BASE.items()}


def _wrong(table, letter):
    return {f"{letter}{n}#{d}/{b}": ids[:c] for (n, d), counts in table.items() for (b, ids), c in zip(BASE.items(), counts)}


def _flat(table):
    return {p: [3, 3, 3, 3] for p in table}  # 70 % at every point


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("curves")
    write_fake_run(d / "learn", CAPS, _folds(LEARN, "n"), [
        FakeMethod("msd", "rf", wrong=_wrong(LEARN, "n")), FakeMethod("sd", "rf", wrong=_wrong(_flat(LEARN), "n")),
    ], scheme={"name": "loso"}, run_id="learn", curve="subjects")
    write_fake_run(d / "calib", CAPS, _folds(CALIB, "k"), [
        FakeMethod("msd", "rf", wrong=_wrong(CALIB, "k")), FakeMethod("sd", "rf", wrong=_wrong(_flat(CALIB), "k")),
    ], scheme={"name": "loso"}, run_id="calib", curve="calibration")
    write_fake_run(d / "plain", CAPS, BASE, [FakeMethod("msd", "rf", wrong={"subject=s1": BASE["subject=s1"][:2]})],
                   scheme={"name": "loso"}, run_id="plain")
    return d


def _board(path, **kw):
    [lb] = build_leaderboards(load_results([path]), **kw)
    return lb


def _t(values):
    """Mean and 95 % Student t interval, computed here from scipy's t distribution."""
    v = np.asarray(values, dtype=np.float64)
    half = stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / math.sqrt(len(v))
    return v.mean(), v.mean() - half, v.mean() + half


def _units(table, size):
    """Per base fold, the mean over the draws of the point's accuracy (by hand from the wrong counts)."""
    draws = [np.array(c) for (n, _), c in table.items() if n == size]
    return 1 - np.mean(draws, axis=0) / 10


def test_learning_curve_means_and_intervals(runs):
    lb = _board(runs / "learn")
    pts = lb.curve.points
    msd = lb.rows.set_index("features").loc["msd", "method_id"]
    # n=2: the draws' means per subject are 0.8, 0.8, 0.8, 0.7
    assert list(_units(LEARN, 2)) == pytest.approx([0.8, 0.8, 0.8, 0.7])
    for size in (1, 2, 3):
        p = pts[(pts["method_id"] == msd) & (pts["size"] == size)].iloc[0]
        mean, lo, hi = _t(_units(LEARN, size))
        assert p["n_units"] == 4 and p["ci_method"] == "t"
        assert (p["accuracy"], p["ci_low"], p["ci_high"]) == pytest.approx((mean, max(lo, 0), min(hi, 1)))
    assert pts[(pts["method_id"] == msd) & (pts["size"] == 2)]["accuracy"].iloc[0] == pytest.approx(0.775)
    assert lb.curve.sizes == [1.0, 2.0, 3.0]


def test_the_table_ranks_at_the_full_point(runs):
    lb = _board(runs / "learn")
    r = lb.rows.set_index("features")
    # the full point n=3 alone: 0.9, 0.8, 0.9, 0.8 over the 4 subjects, never the smaller points
    assert r.loc["msd", "accuracy"] == pytest.approx(0.85) and r.loc["msd", "n_folds"] == 4
    assert r.loc["sd", "accuracy"] == pytest.approx(0.70)
    assert "full point (n=3" in lb.notes[0]


def test_confusion_matrix_of_the_full_point(runs):
    rs = load_results([runs / "learn"])
    [lb] = build_leaderboards(rs)
    msd = lb.rows.set_index("features").loc["msd", "method_id"]
    m = confusion_matrix(rs, lb, msd)
    # n=3 alone: 40 test captures, 1 + 2 + 1 + 2 of them wrong (never the other points' predictions)
    assert int(m.to_numpy().sum()) == 40 and int(np.trace(m.to_numpy())) == 34


def test_smallest_size_reaching_the_share(runs):
    lb = _board(runs / "learn")
    reach = lb.curve.reach.set_index("method_id")
    msd, sd = (lb.rows.set_index("features").loc[f, "method_id"] for f in ("msd", "sd"))
    # full 0.85: 95 % of it is 0.8075, which only n=3 reaches; 90 % is 0.765, reached at n=2 (0.775)
    assert reach.loc[msd, "size"] == 3 and reach.loc[sd, "size"] == 1
    lb90 = _board(runs / "learn", fraction=0.9)
    assert lb90.curve.reach.set_index("method_id").loc[msd, "size"] == 2


def test_calibration_gains_paired_over_test_folds(runs):
    lb = _board(runs / "calib")
    msd = lb.rows.set_index("features").loc["msd", "method_id"]
    g = lb.curve.gains[lb.curve.gains["method_id"] == msd].set_index("size")
    for k in (1, 3):
        diffs = _units(CALIB, k) - _units(CALIB, 0)
        mean, lo, hi = _t(diffs)
        assert (g.loc[k, "gain"], g.loc[k, "ci_low"], g.loc[k, "ci_high"]) == pytest.approx((mean, lo, hi))
    assert g.loc[1, "gain"] == pytest.approx(0.1375) and g.loc[3, "gain"] == pytest.approx(0.3125)
    # the table ranks at k=0 (0.5, 0.6, 0.5, 0.6), the baseline
    assert lb.rows.set_index("features").loc["msd", "accuracy"] == pytest.approx(0.55)
    reach = lb.curve.reach.set_index("method_id").loc[msd]
    assert reach["baseline"] == pytest.approx(0.55) and reach["full_size"] == 3 and reach["size"] == 3
    # 79 % of k=3's 0.8625 is 0.681..., which k=1 (0.6875) reaches
    assert _board(runs / "calib", fraction=0.79).curve.reach.set_index("method_id").loc[msd, "size"] == 1


def _loop_interval(a, b=None, resamples=4000, seed=11):
    """A plain-loop pigeonhole bootstrap, written here: per resample the captures (rows) drawn once,
    each point's draws (columns) on its own, and the mean over the scored cells drawn; the 2.5 and
    97.5 percentiles of the resamples' means (of ``a``'s minus ``b``'s)."""
    rng = np.random.default_rng(seed)
    stats_ = []
    for _ in range(resamples):
        rows = rng.integers(0, a.shape[0], a.shape[0])
        means = []
        for m in (a,) if b is None else (a, b):
            cols = rng.integers(0, m.shape[1], m.shape[1])
            cells = [m[i, j] for i in rows for j in cols if not math.isnan(m[i, j])]
            means.append(sum(cells) / len(cells))
        stats_.append(means[0] - (means[1] if b is not None else 0.0))
    return tuple(np.percentile(stats_, [2.5, 97.5]))


def test_one_test_set_bootstraps_draws_and_captures(tmp_path):
    ids = CAPS["capture_id"].tolist()  # 40 captures, one holdout
    table = {(1, 0): 10, (1, 1): 14, (3, 0): 4}
    folds = {f"n{n}#{d}/holdout": ids for n, d in table}
    write_fake_run(tmp_path / "one", CAPS, folds, [FakeMethod("msd", "rf", wrong={
        f"n{n}#{d}/holdout": ids[:c] for (n, d), c in table.items()})], run_id="one", curve="subjects")
    lb = _board(tmp_path / "one")
    p = lb.curve.points.set_index("size")
    assert p.loc[1.0, "accuracy"] == pytest.approx(1 - 12 / 40) and p.loc[1.0, "ci_method"] == "bootstrap"
    assert p.loc[1.0, "n_units"] == 1 and p.loc[1.0, "ci_low"] < 0.7 < p.loc[1.0, "ci_high"]
    # captures x draws, built from the table above: draw 0 wrong on the first 10, draw 1 on the first 14
    m = np.ones((40, 2))
    m[:10, 0] = m[:14, 1] = 0.0
    lo, hi = _loop_interval(m)
    assert (p.loc[1.0, "ci_low"], p.loc[1.0, "ci_high"]) == pytest.approx((lo, hi), abs=0.015)
    three = p.loc[3.0]  # one draw: a bootstrap over the captures alone, the normal interval of 36 / 40
    half = 1.959964 * math.sqrt(0.9 * 0.1 / 40)
    assert (three["ci_low"], three["ci_high"]) == pytest.approx((0.9 - half, 0.9 + half), abs=0.03)


def test_terminal_table_and_sentences(runs):
    lb = _board(runs / "learn", fraction=0.9)
    console = Console(width=200, record=True)
    print_terminal([lb], console)
    text = console.export_text()
    assert "learning curve" in text and "77.5 [69.5, 85.5]" in text  # 0.775 -/+ 3.182 * 0.05 / 2
    assert "msd / rf reaches 90 % of its full accuracy with 2 subjects" in text
    narrow = Console(width=60, record=True)
    print_terminal([lb], narrow)
    out = narrow.export_text()
    # the smallest and largest sizes and the reach stay; the interval goes below its number, never cut
    assert "n=1" in out and "n=3" in out and "90 % of" in out
    assert "[75.8, 94.2]" in out and "85.0 [75.8" not in out


def test_calibration_terminal_and_markdown(runs):
    lb = _board(runs / "calib")
    console = Console(width=200, record=True)
    print_terminal([lb], console)
    text = console.export_text()
    assert "gain over k=0" in text and "+13.7" in text and "+31.3" in text
    assert "msd / rf: 55.0 % with no labelled capture from the test data" in text
    md = to_markdown([lb])
    assert "calibration curve" in md and "| k=0 | k=1 | k=3 |" in md
    doc = json.loads(to_json([lb]))["tables"][0]["curve"]
    assert doc["axis"] == "calibration" and doc["sizes"] == [0.0, 1.0, 3.0]


def test_figure_one_line_and_band_per_method(runs, tmp_path, monkeypatch):
    lb = _board(runs / "learn")
    made = plot_table(load_results([runs / "learn"]), lb, tmp_path, ["learning-curve"], formats=("svg",))
    [path] = made["learning-curve"]
    assert path.is_file() and path.stat().st_size > 0
    seen = []
    monkeypatch.setattr(learning_curve, "save", lambda fig, base, formats: seen.append(fig) or [])
    learning_curve.plot_learning_curve(lb, tmp_path / "x", "column", ("svg",))
    [ax] = seen[0].axes
    assert len(ax.lines) == 2 and len(ax.collections) == 2  # a line and a band per method
    title = ax.get_title().replace("\n", " ")
    assert "held-out captures against n training subjects" in title and "over 4 test folds" in title
    assert ax.get_xlabel() == "training subjects (n)"
    assert list(ax.lines[0].get_ydata()) == pytest.approx([55.0, 77.5, 85.0])


def test_html_report_holds_the_curve(runs, tmp_path):
    rs = load_results([runs / "calib"])
    lbs = build_leaderboards(rs)
    page = write_report(rs, lbs, tmp_path / "rep", kinds=("learning-curve",))
    html = page.read_text()
    assert "calibration curve" in html and "<td class='num'>86.2 [" in html and "gain over k=0" in html


def test_cli_fraction(runs, tmp_path):
    res = CliRunner().invoke(cli, ["leaderboard", str(runs / "learn"), "--fraction", "0.9"], env={"COLUMNS": "200"})
    assert res.exit_code == 0, res.output
    assert "reaches 90 % of its full accuracy with 2 subjects" in res.output
    bad = CliRunner().invoke(cli, ["leaderboard", str(runs / "learn"), "--fraction", "1.5"])
    assert bad.exit_code != 0 and "--fraction" in bad.output
    res = CliRunner().invoke(cli, ["plot", str(runs / "learn"), "--out", str(tmp_path), "--kind", "learning-curve",
                                   "--format", "png"])
    assert res.exit_code == 0, res.output
    assert len(list(tmp_path.glob("*learning-curve.png"))) == 1


def test_two_curves_never_share_a_table(runs):
    lbs = build_leaderboards(load_results([runs / "learn", runs / "calib"]))  # one dataset, one scheme label
    assert sorted(lb.curve.axis for lb in lbs) == ["calibration", "subjects"]
    assert sorted(lb.rows.set_index("features").loc["msd", "accuracy"] for lb in lbs) == pytest.approx([0.55, 0.85])


def test_off_curve_run_is_unchanged(runs):
    rs = load_results([runs / "plain"])
    assert not rs.scores["fold_key"].str.contains("|", regex=False).any()
    lb = _board(runs / "plain")
    assert lb.curve is None and not any("curve" in n for n in lb.notes)
    assert lb.rows["accuracy"].iloc[0] == pytest.approx((0.8 + 1 + 1 + 1) / 4) and lb.rows["n_folds"].iloc[0] == 4
    console = Console(width=200, record=True)
    print_terminal([lb], console)
    assert "curve" not in console.export_text() and "curve" not in to_markdown([lb])
    assert json.loads(to_json([lb]))["tables"][0]["curve"] is None


def test_sizes_read_as_subjects_shares_or_captures():
    empty = pd.DataFrame()
    shares = Curve("subjects", [0.25, 0.5, 1.0], empty, empty, empty, 0.95)
    counts = Curve("subjects", [0.5, 2.0, 8.0], empty, empty, empty, 0.95)
    calib = Curve("calibration", [0.0, 1.0, 5.0], empty, empty, empty, 0.95)
    assert [size_label(shares, s) for s in shares.sizes] == ["25 %", "50 %", "100 %"]
    assert [size_label(counts, s) for s in counts.sizes] == ["50 %", "n=2", "n=8"]
    assert size_words(counts, 1.0) == "1 subject" and size_words(shares, 1.0) == "100 % of the training subjects"
    assert [size_label(calib, s) for s in calib.sizes] == ["k=0", "k=1", "k=5"]
    assert size_words(calib, 0.0) == "no labelled capture from the test data"
    assert size_words(calib, 5.0) == "5 labelled captures per class"


def test_base_folds_with_different_numbers_of_training_subjects(tmp_path):
    """Each base fold's own largest n is its full point: one column "all", and the table's rows."""
    sides = {"fa": CAPS[CAPS["subject"].isin(["s1", "s2"])]["capture_id"].tolist(),  # 20 captures each
             "fb": CAPS[CAPS["subject"].isin(["s3", "s4"])]["capture_id"].tolist()}
    wrong = {"n1#0/fa": 8, "n2#0/fa": 4, "n3#0/fa": 2, "n1#0/fb": 10, "n2#0/fb": 3}  # fa has 3 training subjects, fb 2
    folds = {name: sides[name.split("/")[1]] for name in wrong}
    write_fake_run(tmp_path / "uneven", CAPS, folds, [FakeMethod("msd", "rf", wrong={
        name: folds[name][:c] for name, c in wrong.items()})], run_id="uneven", curve="subjects")
    lb = _board(tmp_path / "uneven")
    assert lb.rows["accuracy"].iloc[0] == pytest.approx((0.9 + 0.85) / 2) and lb.rows["n_folds"].iloc[0] == 2
    p = lb.curve.points.set_index("size")
    assert lb.curve.sizes == [1.0, 2.0, 3.0] and lb.curve.full_varies
    assert p.loc[1.0, "accuracy"] == pytest.approx(0.55) and p.loc[1.0, "n_units"] == 2
    assert p.loc[2.0, "accuracy"] == pytest.approx(0.8) and p.loc[2.0, "n_units"] == 1  # fa's n=2 alone
    assert p.loc[3.0, "accuracy"] == pytest.approx(0.875) and p.loc[3.0, "n_units"] == 2
    header = to_markdown([lb])
    assert "| method | n=1 | n=2 | all |" in header and "(every training subject)" in header


def test_calibration_draws_scoring_different_captures_stay_one_test_fold(tmp_path):
    """A calibration pool is drawn per draw, so the draws of a point score different captures: they
    are still one test fold (averaged first), in the curve and in the table at k=0."""
    wrong0 = {"subject=s1": (2, 4), "subject=s2": (0, 2), "subject=s3": (4, 4), "subject=s4": (2, 2)}  # of 8
    folds, wrong = {}, {}
    for b, ids in BASE.items():
        for d, scored in enumerate((ids[:8], ids[2:])):
            for k in (0, 2):
                folds[f"k{k}#{d}/{b}"] = scored
                wrong[f"k{k}#{d}/{b}"] = scored[:wrong0[b][d]] if k == 0 else []
    write_fake_run(tmp_path / "pools", CAPS, folds, [FakeMethod("msd", "rf", wrong=wrong)], run_id="pools",
                   curve="calibration")
    lb = _board(tmp_path / "pools")
    per_base = [0.625, 0.875, 0.5, 0.75]  # the two draws' accuracies averaged, e.g. s1: (6/8 + 4/8) / 2
    assert lb.rows["n_folds"].iloc[0] == 4 and lb.rows["accuracy"].iloc[0] == pytest.approx(np.mean(per_base))
    p = lb.curve.points.set_index("size")
    assert p.loc[0.0, "n_units"] == 4 and p.loc[0.0, "n_draws"] == 2
    g = lb.curve.gains.set_index("size").loc[2.0]
    mean, lo, hi = _t([1 - v for v in per_base])
    assert (g["gain"], g["ci_low"], g["ci_high"], g["n_units"]) == pytest.approx((mean, lo, hi, 4))


def test_one_test_set_calibration_gain_by_bootstrap(tmp_path):
    ids = CAPS["capture_id"].tolist()
    folds = {f"k{k}#{d}/holdout": ids[d * 5:] for k in (0, 1) for d in (0, 1)}  # the draws score different captures
    wrong = {f"k0#{d}/holdout": ids[d * 5:][:10] for d in (0, 1)}  # k=0: 10 wrong; k=1: none
    write_fake_run(tmp_path / "one", CAPS, folds, [FakeMethod("msd", "rf", wrong=wrong)], run_id="one",
                   curve="calibration")
    g = _board(tmp_path / "one").curve.gains.set_index("size").loc[1.0]
    gain = ((1 - (1 - 10 / 40)) + (1 - (1 - 10 / 35))) / 2  # 1 minus each draw's accuracy at k=0, averaged
    assert g["gain"] == pytest.approx(gain) and g["ci_method"] == "bootstrap" and g["n_units"] == 1
    assert 0 < g["ci_low"] < gain < g["ci_high"] < 1
    # captures x draws on the union of the captures (draw 1 did not score the first 5): k=1 right
    # wherever scored, k=0 wrong on each draw's first 10 scored
    k1, k0 = np.ones((40, 2)), np.ones((40, 2))
    k1[:5, 1] = k0[:5, 1] = math.nan
    k0[:10, 0] = k0[5:15, 1] = 0.0
    lo, hi = _loop_interval(k1, k0)
    assert (g["ci_low"], g["ci_high"]) == pytest.approx((lo, hi), abs=0.015)


def test_the_tables_per_capture_columns_read_the_reference_point_only(runs, tmp_path):
    """Held-out accuracy (and every column read from the predictions) is the reference point's, not a
    pool of every point of the curve."""
    import shutil
    d = tmp_path / "learn"
    shutil.copytree(runs / "learn", d)
    manifest = json.loads((d / "manifest.json").read_text())
    manifest["protocol"]["design"] = {"subjects": ["s1"], "methods": [], "rows": {}, "note": ""}
    manifest["protocol"]["design_captures"] = BASE["subject=s1"]
    (d / "manifest.json").write_text(json.dumps(manifest))
    rows = _board(d).rows.set_index("features")
    # the full point n=3 misses 1, 2, 1, 2 of 10 in s1..s4: held out (s2..s4) = mean(0.8, 0.9, 0.8)
    assert rows.loc["msd", "held_out_accuracy"] == pytest.approx((0.8 + 0.9 + 0.8) / 3)
    assert rows.loc["msd", "n_held_out"] == 30
