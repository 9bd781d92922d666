"""The ledger of test-set looks counts every run that scored a test set once, in any results folder
of a results root: a run in a deeper folder (an audit's, a paper profile's) is not lost, and the
session that resumes an interrupted run is the same run. Ledgers that earlier versions kept per
folder of results folders are still counted, then merged into the root's without losing a line."""

from __future__ import annotations

import json
import multiprocessing as mp
from pathlib import Path

import pytest
from click.testing import CliRunner
from helpers import SUBPROCESS_HANG_S

from touchbench.cli import exitcodes
from touchbench.cli.main import cli
from touchbench.core.errors import WriteError
from touchbench.core.paths import results_root
from touchbench.engine import run_protocol, runner
from touchbench.engine.testing import random_dataset
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.results import load_results
from touchbench.results.ledger import (RUN_FILE, Looks, check_final, looks, merge_ledgers, old_ledgers, read_ledger,
                                       record_look)


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _protocol(tmp_path: Path) -> Path:
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2).to_parquet(data)
    p = tmp_path / "p.yaml"
    p.write_text(f"name: p\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    return p


def _looks_of(folder: Path) -> Looks:
    return build_leaderboards(load_results([folder]))[0].looks


def test_the_results_root_is_the_nearest_results_folder_above(tmp_path):
    assert results_root(tmp_path / "results" / "audit" / "p" / "honest") == tmp_path / "results"
    assert results_root(tmp_path / "results" / "p") == tmp_path / "results"
    assert results_root(tmp_path / "elsewhere" / "p") is None


def test_one_protocol_in_two_folders_of_one_root_is_two_looks(tmp_path):
    p = _protocol(tmp_path)
    root = tmp_path / "results"
    # as `run` and `audit` place them: results/p and results/audit/p/honest
    run_protocol(p, out=root / "p", progress=False)
    run_protocol(p, out=root / "audit" / "p" / "honest", progress=False)
    assert len(read_ledger(root / "ledger.jsonl")) == 2
    assert not (root / "audit" / "p" / "ledger.jsonl").exists()
    for folder in (root / "p", root / "audit" / "p" / "honest"):
        lb = build_leaderboards(load_results([folder]))[0]
        assert (lb.looks.runs, lb.looks.methods) == (2, 1)
        assert any("scored by 2 run(s), 1 method(s)" in n for n in lb.notes)


def test_a_run_of_some_methods_counts_only_the_methods_it_scored(tmp_path):
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2).to_parquet(data)
    p = tmp_path / "p.yaml"
    p.write_text(f"name: p\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                 "classifiers: [test-logreg, test-forest]\n")
    out = tmp_path / "results" / "p"
    run_protocol(p, out=out, progress=False, methods=["test-logreg"])
    assert _looks_of(out) == Looks(runs=1, methods=1, finals=0)  # the other planned method was not scored
    run_protocol(p, out=out, progress=False, methods=["test-forest"])
    assert _looks_of(out) == Looks(runs=2, methods=2, finals=0)


class _Interrupted(BaseException):
    """What Ctrl-C (or a kill) does to a run: it stops between two tasks."""


def test_an_interrupted_run_and_its_resume_are_one_look(tmp_path, monkeypatch):
    p = _protocol(tmp_path)
    out = tmp_path / "results" / "p"
    real, calls = runner.execute_task, []

    def stop_at_the_second_task(task, ctx):
        calls.append(task.task_id)
        if len(calls) == 2:
            raise _Interrupted
        return real(task, ctx)

    monkeypatch.setattr(runner, "execute_task", stop_at_the_second_task)
    with pytest.raises(_Interrupted):
        run_protocol(p, out=out, progress=False)
    assert (out / RUN_FILE).is_file()  # the run is under way
    monkeypatch.setattr(runner, "execute_task", real)
    res = run_protocol(p, out=out, progress=False)  # the resume: the 2 tasks left of 3 folds
    assert (res.n_ran, res.n_skipped) == (2, 1)
    entries = read_ledger(tmp_path / "results" / "ledger.jsonl")
    assert [e["resumed"] for e in entries] == [False, True] and entries[0]["look"] == entries[1]["look"]
    assert _looks_of(out).runs == 1
    assert not (out / RUN_FILE).exists()  # the run ended
    run_protocol(p, out=out, progress=False, force=True)  # a new run on the same test set
    assert _looks_of(out).runs == 2


def _old_entry(test_set: str, method: str) -> dict:
    """A line as earlier versions wrote it: no look id."""
    return {"time": "2024-01-01T00:00:00+00:00", "protocol": "old", "evaluation": None, "test_set": test_set,
            "run_id": "r0", "methods": [method], "tasks": 3, "final": False, "forced": False}


def test_a_ledger_of_an_earlier_version_is_counted_then_merged(tmp_path):
    p = _protocol(tmp_path)
    root = tmp_path / "results"
    run_protocol(p, out=root / "p", progress=False)
    test_set = read_ledger(root / "ledger.jsonl")[0]["test_set"]
    old = root / "audit" / "p" / "ledger.jsonl"  # where an audit's run recorded its look
    old.parent.mkdir(parents=True)
    old.write_text(json.dumps(_old_entry(test_set, "old / clf")) + "\n")
    assert old_ledgers(root) == [old]
    assert _looks_of(root / "p") == Looks(runs=2, methods=2, finals=0)  # read where it is
    run_protocol(p, out=root / "p", progress=False, force=True)  # a run merges it into the root's
    assert not old.exists() and read_ledger(old.with_name("ledger.jsonl.merged")) == [_old_entry(test_set, "old / clf")]
    assert old_ledgers(root) == []
    assert len(read_ledger(root / "ledger.jsonl")) == 3
    assert _looks_of(root / "p") == Looks(runs=3, methods=2, finals=0)


def _merge_and_record(root: str, old: str, who: int) -> None:
    for i in range(20):
        merge_ledgers(Path(root) / "ledger.jsonl", [old])
        record_look(Path(root) / "ledger.jsonl", {"test_set": "t", "look": f"w{who}-{i}", "methods": ["m"]})


def test_concurrent_runs_merge_an_old_ledger_once_and_lose_no_look(tmp_path):
    root = tmp_path / "results"
    old = root / "papers" / "quick" / "ledger.jsonl"
    old.parent.mkdir(parents=True)
    old.write_text("".join(json.dumps(_old_entry("t", f"m{i}")) + "\n" for i in range(5)))
    ctx = mp.get_context("fork")
    procs = [ctx.Process(target=_merge_and_record, args=(str(root), str(old), w)) for w in range(2)]
    for proc in procs:
        proc.start()
    for proc in procs:
        proc.join(SUBPROCESS_HANG_S)
        assert proc.exitcode == 0
    entries = read_ledger(root / "ledger.jsonl")
    assert len(entries) == 5 + 40
    assert looks(root / "ledger.jsonl", "t") == Looks(runs=45, methods=6, finals=0)


# ------------------------------------------------------------------ a ledger that cannot be written

def test_a_ledger_that_is_a_folder_stops_the_run_with_one_clear_error(tmp_path):
    p = _protocol(tmp_path)
    ledger = tmp_path / "results" / "ledger.jsonl"
    ledger.mkdir(parents=True)
    out = tmp_path / "results" / "p"
    r = CliRunner().invoke(cli, ["run", str(p), "--out", str(out), "--no-progress"])
    assert r.exit_code == exitcodes.DATA, r.output
    assert r.output.strip().splitlines()[-1] == (
        f"error: {ledger}: cannot write the ledger of test-set looks: it is a folder, not a file "
        "(rename or remove that folder)")
    assert "Traceback" not in r.output and "TypeError" not in r.output
    assert not (out / "scores.parquet").exists() and not list(out.glob("fragments/*"))  # no task ran


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (a device that is always full)")
def test_a_full_disk_under_the_ledger_is_one_clear_error(tmp_path):
    ledger = tmp_path / "ledger.jsonl"
    ledger.symlink_to("/dev/full")  # every write to it fails with ENOSPC, as on a full disk
    with pytest.raises(WriteError) as e:
        record_look(ledger, {"test_set": "t", "methods": ["m"]})
    assert str(e.value) == (f"{ledger}: cannot write the ledger of test-set looks: no space left on the device "
                            "(free some space and run again; finished work is kept)")


def test_a_merged_ledger_that_cannot_be_renamed_is_one_clear_error_and_loses_nothing(tmp_path):
    root = tmp_path / "results"
    old = root / "audit" / "p" / "ledger.jsonl"
    old.parent.mkdir(parents=True)
    old.write_text(json.dumps(_old_entry("t", "m")) + "\n")
    (old.parent / "ledger.jsonl.merged" / "x").mkdir(parents=True)  # a folder where the rename goes
    with pytest.raises(WriteError) as e:
        merge_ledgers(root / "ledger.jsonl", [old])
    assert str(e.value) == (f"{old}: merged into {root / 'ledger.jsonl'}, but cannot be renamed ledger.jsonl.merged: "
                            "it is a folder, not a file (rename or remove that folder)")
    assert read_ledger(root / "ledger.jsonl") == read_ledger(old) == [_old_entry("t", "m")]


# ------------------------------------------------------------------ lines of the wrong type

ILL_TYPED = [  # (the line, the field named in the warning)
    ({"test_set": "t", "methods": 5, "final": False}, "methods is 5, not a list of strings"),
    ({"test_set": "t", "methods": "abcdef", "final": False}, 'methods is "abcdef", not a list of strings'),
    ({"test_set": "t", "methods": ["m1", 7], "final": False}, 'methods is ["m1", 7], not a list of strings'),
    ({"test_set": "t", "methods": ["m1"], "final": "false"}, 'final is "false", not true or false'),
    ({"test_set": "t", "methods": ["m1"], "evaluation": 3, "final": True}, "evaluation is 3, not a string or null"),
    ({"test_set": "t", "methods": ["m1"], "look": ["a"]}, 'look is ["a"], not a string'),
    ({"test_set": "t", "methods": ["m1"], "tasks": True}, "tasks is true, not a whole number >= 0"),
    ({"test_set": 12, "methods": ["m1"]}, "test_set is 12, not a string"),
    ([1, 2], "not an entry of the ledger"),
]


def test_lines_of_the_wrong_type_are_skipped_with_a_warning_naming_the_line(tmp_path, touchbench_warnings):
    ledger = tmp_path / "ledger.jsonl"
    good = {"test_set": "t", "look": "a", "methods": ["m1"], "final": False, "evaluation": None, "tasks": 3}
    ledger.write_text("\n".join([json.dumps(good)] + [json.dumps(line) for line, _ in ILL_TYPED]
                                + ['{"test_set": "t", "meth']) + "\n")
    assert read_ledger(ledger) == [good]
    # one run (look a), one method: neither 5, nor the letters of "abcdef", nor 7 are methods, "false" is no final
    assert looks(ledger, "t") == Looks(runs=1, methods=1, finals=0)
    assert check_final(ledger, "t", ["another"]) == []  # no final run before: "final": "false" is not one
    text = touchbench_warnings.text
    for n, (_, why) in enumerate(ILL_TYPED, 2):
        assert f"{ledger}:{n}: a line of the ledger of test-set looks was skipped: " in text
        assert why in text
    assert f"{ledger}:{len(ILL_TYPED) + 2}: a line of the ledger of test-set looks was skipped: not a complete JSON line" in text
    assert f"{ledger}:1:" not in text
    touchbench_warnings.clear()
    read_ledger(ledger)
    assert touchbench_warnings.text == ""  # said once per process


def test_the_leaderboard_skips_an_ill_typed_line_of_the_ledger(tmp_path, touchbench_warnings):
    p = _protocol(tmp_path)
    out = tmp_path / "results" / "p"
    run_protocol(p, out=out, progress=False)
    ledger = tmp_path / "results" / "ledger.jsonl"
    test_set = read_ledger(ledger)[0]["test_set"]
    with ledger.open("a") as f:  # a line edited by hand: five methods written as a number, a final run as a string
        f.write(json.dumps({"test_set": test_set, "look": "x", "methods": 5, "final": "true"}) + "\n")
    assert _looks_of(out) == Looks(runs=1, methods=1, finals=0)
    assert f"{ledger}:2: a line of the ledger of test-set looks was skipped: its methods is 5" in touchbench_warnings.text
