"""The results folder's interface to a run (results/session.py): one question, finished tasks handed over."""

from __future__ import annotations

import pandas as pd
import pytest

from touchbench.results.ledger import read_ledger
from touchbench.results.locking import ResultsBusyError
from touchbench.results.session import open_results

IDS = ["t0", "t1", "t2", "t3"]


def _open(folder, **kw):
    return open_results(folder, protocol="p", evaluation=None, run_id="run-1", ids_hash="h", task_ids=IDS,
                        ledger=folder.parent / "ledger.jsonl", **kw)


def _ask(store, ids=IDS, **kw):
    return store.remaining(ids, test_set=lambda: "test-set", methods=["f / m"], **kw)


def _ok_task(tid: str) -> tuple[dict, pd.DataFrame]:
    """A succeeded task that labelled two test captures, one of them right."""
    row = {"task_id": tid, "status": "ok", "n_test": 2, "accuracy": 0.5}
    preds = pd.DataFrame({"task_id": [tid, tid], "capture_id": ["c1", "c2"], "true_label": ["a", "b"],
                          "predicted_label": ["a", "a"], "correct": [True, False]})
    return row, preds


def _failed_task(tid: str) -> tuple[dict, None]:
    return {"task_id": tid, "status": "failed", "n_test": 2}, None


def test_an_empty_folder_has_every_task_to_do(tmp_path):
    with _open(tmp_path / "out") as store:
        todo = _ask(store)
    assert todo.pending == IDS and todo.damaged == {} and not todo.current


def test_the_tasks_handed_over_are_not_asked_again(tmp_path):
    out = tmp_path / "out"
    with _open(out) as store:
        _ask(store)
        store.add(*_ok_task("t1"))
        store.add(*_failed_task("t3"))
    with _open(out) as store:
        assert _ask(store).pending == ["t0", "t2"]
    with _open(out) as store:  # a failed task is asked again only when retrying failed ones
        assert _ask(store, retry_failed=True).pending == ["t0", "t2", "t3"]
    with _open(out) as store:  # the order asked is kept, and only the tasks asked about are answered
        assert _ask(store, ["t3", "t2", "t1"]).pending == ["t2"]


def test_a_fragment_edited_on_disk_is_to_do_again_and_named(tmp_path):
    out = tmp_path / "out"
    with _open(out) as store:
        _ask(store)
        store.add(*_ok_task("t0"))
        store.add(*_ok_task("t1"))
    path = out / "fragments" / "t1.predictions.parquet"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF  # one byte changed: no longer what its task wrote
    path.write_bytes(bytes(data))
    with _open(out) as store:
        todo = _ask(store)
    assert todo.pending == ["t1", "t2", "t3"]
    assert list(todo.damaged) == ["t1"] and todo.damaged["t1"]


def test_force_forgets_every_task_of_the_plan(tmp_path):
    out = tmp_path / "out"
    with _open(out) as store:
        _ask(store)
        store.add(*_failed_task("t0"))
        store.add(*_failed_task("t2"))
    with _open(out) as store:
        assert _ask(store, ["t1"], force=True).pending == ["t1"]
    assert not (out / "fragments" / "t0.scores.parquet").exists()
    assert not (out / "fragments" / "t2.scores.parquet").exists()


def test_a_second_open_while_the_folder_is_held_is_refused(tmp_path):
    out = tmp_path / "out"
    with _open(out):
        with pytest.raises(ResultsBusyError, match="touchbench run p"):
            with _open(out):
                pass
    with _open(out) as store:  # released when the first run leaves
        assert _ask(store).pending == IDS


def test_the_look_is_recorded_in_the_ledger_before_any_task(tmp_path):
    out = tmp_path / "out"
    with _open(out) as store:
        _ask(store, ["t0", "t1"])
        entries = read_ledger(tmp_path / "ledger.jsonl")  # before any task was handed over
    assert len(entries) == 1
    e = entries[0]
    assert (e["protocol"], e["test_set"], e["tasks"], e["methods"], e["final"], e["resumed"]) == \
        ("p", "test-set", 2, ["f / m"], False, False)
    with _open(out) as store:  # the same run resumed: the same look, marked resumed
        _ask(store, ["t0", "t1"])
    again = read_ledger(tmp_path / "ledger.jsonl")
    assert len(again) == 2 and again[1]["look"] == e["look"] and again[1]["resumed"] is True
