"""The terminal leaderboard at narrow widths: method names fitted so that each row stays told apart
(expected strings worked out by hand), and the Pareto mark shown with the time it is on."""

from __future__ import annotations

import math

import pandas as pd
import pytest
from rich.console import Console

from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import (
    _terminal_table,
    display_rows,
    legend,
    print_terminal,
    terminal_priority,
)
from touchbench.reports.results import load_results
from touchbench.reports.short_labels import fit_labels, reads_as, shared_affixes
from touchbench.reports.testing import FakeMethod, write_fake_run

SUBJECTS = [f"s{i}" for i in range(1, 7)]
CAPS = pd.DataFrame([(f"{s}-{g}-{r}", s, g) for s in SUBJECTS for g in ("pat", "rub", "stroke") for r in range(2)],
                    columns=["capture_id", "subject", "gesture"])
FOLDS = {f"subject={s}": CAPS[CAPS["subject"] == s]["capture_id"].tolist() for s in SUBJECTS}
TREES = "touch-rhythm+contact-motion / extra-trees"
HIST = "touch-rhythm+contact-motion / hist-gb"


def _wrong(counts):
    return {f: ids[:c] for (f, ids), c in zip(FOLDS.items(), counts)}


# ----------------------------------------------------------------- labels alone
def test_the_shared_start_and_end_are_cut_at_a_separator():
    assert shared_affixes([TREES, HIST]) == ("touch-rhythm+contact-motion / ", "")
    end = " with the paper's settings"
    assert shared_affixes([f"a / {x}{end}" for x in ("extra-trees", "hist-gb")]) == ("a / ", end)
    # "sd" and "sd+msd" share "sd", which is no whole word: only the end " / gaus-rf" goes
    assert shared_affixes(["sd / gaus-rf", "sd+msd / gaus-rf"]) == ("", " / gaus-rf")
    # one label is the whole shared start "touch-et": the start goes up to its last separator
    assert shared_affixes(["touch-et", "touch-et-win"]) == ("touch-", "")
    assert shared_affixes(["same", "same"]) == ("", "")  # one label: nothing shared with another


def test_labels_that_fit_are_shown_whole():
    fitted = fit_labels([TREES, HIST], 41)
    assert fitted.shown == [TREES, HIST] and fitted.heading() is None and fitted.legend() is None


def test_the_shared_start_goes_first_and_is_said_once():
    fitted = fit_labels([TREES, HIST, TREES], 12)
    assert fitted.shown == ["extra-trees", "hist-gb", "extra-trees"]
    assert fitted.heading() == "Method names below leave out the start “touch-rhythm+contact-motion / ” that all share."
    assert fitted.legend() is None
    # narrower than "extra-trees" (11): its first 4 and last 3 characters around "…"; "hist-gb" (7) fits
    assert fit_labels([TREES, HIST], 8).shown == ["extr…ees", "hist-gb"]


def test_a_shortening_that_another_label_reads_as_is_not_taken():
    labels = ["p1 / middle-part / q1", "p1 / middle-part / q2", "p2 / middle-part / q1"]
    # 6 cells: "p1 " and "q1" around "…" tell the first from the others
    assert fit_labels(labels, 6).shown == ["p1 …q1", "p1 …q2", "p2 …q1"]
    # 4 cells: the start "p1" and the last character
    assert fit_labels(labels, 4).shown == ["p1…1", "p1…2", "p2…1"]


def test_labels_no_shortening_tells_apart_are_numbered_and_only_they_are_listed():
    labels = ["p1 / middle-part / q1", "p1 / middle-part / q2", "zz", "p2 / middle-part / q1"]
    # 3 cells: p1/q1's "p…1" reads as p2/q1 too, "p1…" as p1/q2, "…q1" as p2/q1: numbered; p1/q2 is
    # the only label ending in "2" ("p…2"), p2/q1 the only one starting "p2" ("p2…")
    fitted = fit_labels(labels, 3)
    assert fitted.shown == ["[1]", "p…2", "zz", "p2…"]
    assert fitted.legend() == "Numbered: [1] p1 / middle-part / q1."


def test_reads_as():
    assert reads_as("sd…rf", "sd / gaus-rf") and reads_as("sd…rf", "sd+msd / gaus-rf")
    assert not reads_as("sd…d", "sd")  # "sd" and "d" need three characters
    assert reads_as("…a…", "xay") and not reads_as("…a…b", "xbay")
    assert reads_as("abc", "abc") and not reads_as("abc", "abcd")


# ----------------------------------------------------------------- in the terminal
def _table_rows(text: str) -> list[list[str]]:
    """The cells of each table line that starts a row (its rank filled)."""
    rows = [[x.strip() for x in line.strip("│").split("│")] for line in text.splitlines() if line.startswith("│")]
    return [r for r in rows if r[0]]


def test_at_80_columns_a_long_shared_start_goes_and_no_legend_is_printed(tmp_path):
    write_fake_run(tmp_path / "r", CAPS, FOLDS, [
        FakeMethod("touch-rhythm+contact-motion", "extra-trees", wrong=_wrong([0, 1, 0, 1, 0, 0])),
        FakeMethod("touch-rhythm+contact-motion", "hist-gb", wrong=_wrong([1, 2, 1, 2, 1, 1])),
    ])
    console = Console(record=True, width=80)
    print_terminal(build_leaderboards(load_results([tmp_path / "r"])), console)
    text = console.export_text()
    assert [r[1] for r in _table_rows(text)] == ["extra-trees", "hist-gb"]
    before_table = text.split("┏")[0]
    assert "leave out the start “touch-rhythm+contact-motion / ”" in " ".join(before_table.split())
    assert "Numbered" not in text
    assert max(len(x) for x in text.splitlines()) <= 80


FEATURES = ["touch-rhythm", "cell-rhythm", "contact-motion", "touch-windows", "contact-evidence"]
ESTIMATORS = ["extra-trees", "hist-gb", "gaus-rf", "zhou-lda", "svm-rbf", "knn-5", "logreg", "xgb", "lgbm", "mlp"]


@pytest.fixture(scope="module")
def board_of_200(tmp_path_factory):
    """200 methods, 20 feature combinations by 10 estimators: a two-method table's rows repeated
    with each method's names (building 200 methods' tests would take a minute, and the names are
    all that is looked at here)."""
    feats = [f"{a}+{b}" for i, a in enumerate(FEATURES) for b in FEATURES[i + 1:]] + FEATURES
    feats += [f"{FEATURES[0]}+{FEATURES[1]}+{x}" for x in FEATURES[2:]] + ["cell-rhythm+contact-motion+touch-windows",
                                                                            "touch-rhythm+contact-evidence+touch-windows"]
    assert len(set(feats)) == 20
    out = tmp_path_factory.mktemp("board") / "r"
    write_fake_run(out, CAPS, FOLDS, [FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1, 0, 0])),
                                      FakeMethod("sd", "rf", wrong=_wrong([1, 2, 1, 2, 1, 1]))])
    [lb] = build_leaderboards(load_results([out]))
    second = lb.rows.iloc[[1]]
    rows = pd.concat([lb.rows.iloc[[0]]] + [second] * 199, ignore_index=True)
    rows["features"] = [f for f in feats for _ in ESTIMATORS]
    rows["classifier"] = rows["classifier_name"] = ESTIMATORS * 20
    rows["method_id"] = [f"m{i}" for i in range(200)]
    rows["rank"] = [1] + [2] * 199
    lb.rows = rows
    return lb


@pytest.mark.parametrize("width", [20, 40, 80])
def test_200_methods_at_a_narrow_terminal_keep_every_label_distinct(board_of_200, width):
    lb = board_of_200
    full = [c[1] for c in display_rows(lb)[1]]
    assert len(set(full)) == 200 and full[0] == "touch-rhythm+cell-rhythm / extra-trees"
    _, _, ((what, names), *_) = _terminal_table(lb, width)
    assert what == "method names"
    assert len(set(names.shown)) == 200
    for s, f in zip(names.shown, full):
        if s.startswith("["):  # numbered: the legend names it in full
            assert names.numbered[s.split(" ")[0]] == f
        else:  # shortened: no other label of the table reads as it, its own does
            assert reads_as(s, f) and not any(reads_as(s, g) for g in full if g != f), (s, f)
    assert len(names.numbered) == sum(s.startswith("[") for s in names.shown)  # the legend: the numbered only
    console = Console(record=True, width=width)
    print_terminal([lb], console)
    text = console.export_text()
    assert [r[1] for r in _table_rows(text)] == names.shown  # as printed, one line each
    assert ("Numbered: [1] " in text) == bool(names.numbered)


# ----------------------------------------------------------------- the Pareto mark
def _pareto_run(tmp_path, cpu=True):
    """A most accurate (CPU 5 ms, wall 1 ms), B (CPU 1, wall 9), C least accurate (CPU 2, wall 0.5):
    on CPU time the front is A and B (C is slower than B and less accurate); on wall time A and C."""
    nan = math.nan
    write_fake_run(tmp_path / "r", CAPS, FOLDS, [
        FakeMethod("msd", "rf", wrong=_wrong([0, 1, 0, 1, 0, 0]), latency_ms=1.0, latency_cpu_ms=5.0 if cpu else nan),
        FakeMethod("sd", "rf", wrong=_wrong([1, 2, 1, 2, 1, 1]), latency_ms=9.0, latency_cpu_ms=1.0 if cpu else nan),
        FakeMethod("bmh", "rf", wrong=_wrong([2, 1, 3, 2, 0, 1]), latency_ms=0.5, latency_cpu_ms=2.0 if cpu else nan),
    ])
    [lb] = build_leaderboards(load_results([tmp_path / "r"]))
    return lb


def test_the_pareto_mark_is_shown_beside_the_cpu_column_it_is_on(tmp_path):
    lb = _pareto_run(tmp_path)
    assert lb.pareto_costs == ["latency_cpu_ms"]
    header, cells = display_rows(lb)
    cpu, mark = header.index("CPU ms"), header.index("Pareto")
    assert {c[1]: (c[cpu], c[mark]) for c in cells} == {
        "msd / rf": ("5.00", "★"), "sd / rf": ("1.00", "★"), "bmh / rf": ("2.00", "")}
    for width in range(60, 260, 5):  # wherever the mark is shown, so is the time it is on
        _, shown, _ = _terminal_table(lb, width)
        assert "Pareto" not in shown or "CPU ms" in shown, (width, shown)
    console = Console(record=True, width=250)
    print_terminal([lb], console)
    text = console.export_text()
    words = " ".join(text.split())
    assert "★ = on the Pareto front of accuracy against the CPU time of labelling one capture (the CPU ms column)." in words
    rows = {r[1]: r for r in _table_rows(text)}
    assert "5.00" in rows["msd / rf"] and "★" in rows["msd / rf"] and "★" not in rows["bmh / rf"]


def test_a_pareto_mark_without_its_column_says_which_cost_it_is_on(tmp_path):
    lb = _pareto_run(tmp_path)
    text = legend(lb, ["#", "method", "accuracy % (±sd)", "Pareto"])
    assert "★ = Pareto: accuracy vs CPU ms per capture (column hidden at this width)." in text
    assert "★" not in legend(lb, ["#", "method", "accuracy % (±sd)"])  # no mark shown: no sentence


def test_results_without_cpu_time_mark_the_front_on_the_latency_column(tmp_path):
    lb = _pareto_run(tmp_path, cpu=False)
    assert lb.pareto_costs == ["latency_ms"]
    header, cells = display_rows(lb)
    assert "CPU ms" not in header  # no method has a CPU time: no column of dashes
    mark = header.index("Pareto")
    assert {c[1]: c[mark] for c in cells} == {"msd / rf": "★", "sd / rf": "", "bmh / rf": "★"}
    priority = terminal_priority(lb)
    assert priority.index("latency ms") == priority.index("Pareto") - 1
    assert "against the wall-clock time of labelling one capture (the latency ms column)" in legend(lb)
