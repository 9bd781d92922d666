"""Paper-ready figures and leaderboards: formats and print sizes, fonts of at least 7 pt at print
size, names without hashes and unique for a dataset given as a Parquet file, critical difference
diagrams (aeon), intervals within [0, 100] %, failed methods shown failed, rows told apart by their
parameters, markup-safe titles, mean ranks across tables."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import fake_loso
from rich.console import Console
from scipy.stats import rankdata

from touchbench.reports.across import mean_ranks
from touchbench.reports.labels import method_labels
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import display_rows, print_terminal, to_markdown
from touchbench.reports.figures import SIZES, plot_table
from touchbench.reports.figures.cd import NoDiagram, plot_cd_across
from touchbench.reports.html import write_report
from touchbench.reports.figures.pareto import plot_pareto
from touchbench.reports.results import load_results
from touchbench.reports.testing import FakeMethod, write_fake_run

SUBJECTS = ["s1", "s2", "s3", "s4", "s5"]
GESTURES = ["pat", "rub", "stroke"]
CAPS, FOLDS, _wrong = fake_loso(SUBJECTS, GESTURES)


METHODS = [  # 6 test captures per fold: accuracies (6 - wrong) / 6
    FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1, 0]), latency_ms=4.0),
    FakeMethod("sd", "rf", wrong=_wrong([2, 2, 1, 2, 2]), latency_ms=0.5),
    FakeMethod("bmh", "lda", wrong=_wrong([3, 2, 3, 3, 2]), latency_ms=0.2),
]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    # a dataset given as a Parquet file: its name is the file's
    write_fake_run(d / "a", CAPS, FOLDS, METHODS, dataset="my-recordings.parquet", scheme={"name": "loso"},
                   run_id="a")
    write_fake_run(d / "b", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([1, 1, 1, 1, 1])),
        FakeMethod("sd", "rf", wrong=_wrong([0, 0, 1, 0, 0])),
        FakeMethod("bmh", "lda", wrong=_wrong([2, 2, 2, 2, 2])),
    ], dataset="other", dataset_hash="e" * 64, scheme={"name": "loso"}, run_id="b")
    return d


def _svg(path):
    """Width in points and every font size (points) of an SVG matplotlib wrote (1 user unit = 1 pt)."""
    root = ET.parse(path).getroot()
    width = float(re.match(r"[\d.]+", root.get("width")).group())
    sizes = [float(m) for el in root.iter() for m in re.findall(r"font-size: ([\d.]+)px", el.get("style") or "")]
    return width, sizes


# ----------------------------------------------------------------- names
def test_file_names_are_unique_readable_and_hash_free_named_by_the_results_folder(runs, tmp_path):
    rs = load_results([runs / "a"])
    [lb] = build_leaderboards(rs)
    made = plot_table(rs, lb, tmp_path, methods=list(lb.rows["method_id"][:2]))
    files = [p for paths in made.values() for p in paths]
    assert len(files) == len({p.name for p in files}) == 3 * len(made)  # pdf, svg, png each, none overwritten
    stems = sorted({p.name.rsplit(".", 1)[0] for p in files})
    # the results folder is "a": the figures are named by it, not by the dataset and scheme
    assert stems == ["a-confusion-msd-rf", "a-confusion-sd-rf", "a-pareto", "a-subjects"]
    assert lb.title == "my-recordings.parquet — loso" and "dddd" not in lb.title
    taken = set()
    plot_table(rs, lb, tmp_path / "two", kinds=("pareto",), taken=taken)
    again = plot_table(rs, lb, tmp_path / "two", kinds=("pareto",), taken=taken)  # a second table of that name
    assert [p.name for p in again["pareto"]] == ["a-2-pareto.pdf", "a-2-pareto.svg", "a-2-pareto.png"]


def test_two_datasets_of_one_name_are_told_apart_in_titles(runs, tmp_path):
    write_fake_run(tmp_path / "c", CAPS, FOLDS, METHODS[:2], dataset="other", dataset_hash="f" * 64,
                   scheme={"name": "loso"}, run_id="c")
    lbs = build_leaderboards(load_results([runs / "b", tmp_path / "c"]))
    assert sorted(lb.title for lb in lbs) == ["other (data 1) — loso", "other (data 2) — loso"]


def test_a_title_names_the_evaluation_and_never_carries_a_whole_file_name_pattern(tmp_path):
    import json

    pattern = r"(?P<study>\d+)-(?P<participant>\d+)(?P<substrate>curve|foam|none)(?P<gesture>[a-z]+)"
    scheme = {"name": "cross-dataset", "test": {"name": "other-study/", "format": "haart-raw",
                                                "options": {"pattern": pattern}}}
    write_fake_run(tmp_path / "a", CAPS, FOLDS, METHODS[:2], dataset="haart", scheme=scheme,
                   protocol="to-other-study", run_id="a")
    [lb] = build_leaderboards(load_results([tmp_path / "a"]))
    assert pattern not in lb.title and "(?P<" not in lb.title
    # named as a person would: what it was trained on and what tested on, never the scheme's options
    assert lb.title == "haart — cross-dataset: trained on haart, tested on other-study"
    assert pattern in lb.scheme  # the table's identity (--scheme, JSON) keeps the whole entry
    console = Console(record=True, width=300)
    print_terminal([lb], console)
    assert "(?P<" not in console.export_text() and "(?P<" not in to_markdown([lb])
    # one evaluation of several: its name leads the title, the scheme as written
    write_fake_run(tmp_path / "b", CAPS, FOLDS, METHODS[:2], dataset="haart", scheme={"name": "challenge",
                   "column": "substrate", "train": ["foam", "none"], "test": ["curve"]}, run_id="b")
    manifest = json.loads((tmp_path / "b" / "manifest.json").read_text())
    manifest["protocol"]["evaluation"] = "to-curve"
    (tmp_path / "b" / "manifest.json").write_text(json.dumps(manifest))
    [lb] = build_leaderboards(load_results([tmp_path / "b"]))
    assert lb.title == "haart — to-curve: challenge(column=substrate,test=[curve],train=[foam,none])"



@pytest.mark.parametrize("test_name, shown", [
    ("/srv/studies/2024/haart-replication-recordings-second-site/", "haart-replication-recordings-second-site"),
    ("../recordings/session-3.parquet", "session-3.parquet"),
    ("socialtouch", "socialtouch"),
])
def test_a_cross_dataset_title_names_the_test_data_by_its_name_or_file_name(tmp_path, test_name, shown):
    import json

    scheme = {"name": "cross-dataset", "test": {"name": test_name, "format": "haart-raw",
                                                "filters": {"substrate": ["foam"]}, "options": {"pattern": "(?P<x>.+)"}}}
    write_fake_run(tmp_path / "a", CAPS, FOLDS, METHODS[:2], dataset="haart", scheme=scheme, run_id="a")
    [lb] = build_leaderboards(load_results([tmp_path / "a"]))
    assert lb.title == f"haart — cross-dataset: trained on haart, tested on {shown}"
    # one evaluation of several: its name, then the scheme named
    manifest = json.loads((tmp_path / "a" / "manifest.json").read_text())
    manifest["protocol"]["evaluation"] = "replication"
    (tmp_path / "a" / "manifest.json").write_text(json.dumps(manifest))
    [lb] = build_leaderboards(load_results([tmp_path / "a"]))
    assert lb.title == f"haart — replication — cross-dataset: trained on haart, tested on {shown}"
    assert "{" not in to_markdown([lb]).split("\n")[2]  # the Markdown heading: no raw options


# ----------------------------------------------------------------- print sizes and fonts
@pytest.mark.parametrize("size", ["text", "column"])
def test_figures_are_at_print_width_with_fonts_of_at_least_7_pt(runs, tmp_path, size):
    rs = load_results([runs / "a"])
    [lb] = build_leaderboards(rs)
    made = plot_table(rs, lb, tmp_path, size=size)
    for kind, paths in made.items():
        pdf, svg, png = paths
        assert pdf.read_bytes()[:5] == b"%PDF-" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        width, fonts = _svg(svg)
        if kind != "cd":  # aeon sizes the diagram itself, to the width asked for
            assert width == pytest.approx(SIZES[size] * 72)
        assert fonts and min(fonts) >= 7.0, (kind, sorted(set(fonts)))


def test_png_is_300_dpi(runs, tmp_path):
    from PIL import Image

    [lb] = build_leaderboards(load_results([runs / "a"]))
    _, _, png = plot_pareto(lb, tmp_path / "p", size="text")
    with Image.open(png) as im:
        assert im.size[0] == 7 * 300 and round(im.info["dpi"][0]) == 300


# ----------------------------------------------------------------- critical difference diagrams
@pytest.fixture(scope="module")
def third(tmp_path_factory):
    """A third table of the three methods (ranks msd 1, sd 3, bmh 2)."""
    d = tmp_path_factory.mktemp("third")
    return write_fake_run(d, CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([0, 0, 0, 0, 0])),
        FakeMethod("sd", "rf", wrong=_wrong([3, 3, 3, 3, 3])),
        FakeMethod("bmh", "lda", wrong=_wrong([1, 1, 1, 1, 1])),
    ], dataset="third", dataset_hash="c" * 64, scheme={"name": "loso"}, run_id="c")


def test_critical_difference_diagram_across_tables_not_per_table(runs, third, tmp_path):
    lbs = build_leaderboards(load_results([runs / "a", runs / "b"]))
    # a table's folds are not data sets: the cd kind draws nothing for one table
    rs = load_results([runs / "a"])
    assert plot_table(rs, build_leaderboards(rs)[0], tmp_path, kinds=("cd",)) == {}
    # 3 methods over 2 tables: CD = 2.343 * sqrt(3 * 4 / (6 * 2)) = 2.34 > the largest rank difference 2;
    # 2.343**2 * 12 / (6 * 4) = 2.74: 3 tables are needed (Demsar 2006, Table 5)
    with pytest.raises(NoDiagram, match=r"critical difference at α=0.05: 2.34 .*at least 3 tables"):
        plot_cd_across(lbs, tmp_path / "across")
    lbs3 = build_leaderboards(load_results([runs / "a", runs / "b", third]))
    pdf, svg, png = plot_cd_across(lbs3, tmp_path / "across")  # CD = 2.343 * sqrt(12 / 18) = 1.91 <= 2
    text = svg.read_text()
    assert "mean rank over 3 tables" in text and all(lab in text for lab in ("msd / rf", "sd / rf", "bmh / lda"))


def test_friedman_across_tables_against_scipy(runs, third):
    from scipy.stats import friedmanchisquare

    from touchbench.reports.across import across_friedman

    lbs = build_leaderboards(load_results([runs / "a", runs / "b", third]))
    f = across_friedman(lbs)
    # mean accuracies per table (rows) of msd, sd, bmh: worked out from the wrong counts above
    acc = np.array([[14 / 15, 20 / 30, 17 / 30], [25 / 30, 29 / 30, 20 / 30], [1.0, 15 / 30, 25 / 30]])
    ref = friedmanchisquare(*acc.T)
    assert (f.n_datasets, f.k) == (3, 3)
    assert f.statistic == pytest.approx(ref.statistic) and f.pvalue == pytest.approx(ref.pvalue)
    assert "Friedman test over N = 3 tables of 3 methods" in to_markdown(lbs)


def test_report_without_aeon_is_written_with_a_note(runs, third, tmp_path, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "aeon.visualisation", None)  # import aeon.visualisation: ImportError
    monkeypatch.setitem(sys.modules, "aeon", None)
    rs = load_results([runs / "a", runs / "b", third])
    page = write_report(rs, build_leaderboards(rs), tmp_path / "rep")
    text = page.read_text()
    assert "Across 3 tables" in text and "pip install &#x27;touchbench[peers]&#x27;" in text
    assert (tmp_path / "rep" / "leaderboard.md").exists() and not list((tmp_path / "rep").rglob("*cd*"))


# ----------------------------------------------------------------- leaderboard
def test_intervals_stay_within_0_and_100(runs):
    [lb] = build_leaderboards(load_results([runs / "a"]))
    assert ((lb.rows["ci_low"] >= 0) & (lb.rows["ci_high"] <= 1)).all()
    # msd: folds 1, 5/6, 1, 5/6, 1 -> mean 14/15; its t interval would pass 100 %
    msd = lb.rows[lb.rows["features"] == "msd"].iloc[0]
    acc = np.array([1, 5 / 6, 1, 5 / 6, 1])
    from scipy import stats
    half = stats.t.ppf(0.975, 4) * acc.std(ddof=1) / np.sqrt(5)
    assert acc.mean() + half > 1 and msd["ci_high"] == 1.0
    assert msd["ci_low"] == pytest.approx(acc.mean() - half)
    _, cells = display_rows(lb)
    assert cells[0][6] == f"{100 * (acc.mean() - half):.1f}–100.0"


def test_failed_methods_show_failed_with_their_error(tmp_path):
    write_fake_run(tmp_path / "r", CAPS, FOLDS, [METHODS[0], FakeMethod("sd", "boom", failed_folds=list(FOLDS))],
                   scheme={"name": "loso"})
    [lb] = build_leaderboards(load_results([tmp_path / "r"]))
    header, cells = display_rows(lb)
    row = next(c for c in cells if c[3] == "boom")
    assert row[5] == "failed" and row[header.index("vs best: Δ pp, p (Holm)")].startswith("failed: ")
    assert "not tested" not in " ".join(row)


def test_rows_that_differ_only_by_feature_parameters_show_them(tmp_path):
    write_fake_run(tmp_path / "r", CAPS, FOLDS, [
        FakeMethod("sd", "gaus-rf", feature_params=[["sd", {"bins": 8}]], wrong=_wrong([0, 0, 0, 0, 0])),
        FakeMethod("sd", "gaus-rf", feature_params=[["sd", {"bins": 16}]], wrong=_wrong([1, 1, 1, 1, 1])),
    ], scheme={"name": "loso"})
    [lb] = build_leaderboards(load_results([tmp_path / "r"]))
    labels = sorted(method_labels(lb.rows).values())
    assert labels == ["sd / gaus-rf (features: sd; bins=16)", "sd / gaus-rf (features: sd; bins=8)"]
    _, cells = display_rows(lb)
    assert cells[0][2] != cells[1][2] and "bins=8" in cells[0][2]


def test_titles_are_not_read_as_markup(tmp_path):
    write_fake_run(tmp_path / "r", CAPS, FOLDS, METHODS[:2], dataset="[b5830b]", scheme={"name": "loso"})
    lbs = build_leaderboards(load_results([tmp_path / "r"]))
    console = Console(record=True, width=300)
    print_terminal(lbs, console)
    assert "[b5830b] — loso" in console.export_text()


def test_mean_ranks_across_tables_by_hand(runs):
    lbs = build_leaderboards(load_results([runs / "a", runs / "b"]))
    # table a: msd 14/15, sd 2/3 (20/30), bmh 17/30 -> ranks 1, 2, 3
    # table b: msd 25/30, sd 29/30, bmh 20/30 -> ranks 2, 1, 3
    ranks = mean_ranks(lbs).set_index("method")
    assert ranks.loc["msd / rf", "mean_rank"] == pytest.approx(1.5)
    assert ranks.loc["sd / rf", "mean_rank"] == pytest.approx(1.5)
    assert ranks.loc["bmh / lda", "mean_rank"] == pytest.approx(3.0)
    assert (ranks["tables"] == 2).all()
    # the same with scipy on the table the function builds from
    acc = np.array([[14 / 15, 20 / 30, 17 / 30], [25 / 30, 29 / 30, 20 / 30]])
    expected = np.mean([rankdata(-row) for row in acc], axis=0)
    assert [ranks.loc[m, "mean_rank"] for m in ("msd / rf", "sd / rf", "bmh / lda")] == pytest.approx(expected)
    md = to_markdown(lbs)
    assert "## Mean rank across 2 tables" in md and "| bmh / lda | 3.00 |" in md
