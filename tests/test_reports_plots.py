"""Plots, the HTML report and the report commands, on hand-built results."""

from __future__ import annotations

import base64
import json
import math
import pkgutil
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats
from helpers import fake_loso

from touchbench.cli.main import cli
from touchbench.cli.reports import parse_reference, plot
from touchbench.core.errors import UnknownNameError
from touchbench.reports import figures
from touchbench.reports.figures import FIGURES, plot_table
from touchbench.reports.html import write_report
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.figures.base import label_offsets
from touchbench.reports.figures.confusion import confusion_matrix, plot_confusion
from touchbench.reports.figures.frames import plot_frames
from touchbench.reports.results import load_results
from touchbench.reports.testing import FakeMethod, write_fake_run

SUBJECTS = ["s1", "s2", "s3", "s4"]
GESTURES = ["pat", "rub", "stroke"]
CAPS, FOLDS, _wrong = fake_loso(SUBJECTS, GESTURES)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    write_fake_run(d / "loso", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1]), latency_ms=4.0, fit_seconds=2.0),
        FakeMethod("sd", "rf", wrong=_wrong([2, 2, 1, 2]), latency_ms=0.5, fit_seconds=0.1),
    ], scheme={"name": "loso"}, run_id="loso")
    write_fake_run(d / "early", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([4, 4, 3, 4]), early_frames=27),
        FakeMethod("msd", "rf", wrong=_wrong([2, 2, 1, 2]), early_frames=54),
        FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1]), early_frames=108),
    ], scheme={"name": "early", "base": {"name": "loso"}, "frames": [27, 54, 108]}, run_id="early", frame_rate=54.0)
    return d


def test_confusion_counts_by_hand(runs, tmp_path):
    rs = load_results([runs / "loso"])
    [lb] = build_leaderboards(rs)
    best = lb.rows.iloc[0]
    assert best["features"] == "msd"
    m = confusion_matrix(rs, lb, best["method_id"])
    # msd misses the first capture (a pat) of folds s2 and s4, predicted as rub
    assert list(m.index) == GESTURES and list(m.columns) == GESTURES
    assert m.loc["pat", "pat"] == 6 and m.loc["pat", "rub"] == 2 and m.loc["rub", "rub"] == 8
    assert int(m.to_numpy().sum()) == 24
    pdf, svg, png = plot_confusion(rs, lb, best["method_id"], tmp_path / "conf")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    root = ET.parse(svg).getroot()
    texts = "".join(t.text or "" for t in root.iter() if t.tag.endswith("text"))
    for g in GESTURES:  # class names on the axes
        assert g in texts
    assert "row-normalised" in texts and "0.75" in texts  # pat recall 6/8


def test_frames_plot_has_seconds_axis(runs, tmp_path):
    rs = load_results([runs / "early"])
    [lb] = build_leaderboards(rs)
    assert lb.is_early and sorted(lb.rows["early_frames"]) == [27.0, 54.0, 108.0]
    # accuracy grows with frames seen: 15/24, 17/24, 22/24
    acc = lb.rows.set_index("early_frames")["accuracy"]
    assert acc[27.0] == pytest.approx(9 / 24) and acc[108.0] == pytest.approx(22 / 24)
    pdf, svg, png = plot_frames(lb, tmp_path / "frames")
    texts = "".join(t.text or "" for t in ET.parse(svg).getroot().iter() if t.tag.endswith("text"))
    assert "frames seen" in texts and "seconds seen (at 54 frames/s)" in texts


def test_html_report_is_self_contained(runs, tmp_path):
    rs = load_results([runs])
    lbs = build_leaderboards(rs)
    page = write_report(rs, lbs, tmp_path / "rep", title="test report")
    html = page.read_text()
    # every image embedded, nothing fetched from elsewhere
    assert html.count("data:image/png;base64,") >= 5
    assert not re.search(r'src="(?!data:)', html) and "<link" not in html and "<script" not in html
    first = re.search(r'data:image/png;base64,([A-Za-z0-9+/=]+)"', html).group(1)
    assert base64.b64decode(first)[:4] == b"\x89PNG"
    for name in ("leaderboard.md", "leaderboard.csv", "leaderboard.json"):
        assert (tmp_path / "rep" / name).is_file()
    kinds = {p.name.split("-")[-1].split(".")[0] for p in (tmp_path / "rep" / "plots").glob("*.png")}
    assert {"pareto", "frames", "subjects"} <= kinds
    assert len(list((tmp_path / "rep" / "plots").glob("*.svg"))) == len(list((tmp_path / "rep" / "plots").glob("*.png")))
    assert "early(base=loso)" in html and "★" in html


def test_cli_leaderboard_compare_plot(runs, tmp_path):
    r = CliRunner()
    res = r.invoke(cli, ["leaderboard", str(runs / "loso"), "--format", "md"])
    assert res.exit_code == 0, res.output
    assert "| 1 |" in res.output and "msd" in res.output
    res = r.invoke(cli, ["leaderboard", str(runs), "--out", str(tmp_path / "lb"), "--format", "json"])
    assert res.exit_code == 0, res.output
    js = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    assert len(js["tables"]) == 2
    res = r.invoke(cli, ["leaderboard", str(runs), "--scheme", "loso"], env={"COLUMNS": "250"})
    assert res.exit_code == 0 and "Pareto" in res.output  # a terminal wide enough for the Pareto column
    res = r.invoke(cli, ["compare", str(runs / "loso"), "--a", "msd/rf", "--b", "sd/rf"])
    assert res.exit_code == 0, res.output
    # per-fold differences (sixths): 2, 1, 1, 1: mean 5/24, sample variance 0.25 / 36; each fold tests 6
    # captures and trains on 18: corrected t = (5/24) / sqrt((1/4 + 6/18) * 0.25 / 36), 3 df
    t = (5 / 24) / math.sqrt((1 / 4 + 6 / 18) * 0.25 / 36)
    assert f"corrected resampled t-test, two-sided p = {2 * stats.t.sf(t, 3):.4g}" in res.output
    assert "subject=s1" in res.output and "pat" in res.output
    res = r.invoke(cli, ["compare", str(runs / "loso"), "--a", "msd/rf", "--b", "nope"])
    assert res.exit_code == 3 and "no method 'nope'" in res.output
    res = r.invoke(cli, ["plot", str(runs / "early"), "--out", str(tmp_path / "pl"), "--kind", "frames"])
    assert res.exit_code == 0, res.output
    assert len(list((tmp_path / "pl").glob("*frames.svg"))) == 1
    res = r.invoke(cli, ["leaderboard", str(tmp_path / "missing")])
    assert res.exit_code == 2


def test_pareto_references_and_labels(runs, tmp_path):
    r = CliRunner()
    res = r.invoke(cli, ["plot", str(runs / "loso"), "--out", str(tmp_path / "pl"), "--kind", "pareto",
                         "--reference", "paper A=66.5", "--reference", "target=88"])
    assert res.exit_code == 0, res.output
    svg = next((tmp_path / "pl").glob("*pareto.svg")).read_text()
    # the reference labels, and the methods labelled by features/classifier (two feature sets here)
    assert "paper A 66.5 %" in svg and "target 88 %" in svg
    assert "msd/rf" in svg and "sd/rf" in svg
    for bad in ("nolabel", "x=abc", "x=101", "=50"):
        res = r.invoke(cli, ["plot", str(runs / "loso"), "--out", str(tmp_path / "pl"), "--reference", bad])
        assert res.exit_code == 2 and "--reference" in res.output and "LABEL=PERCENT" in res.output


def test_parse_reference_keeps_equals_signs_in_the_label():
    assert parse_reference("F1=acc=70.9") == ("F1=acc", 70.9)
    assert parse_reference(" best 2015 entry =70.9") == ("best 2015 entry", 70.9)


def test_label_offsets_move_colliding_labels_apart():
    # three labels 40 pt wide, 8.5 pt high at one point: the first right of it at (4, 3), each next one
    # 1 pt below the one before (3 - 8.5 - 1 = -6.5, then -16); a far one keeps (4, 3)
    offs = label_offsets(np.array([[100.0, 100.0], [100.0, 100.0], [100.0, 100.0], [400.0, 300.0]]),
                         np.array([40.0, 40.0, 40.0, 40.0]))
    assert offs == [(4, 3), (4, -6.5), (4, -16.0), (4, 3)]
    # a label below another but not under it (its box starts right of the first's end) stays in place
    offs = label_offsets(np.array([[100.0, 100.0], [150.0, 98.0]]), np.array([40.0, 40.0]))
    assert offs == [(4, 3), (4, 3)]


def test_label_offsets_avoid_drawn_text_and_the_panel_edge():
    # a label 40 pt wide at (100, 100); the box right of it, (104..144, 103..111.5), is taken by other
    # text: it moves below that text, its bottom at 103 - 8.5 - 1 = 93.5 (offset -6.5)
    offs = label_offsets(np.array([[100.0, 100.0]]), np.array([40.0]), taken=[(104.0, 103.0, 144.0, 111.5)])
    assert offs == [(4, -6.5)]
    # a point 10 pt from the panel's right edge (x1 = 110): no box right of it fits, so the label goes
    # left of the point: x from 100 - 40 - 4 = 56 to 96
    offs = label_offsets(np.array([[100.0, 100.0]]), np.array([40.0]), bounds=(0.0, 0.0, 110.0, 200.0))
    assert offs == [(-44, 3)]
    # heights as measured: a 12 pt high label moves 12 + 1 below the one before
    offs = label_offsets(np.array([[100.0, 100.0], [100.0, 100.0]]), np.array([40.0, 40.0]),
                         heights_pt=np.array([12.0, 12.0]))
    assert offs == [(4, 3), (4, -10.0)]


def test_pareto_leaves_out_a_cost_a_method_does_not_have(tmp_path):
    # one method computes its features inside its estimator (feature time 0): a log axis has no 0,
    # so it is left out of that panel only, and the panel says so
    write_fake_run(tmp_path / "run", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1]), latency_ms=4.0, feature_seconds_per_capture=2e-3),
        FakeMethod("raw", "rocket", wrong=_wrong([2, 2, 1, 2]), latency_ms=0.5, feature_seconds_per_capture=0.0),
    ], scheme={"name": "loso"}, run_id="zero")
    res = CliRunner().invoke(cli, ["plot", str(tmp_path / "run"), "--out", str(tmp_path / "pl"), "--kind", "pareto",
                                   "--format", "svg"])
    assert res.exit_code == 0, res.output
    svg = next((tmp_path / "pl").glob("*pareto.svg")).read_text()
    assert svg.count("not shown: 1 without this cost") == 1
    assert "1e-06" not in svg


def test_plot_name_gives_stable_file_names(runs, tmp_path):
    r = CliRunner()
    res = r.invoke(cli, ["plot", str(runs / "loso"), "--out", str(tmp_path / "pl"), "--kind", "pareto",
                         "--name", "figure-a"])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "pl").iterdir()) == ["figure-a-pareto.pdf", "figure-a-pareto.png",
                                                                   "figure-a-pareto.svg"]
    # one name cannot serve several tables
    res = r.invoke(cli, ["plot", str(runs / "loso"), str(runs / "early"), "--out", str(tmp_path / "p2"),
                         "--name", "figure-b"])
    assert res.exit_code == 3 and "--name figure-b" in res.output and "tables" in res.output


def test_plot_name_serves_a_table_and_its_adapted_methods_table(tmp_path):
    from touchbench.methods.base import ADAPTED

    caps, folds, wrong = fake_loso(["s1", "s2", "s3"])
    plain = FakeMethod("msd", "rf", wrong=wrong([1, 1, 1]), latency_ms=2.0)
    adapted = FakeMethod("msd", "rf-adapted", latency_ms=2.0, adaptation=ADAPTED)
    write_fake_run(tmp_path / "run", caps, folds, [plain, adapted], scheme={"name": "loso"})
    res = CliRunner().invoke(cli, ["plot", str(tmp_path / "run"), "--out", str(tmp_path / "pl"), "--kind", "pareto",
                                   "--format", "png", "--name", "fig"])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "pl").iterdir()) == ["fig-adapted-pareto.png", "fig-pareto.png"]


# ----------------------------------------------------------------- the figure kinds
def test_every_figure_module_registers_one_kind_named_after_it():
    modules = sorted(m.name for m in pkgutil.iter_modules(figures.__path__)
                     if not m.name.startswith("_") and m.name != "base")
    registered: dict[str, list[str]] = {}
    for e in FIGURES.entries():
        if e.plugin is None:
            registered.setdefault(e.obj.__module__, []).append(e.name)
            assert e.description and "\n" not in e.description, e.name
    assert modules and registered == {f"touchbench.reports.figures.{m}": [m.replace("_", "-")] for m in modules}


def test_plot_offers_exactly_the_registered_kinds(runs, tmp_path):
    [kind] = [p for p in plot.params if p.name == "kinds"]
    assert sorted(kind.type.choices) == FIGURES.names()
    res = CliRunner().invoke(cli, ["plot", str(runs / "loso"), "--out", str(tmp_path), "--kind", "nope"])
    assert res.exit_code == 2 and all(name in res.output for name in FIGURES.names())
    rs = load_results([runs / "loso"])
    [lb] = build_leaderboards(rs)
    with pytest.raises(UnknownNameError, match="unknown figure kind 'paretto'; did you mean 'pareto'"):
        plot_table(rs, lb, tmp_path, kinds=("paretto",))


def test_the_report_commands_read_the_figure_kinds_only_when_plot_needs_them():
    code = "import sys, touchbench.cli.reports\nprint([m for m in sys.modules if m.startswith('touchbench.reports.')])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _crowded_board(n: int):
    """A table of ``n`` methods all on the Pareto front within a few percent of latency and accuracy."""
    import pandas as pd

    from touchbench.reports.leaderboard import Leaderboard

    acc = 0.60 + 0.004 * np.arange(n)
    rows = pd.DataFrame({
        "features": [f"feature-set-{i}" for i in range(n)], "classifier": ["gaus-rf"] * n,
        "timing_machine": ["m-1"] * n, "latency_ms": 1.0 * 1.01 ** np.arange(n),
        "fit_seconds": np.full(n, 2.0), "feature_ms": 0.5 + 0.001 * np.arange(n),
        "accuracy": acc, "ci_low": acc - 0.05, "ci_high": acc + 0.05, "pareto": [True] * n, "leakage": [""] * n,
    })
    return Leaderboard(key="k", dataset="crowd", dataset_hash="0" * 64, target="gesture", scheme="loso", rows=rows,
                       folds=pd.DataFrame(), machines={"m-1": "test"}, reference_machine="m-1", pooled_machines=False,
                       alpha=0.05, frame_rate=54.0)


def _drawn_figure(monkeypatch, module, draw):
    """The figure ``draw()`` would save through ``module.save`` (kept open and drawn instead)."""
    kept = []
    monkeypatch.setattr(module, "save", lambda fig, *a, **k: kept.append(fig) or [])
    draw()
    [fig] = kept
    fig.canvas.draw()
    return fig


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("size", ["text", "column"])
def test_pareto_labels_never_overlap_in_a_crowded_panel(monkeypatch, tmp_path, size):
    from matplotlib.text import Text

    from touchbench.reports.figures import pareto

    lb = _crowded_board(10)
    fig = _drawn_figure(monkeypatch, pareto, lambda: pareto.plot_pareto(lb, tmp_path / "p", [("paper", 62.0)], size=size))
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        # the text's own box (an annotation's extent would take in its leader line)
        boxes = [(t.get_text(), Text.get_window_extent(t, renderer)) for t in ax.texts if t.get_text()]
        labels = [t for t, _ in boxes]
        assert sum(lab.startswith("feature-set-") for lab in labels) == 10  # every method labelled
        for i, (ta, a) in enumerate(boxes):
            for tb, b in boxes[i + 1:]:
                assert not _boxes_overlap(a, b), (ta, tb)


def _audit_figure(monkeypatch, tmp_path, published):
    import pandas as pd

    from touchbench.reports import audit
    from touchbench.reports.figures import base

    # two methods x two variants: four bars, all long (the leaky ones nearly 100 %)
    table = pd.DataFrame({"method": ["sd / gaus-rf"] * 2 + ["msd / gaus-rf"] * 2,
                          "variant": ["honest", "capture-kfold"] * 2, "accuracy": [0.62, 0.97, 0.55, 0.99]})
    return _drawn_figure(monkeypatch, base, lambda: audit.plot_audit(table, tmp_path / "audit", published))


@pytest.mark.parametrize("published", [None, {"sd / gaus-rf": {"value": 83.2, "tolerance": 5.0}}])
def test_the_audit_legend_covers_no_bar_and_the_axis_names_only_lines_drawn(monkeypatch, tmp_path, published):
    fig = _audit_figure(monkeypatch, tmp_path, published)
    [ax] = fig.axes
    renderer = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(renderer)
    bars = [p for p in ax.patches if p.get_width() > 0]
    assert len(bars) == 4
    for bar in bars:
        assert not _boxes_overlap(legend, bar.get_window_extent(renderer))
    dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert len(dashed) == (1 if published else 0)
    assert ("published" in ax.get_xlabel()) is bool(published)
    if published:  # the dashed line at the published 83.2 %, named in the legend
        assert list(dashed[0].get_xdata()) == [83.2, 83.2]
        assert "published" in [t.get_text() for t in ax.get_legend().get_texts()]
