"""A task's fragments become a table only as their task wrote them: a real (small) engine run, then its
folder tampered with: an edited scores fragment is refused by the reports (naming it) and computed
again by ``run``; scores that disagree with their predictions are refused; a folder without its
manifest is said to be unverifiable."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.results import load_results
from touchbench.results.fragments import FragmentError
from touchbench.results.store import read_results_table, write_results_table


def _run(tmp_path):
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=5).to_parquet(data)
    p = parse_protocol(f"name: frag\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                       "classifiers: [test-logreg]\nseed: 3\n", tmp_path / "frag.yaml")
    return p, run_protocol(p, out=tmp_path / "out", progress=False)


def _edit(fragment) -> float:
    """Set the scores fragment's accuracy to another value (1 or, when it is 1 already, 0); its former value."""
    df = read_results_table(fragment)
    before = float(df["accuracy"].iloc[0])
    df["accuracy"] = 0.0 if before == 1.0 else 1.0
    write_results_table(fragment, df)
    return before


def _first(out):
    return sorted((out / "fragments").glob("*.scores.parquet"))[0]


def test_each_finished_task_records_its_fragments_checksums(engine_env, tmp_path):
    _, res = _run(tmp_path)
    sums = sorted((tmp_path / "out" / "fragments").glob("*.sha256"))
    assert len(sums) == res.n_tasks == 3
    import hashlib
    for s in sums:
        tid = s.name[: -len(".sha256")]
        record = json.loads(s.read_text())
        for kind in ("scores", "predictions"):
            data = (s.parent / f"{tid}.{kind}.parquet").read_bytes()
            assert record[kind] == hashlib.sha256(data).hexdigest()


def test_an_edited_fragment_is_refused_by_the_reports_and_computed_again_by_run(engine_env, tmp_path):
    p, first = _run(tmp_path)
    out = tmp_path / "out"
    frag = _first(out)
    before = _edit(frag)
    (out / "scores.parquet").unlink()  # the reports now rebuild the table from the fragments
    with pytest.raises(FragmentError) as e:
        load_results([out])
    assert frag.name in str(e.value) and "does not match the checksum" in str(e.value)

    again = run_protocol(p, out=out, progress=False)
    assert again.n_ran == 1  # that task computed anew, never trusted
    assert any(frag.name in n and "were not used" in n for n in again.notes)
    tid = frag.name[: -len(".scores.parquet")]
    assert again.scores.set_index("task_id").loc[tid, "accuracy"] == before
    pd.testing.assert_frame_equal(again.scores[["task_id", "accuracy"]], first.scores[["task_id", "accuracy"]])


def test_scores_that_disagree_with_their_predictions_are_refused(engine_env, tmp_path):
    p, _ = _run(tmp_path)
    out = tmp_path / "out"
    frag = _first(out)
    _edit(frag)
    for s in (out / "fragments").glob("*.sha256"):  # as results of a version that wrote no checksums
        s.unlink()
    (out / "scores.parquet").unlink()  # the run merges again from the fragments: it refuses that one
    with pytest.raises(FragmentError) as e:
        run_protocol(p, out=out, progress=False)
    assert str(frag) in str(e.value) and "is not that of its predictions" in str(e.value)
    with pytest.raises(FragmentError, match="is not that of its predictions"):
        load_results([out])


def test_a_folder_without_its_manifest_is_said_to_be_unverifiable(engine_env, tmp_path):
    _run(tmp_path)
    out = tmp_path / "out"
    (out / "manifest.json").unlink()
    rs = load_results([out])
    [lb] = build_leaderboards(rs)
    assert any("manifest.json is missing" in n and "cannot be verified" in n for n in lb.notes)
