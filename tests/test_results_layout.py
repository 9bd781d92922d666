"""Results folders of the first layout (no schema version: label columns ``true`` / ``predicted``,
per-task and pooled confusion rows in one ``confusion.parquet`` told apart by ``scope``) are read in
today's layout and upgraded by a rerun; a newer layout is refused with both versions."""

from __future__ import annotations

import json

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.errors import TouchbenchError
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.results import load_results
from touchbench.results.store import ResultStore, read_results_table, write_results_table


def _write_old(df: pd.DataFrame, path) -> None:
    """A table as the first layout wrote it: plain Parquet, no schema version."""
    pq.write_table(pa.Table.from_pandas(df, preserve_index=False), path)


# Two tasks of one configuration: t1 (fold f1) saw pat->pat twice, pat->rub once; t2 (fold f2)
# pat->pat once, rub->rub three times. Pooled by hand: pat->pat 3, pat->rub 1, rub->rub 3.
_TASK_ROWS = [("t1", "f1", "pat", "pat", 2), ("t1", "f1", "pat", "rub", 1),
              ("t2", "f2", "pat", "pat", 1), ("t2", "f2", "rub", "rub", 3)]
_POOLED_ROWS = [("pat", "pat", 3), ("pat", "rub", 1), ("rub", "rub", 3)]


def _old_confusion() -> pd.DataFrame:
    rows = [{"run_id": "r", "scope": "task", "task_id": t, "fold": f, "features": "msd", "classifier": "rf",
             "early_frames": float("nan"), "true": a, "predicted": b, "count": n} for t, f, a, b, n in _TASK_ROWS]
    rows += [{"run_id": "r", "scope": "pooled", "task_id": "", "fold": "", "features": "msd", "classifier": "rf",
              "early_frames": float("nan"), "true": a, "predicted": b, "count": n} for a, b, n in _POOLED_ROWS]
    return pd.DataFrame(rows)


def test_a_confusion_file_of_the_first_layout_gives_both_tables(tmp_path):
    _write_old(_old_confusion(), tmp_path / "confusion.parquet")
    store = ResultStore(tmp_path)
    per_task = store.read_confusion()
    assert "scope" not in per_task and per_task["count"].sum() == 7  # each capture once, not twice
    assert list(per_task[["task_id", "true_label", "predicted_label", "count"]].itertuples(index=False, name=None)) == [
        (t, a, b, n) for t, _, a, b, n in _TASK_ROWS]
    pooled = store.read_confusion(pooled=True)
    assert not {"scope", "task_id", "fold"} & set(pooled.columns)
    assert list(pooled[["true_label", "predicted_label", "count"]].itertuples(index=False, name=None)) == _POOLED_ROWS
    # columns chosen by today's names from a file of the first layout
    got = read_results_table(tmp_path / "confusion.parquet", columns=["task_id", "true_label", "count"])
    assert got.columns.tolist() == ["task_id", "true_label", "count"] and got["count"].tolist() == [2, 1, 1, 3]


def _run(tmp_path):
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=5).to_parquet(data)
    p = parse_protocol(f"name: old\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                       "classifiers: [test-logreg]\nseed: 3\n", tmp_path / "old.yaml")
    return p, run_protocol(p, out=tmp_path / "out", progress=False)


def test_a_rerun_upgrades_a_folder_of_the_first_layout(engine_env, tmp_path):
    p, first = _run(tmp_path)
    out = tmp_path / "out"
    preds = pd.read_parquet(out / "predictions.parquet")
    pooled = pd.read_parquet(out / "confusion_pooled.parquet")
    old_names = {"true_label": "true", "predicted_label": "predicted"}
    # the whole folder as the first layout left it: fragments, merged files and manifest
    for f in (out / "fragments").glob("*.parquet"):
        _write_old(pd.read_parquet(f).rename(columns=old_names), f)
    for f in (out / "fragments").glob("*.sha256"):  # that layout recorded no fragment checksums
        f.unlink()
    _write_old(preds.rename(columns=old_names), out / "predictions.parquet")
    _write_old(pd.read_parquet(out / "scores.parquet"), out / "scores.parquet")
    conf = pd.read_parquet(out / "confusion.parquet").rename(columns=old_names)
    conf.insert(1, "scope", "task")
    old_pooled = pooled.rename(columns=old_names).assign(scope="pooled", task_id="", fold="")
    _write_old(pd.concat([conf, old_pooled[conf.columns]], ignore_index=True), out / "confusion.parquet")
    (out / "confusion_pooled.parquet").unlink()
    manifest = json.loads((out / "manifest.json").read_text())
    del manifest["results_schema"]
    manifest["tasks"]["merged_files"] = ResultStore(out).merged_checksums()
    (out / "manifest.json").write_text(json.dumps(manifest))

    rs = load_results([out])  # read as it is
    assert rs.predictions["true_label"].tolist() == preds["true_label"].tolist()
    assert ResultStore(out).read_confusion(pooled=True)["count"].sum() == len(preds)

    again = run_protocol(p, out=out, progress=False)  # upgraded from the fragments, nothing refitted
    assert again.n_ran == 0 and any("layout of results schema 1" in n for n in again.notes)
    pd.testing.assert_frame_equal(pd.read_parquet(out / "predictions.parquet"), preds)
    pd.testing.assert_frame_equal(pd.read_parquet(out / "confusion_pooled.parquet"), pooled)
    assert "scope" not in pd.read_parquet(out / "confusion.parquet")
    assert json.loads((out / "manifest.json").read_text())["results_schema"] == 3
    for f in out.glob("*.parquet"):  # the merged files (fragments stay as written: readers upgrade them)
        assert pq.read_schema(f).metadata[b"touchbench_results_schema"] == b"3", f


def test_a_manifest_of_a_newer_layout_is_refused(engine_env, tmp_path):
    p, _ = _run(tmp_path)
    out = tmp_path / "out"
    manifest = json.loads((out / "manifest.json").read_text())
    (out / "manifest.json").write_text(json.dumps({**manifest, "results_schema": 4}))
    msg = r"manifest.json: written by a newer touchbench \(results schema 4; this version reads up to 3\)"
    with pytest.raises(TouchbenchError, match=msg):
        load_results([out])
    with pytest.raises(TouchbenchError, match=msg):  # a run never rewrites a newer layout
        run_protocol(p, out=out, progress=False)


# ------------------------------------------------------------------ files edited after the run

CHANGED_SCORES = "scores.parquet changed since the run wrote it (its SHA-256 is not the one manifest.json records)"


def test_scores_edited_after_the_run_are_shown_with_a_warning_and_a_note(engine_env, tmp_path):
    _, first = _run(tmp_path)
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["leaderboard", str(out), "--format", "md"])
    assert r.exit_code == 0 and "changed since" not in r.output  # as the run wrote it: nothing to say
    scores = read_results_table(out / "scores.parquet")
    assert (scores["accuracy"] != 0.25).all()  # the run did not score 25 %; the edit below says it did
    write_results_table(out / "scores.parquet", scores.assign(accuracy=0.25))
    r = CliRunner().invoke(cli, ["leaderboard", str(out), "--format", "md"])
    assert r.exit_code == 0, r.output
    assert r.stderr.count(f"warning: {out}: {CHANGED_SCORES}") == 1
    assert f"Note: {out}: {CHANGED_SCORES}: the tables show these results as they are now" in r.stdout
    assert "| 25.0" in r.stdout  # still shown, as it is now, beside the note
    rows = json.loads(CliRunner().invoke(cli, ["leaderboard", str(out), "--json"]).stdout)["tables"][0]
    assert any(n.startswith(f"{out}: {CHANGED_SCORES}") for n in rows["notes"])


def test_predictions_edited_or_deleted_after_the_run_are_named(engine_env, tmp_path, touchbench_warnings):
    _run(tmp_path)
    out = tmp_path / "out"
    preds = read_results_table(out / "predictions.parquet")
    # the first capture's prediction changed to another class: the predictions no longer match the scores
    other = sorted(set(preds["true_label"]) - {preds.loc[0, "predicted_label"]})[0]
    preds.loc[0, ["predicted_label", "correct"]] = [other, other == preds.loc[0, "true_label"]]
    write_results_table(out / "predictions.parquet", preds)
    notes = build_leaderboards(load_results([out]))[0].notes
    changed = [n for n in notes if "changed since the run wrote it" in n]
    assert len(changed) == 1 and changed[0].startswith(f"{out}: predictions.parquet changed since the run wrote it")
    assert changed[0] in touchbench_warnings.text
    (out / "predictions.parquet").unlink()
    notes = build_leaderboards(load_results([out]))[0].notes
    assert f"{out}: predictions.parquet, which the run wrote, is missing: the tables show these results as they " \
           "are now, which may not be what the run measured" in notes


def test_a_folder_without_recorded_checksums_or_read_from_its_fragments_is_not_flagged(engine_env, tmp_path,
                                                                                     touchbench_warnings):
    _run(tmp_path)
    out = tmp_path / "out"
    manifest = json.loads((out / "manifest.json").read_text())
    # an interrupted run: its tasks' fragments, no merged files (an old checksum record left in the manifest)
    for name in ("scores.parquet", "predictions.parquet", "confusion.parquet", "confusion_pooled.parquet"):
        (out / name).unlink()
    assert build_leaderboards(load_results([out]))[0].rows["accuracy"].notna().all()
    assert "changed since" not in touchbench_warnings.text and "missing" not in touchbench_warnings.text
