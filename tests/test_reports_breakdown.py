"""An evaluation's ``report:`` block: the recall of named classes and the accuracy per metadata value,
in the leaderboard (hand-worked values), and refused at its field when it names what the data lacks."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest

from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.errors import ProtocolError
from touchbench.reports.breakdown import Breakdown
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.rendering import display_rows, to_markdown
from touchbench.reports.results import load_results


def _preds(rows: list[tuple[str, str, str, str, str]]) -> pd.DataFrame:
    """(capture, true, predicted, fold, finished_at) rows of method ``m``, seed 0."""
    return pd.DataFrame([{"method_id": "m", "capture_id": c, "true_label": t, "predicted_label": p,
                          "correct": t == p, "fold_key": f, "seed": 0, "finished_at": at}
                         for c, t, p, f, at in rows])


def test_recall_and_accuracy_per_value_worked_by_hand():
    report = {"recall": ["notouch", "tickle"], "by": ["cover", "motion"],
              "rows": {"cover": {"cover": ["a", "c"], "none": ["b", "d"]},
                       "motion": {"static": ["a", "b", "c", "d"], "dynamic": ["z"]}}}
    preds = _preds([("a", "notouch", "notouch", "f1", "1"), ("b", "notouch", "notouch", "f1", "1"),
                    ("b", "notouch", "pat", "f1", "2"),  # b predicted again later: this one counts
                    ("c", "pat", "pat", "f2", "1"), ("d", "rub", "notouch", "f2", "1")])
    bd = Breakdown.of([{"report": None}, {"report": report}]).tested(preds)
    # 'dynamic' has no test capture: no column
    assert bd.columns == ["recall[notouch]", "recall[tickle]", "accuracy[cover=cover]", "accuracy[cover=none]",
                          "accuracy[motion=static]"]
    got = bd.fields(preds, "m")
    # notouch: a right, b wrong -> 1/2; cover: a, c right -> 2/2; none: b, d wrong -> 0/2; static 2/4
    assert got["recall[notouch]"] == 0.5 and math.isnan(got["recall[tickle]"])
    assert got["accuracy[cover=cover]"] == 1.0 and got["accuracy[cover=none]"] == 0.0
    assert got["accuracy[motion=static]"] == 0.5
    assert all(math.isnan(v) for v in bd.fields(preds, "other").values())
    assert Breakdown.of([{}]) is None


def _protocol(tmp_path: Path, report: str) -> Path:
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, extra={"cover": ["bare", "fur"]}).to_parquet(data)
    p = tmp_path / "p.yaml"
    p.write_text(f"name: p\ndataset: {data}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n"
                 f"evaluations:\n  - name: loso\n    scheme: loso\n    report: {report}\n")
    return p


def test_the_leaderboard_shows_the_reported_columns(engine_env, tmp_path):
    p = _protocol(tmp_path, "{recall: [pat], by: [cover]}")
    (res,) = run_protocol(p, out=tmp_path / "results", progress=False)
    preds = pd.read_parquet(res.out / "predictions.parquet")
    meta = pd.read_parquet(tmp_path / "data.parquet", columns=["capture_id", "cover"])
    preds = preds.merge(meta, on="capture_id")
    pat = preds[preds["true_label"] == "pat"]
    (lb,) = build_leaderboards(load_results([res.out]))
    assert lb.breakdown == ["recall[pat]", "accuracy[cover=bare]", "accuracy[cover=fur]"]
    row = lb.rows.iloc[0]
    assert row["recall[pat]"] == pytest.approx((pat["predicted_label"] == "pat").sum() / len(pat))
    for cover in ("bare", "fur"):
        mine = preds[preds["cover"] == cover]
        assert row[f"accuracy[cover={cover}]"] == pytest.approx(mine["correct"].sum() / len(mine))
    header, cells = display_rows(lb)
    assert header[-3:] == ["pat recall %", "cover=bare %", "cover=fur %"]
    assert cells[0][-3] == f"{100 * row['recall[pat]']:.1f}"
    assert "C recall: of the test captures of class C" in to_markdown([lb])


@pytest.mark.parametrize("report, field, message", [
    ("{by: [colour]}", "report.by[0]", "the dataset has no metadata column 'colour'"),
    ("{recall: [notouch]}", "report.recall[0]", "'notouch' is not a value of the target 'gesture'"),
])
def test_a_report_naming_what_the_data_lacks_is_refused_at_its_field(engine_env, tmp_path, report, field, message):
    p = _protocol(tmp_path, report)
    with pytest.raises(ProtocolError) as e:
        run_protocol(p, out=tmp_path / "results", progress=False)
    assert message in str(e.value) and field in str(e.value)
    assert not list((tmp_path / "results").rglob("*.scores.parquet"))  # refused before any task


def test_a_report_added_after_the_run_is_merged_in_without_rerunning(engine_env, tmp_path):
    p = _protocol(tmp_path, "{recall: [pat]}")
    p.write_text(p.read_text().replace("    report: {recall: [pat]}\n", ""))
    (first,) = run_protocol(p, out=tmp_path / "results", progress=False)
    assert build_leaderboards(load_results([first.out]))[0].breakdown == []
    p.write_text(p.read_text() + "    report: {by: [cover]}\n")
    (again,) = run_protocol(p, out=tmp_path / "results", progress=False)
    assert again.n_ran == 0
    assert build_leaderboards(load_results([again.out]))[0].breakdown == ["accuracy[cover=bare]", "accuracy[cover=fur]"]
