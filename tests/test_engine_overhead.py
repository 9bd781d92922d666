"""What the run engine does beside fit and predict keeps its results: the three scores of every task
equal scikit-learn's to the last bit without going through its scorers, the reports merged from
this session's rows in memory are those merged from the fragments, and a dataset read from the
cache is hashed once, at conversion, and trusted only while its file is the one that was hashed."""

from __future__ import annotations

import hashlib
import json
import os
import threading
import time
import warnings
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from helpers import make_dataset
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.metrics import accuracy_score, balanced_accuracy_score, f1_score

from touchbench.datasets import model as model_module
from touchbench.datasets.model import TouchDataset
from touchbench.core import hashing
from touchbench.core.errors import WriteError
from touchbench.datasets import cache as cache_module
from touchbench.datasets.cache import cached_dataset
from touchbench.engine import identity, run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.scoring import metrics as metrics_module
from touchbench.scoring.metrics import metrics
from touchbench.results import store as store_module
from touchbench.results import ledger
from touchbench.results.store import read_results_table

LABELS = st.sampled_from(["a", "b", "c", "d", "e"])


def _sklearn(y_true, y_pred) -> dict[str, float]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {"accuracy": accuracy_score(y_true, y_pred),
                "balanced_accuracy": balanced_accuracy_score(y_true, y_pred),
                "macro_f1": f1_score(y_true, y_pred, average="macro")}


@settings(max_examples=100, deadline=None)  # the degenerate cases are also checked one by one below
@given(st.lists(st.tuples(LABELS, LABELS), min_size=1, max_size=60))
def test_the_scores_are_scikit_learns_to_the_last_bit(pairs):
    y_true = np.array([t for t, _ in pairs], dtype=object)
    y_pred = np.array([p for _, p in pairs], dtype=object)
    assert metrics(y_true, y_pred) == _sklearn(y_true, y_pred)  # exact: no tolerance


@pytest.mark.parametrize("y_true, y_pred", [
    (["a", "a", "b", "b"], ["a", "a", "a", "a"]),  # a class never predicted
    (["a", "a", "a"], ["a", "b", "c"]),  # predicted classes absent from the truth
    (["a", "b", "c"], ["a", "b", "c"]),  # perfect
    (["a"], ["b"]),  # one capture, wrong
    (["x", "y", "z", "x", "y", "z", "x"], ["y", "z", "x", "x", "y", "y", "z"]),
])
def test_degenerate_predictions_score_as_scikit_learn(y_true, y_pred):
    assert metrics(np.array(y_true), np.array(y_pred)) == _sklearn(y_true, y_pred)


def test_hand_worked_scores():
    # truth a a b b, predicted a b b c: recall a 1/2, b 1/2 -> balanced 0.5;
    # F1 = 2tp / (2tp + fp + fn): a 2/3, b 2/4, c (predicted, never true) 0
    got = metrics(np.array(["a", "a", "b", "b"]), np.array(["a", "b", "b", "c"]))
    assert got["accuracy"] == 0.5
    assert got["balanced_accuracy"] == 0.5
    assert got["macro_f1"] == pytest.approx((2 / 3 + 2 / 4 + 0) / 3)


def test_the_task_scores_do_not_go_through_scikit_learns_scorers(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a scikit-learn scorer was called for the fixed scores")
    monkeypatch.setattr(metrics_module, "scorer_values", refuse, raising=False)
    import sklearn.metrics
    monkeypatch.setattr(sklearn.metrics, "get_scorer", refuse)
    assert metrics(np.array(["a", "b"]), np.array(["a", "a"]))["accuracy"] == 0.5


# ----------------------------------------------------------------- the merge
def _protocol(tmp_path: Path) -> Path:
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2).to_parquet(data)
    p = tmp_path / "p.yaml"
    p.write_text(f"name: p\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                 "classifiers: [test-logreg, test-forest, test-fail]\n")
    return p


def _count_fragment_reads(monkeypatch) -> list[str]:
    seen: list[str] = []
    real = store_module.read_results_table

    def spy(path, *args, **kwargs):
        if Path(path).parent.name == "fragments":
            seen.append(Path(path).name)
        return real(path, *args, **kwargs)
    monkeypatch.setattr(store_module, "read_results_table", spy)
    return seen


def test_the_merge_reads_only_the_fragments_of_earlier_sessions(engine_env, tmp_path, monkeypatch):
    p = _protocol(tmp_path)
    reads = _count_fragment_reads(monkeypatch)
    first = run_protocol(p, out=tmp_path / "out", progress=False, methods=["test-logreg"], jobs=1)
    assert first.n_ran == 3 and reads == []  # every task of this session merged from memory
    merged_first = read_results_table(tmp_path / "out" / "predictions.parquet")
    second = run_protocol(p, out=tmp_path / "out", progress=False, jobs=1)
    assert second.n_ran == 6 and second.n_failed == 3
    logreg = set(merged_first["task_id"])
    # the earlier session's three tasks, scores and predictions: read from their fragments
    assert sorted(reads) == sorted([f"{t}.scores.parquet" for t in logreg] + [f"{t}.predictions.parquet" for t in logreg])


def test_reports_merged_from_memory_are_those_merged_from_the_fragments(engine_env, tmp_path):
    p = _protocol(tmp_path)
    out = tmp_path / "out"
    run_protocol(p, out=out, progress=False, jobs=1)  # one session: every task merged from memory
    names = ["scores.parquet", "predictions.parquet", "confusion.parquet", "confusion_pooled.parquet"]
    from_memory = {n: (out / n).read_bytes() for n in names}
    for n in names:
        (out / n).unlink()
    again = run_protocol(p, out=out, progress=False, jobs=1)  # nothing to run: merged from the fragments
    assert again.n_ran == 0 and (again.scores["status"] == "failed").sum() == 3
    for n in names:
        assert (out / n).read_bytes() == from_memory[n], n


# ----------------------------------------------------------------- the dataset cache
def _cached(tmp_path: Path, build=None):
    src = tmp_path / "source.csv"
    if not src.exists():
        src.write_text("one source file\n")
    return cached_dataset("toy", "1", [src], build or (lambda: make_dataset(seed=3)), tmp_path / "cache")


def _by_hand(ds, column: str) -> list[str]:
    """Each capture's shape, label and float64 frames, hashed as the ledger's test-set items."""
    return [hashlib.sha256(f"{c.shape}|{y}".encode() + c.astype(np.float64).tobytes()).hexdigest()
            for c, y in zip(ds.captures, ds.meta[column].astype(str))]


def test_a_cached_dataset_is_hashed_at_conversion_and_not_again(tmp_path, monkeypatch):
    expected = make_dataset(seed=3).content_hash
    assert _cached(tmp_path).content_hash == expected

    def refuse(*args):
        raise AssertionError("the content was hashed again")
    monkeypatch.setattr(model_module, "_hash_meta", refuse)
    again = _cached(tmp_path, build=lambda: pytest.fail("rebuilt"))
    assert again.content_hash == expected


def test_a_cache_entry_that_is_not_the_file_its_record_hashed_is_hashed_again(tmp_path, monkeypatch):
    first = _cached(tmp_path)
    (entry,) = (tmp_path / "cache" / "datasets").glob("toy-*.parquet")
    record = json.loads(cache_module.record_path(entry).read_text())
    assert record["file"]["size"] == entry.stat().st_size
    record["file"]["sha256"] = "0" * 64  # same size and time, other bytes
    cache_module.record_path(entry).write_text(json.dumps(record))
    calls = []
    real = model_module._hash_meta
    monkeypatch.setattr(model_module, "_hash_meta", lambda *a: calls.append(1) or real(*a))
    assert _cached(tmp_path, build=lambda: pytest.fail("rebuilt")).content_hash == first.content_hash
    assert calls == [1]  # hashed again, and the record made anew
    assert json.loads(cache_module.record_path(entry).read_text())["file"]["sha256"] == hashlib.sha256(entry.read_bytes()).hexdigest()


def _flat(value: int) -> TouchDataset:
    """A dataset of zero frames but one value: two of them differ in one value, not in file size."""
    base = make_dataset(seed=3)
    captures = [np.zeros_like(c) for c in base.captures]
    captures[0][0, 0, 0] = value
    return TouchDataset("toy", captures, base.meta, base.sensor)


def test_a_cache_entry_replaced_with_its_size_and_time_kept_is_hashed_again(tmp_path):
    _cached(tmp_path, build=lambda: _flat(5))
    (entry,) = (tmp_path / "cache" / "datasets").glob("toy-*.parquet")
    st = entry.stat()
    other = _flat(6).to_parquet(tmp_path / "other.parquet")
    assert other.stat().st_size == st.st_size  # the same size: only the bytes tell them apart
    entry.write_bytes(other.read_bytes())
    os.utime(entry, ns=(st.st_atime_ns, st.st_mtime_ns))
    again = _cached(tmp_path, build=lambda: pytest.fail("rebuilt"))  # a whole dataset file: not damaged
    assert again.content_hash == _flat(6).content_hash != _flat(5).content_hash
    assert int(again.captures[0][0, 0, 0]) == 6


def test_the_test_set_checksums_are_kept_with_the_cache_entry(tmp_path, monkeypatch):
    first = _cached(tmp_path)
    assert first.labelled_checksums("gesture") == _by_hand(first, "gesture")
    labels = first.meta["gesture"].astype(str)
    assert ledger.test_set_hash_of(_by_hand(first, "gesture")) == ledger.test_set_hash(first.captures, labels)

    def refuse(*args):
        raise AssertionError("a capture was hashed again")
    monkeypatch.setattr(model_module, "labelled_checksum", refuse)
    again = _cached(tmp_path)
    assert again.labelled_checksums("gesture") == _by_hand(first, "gesture")
    with pytest.raises(AssertionError, match="hashed again"):
        again.labelled_checksums("subject")  # a column no run asked for yet


def test_a_source_file_not_written_since_it_was_hashed_is_not_read_again(tmp_path, monkeypatch):
    monkeypatch.setattr(hashing, "RECENT_SECONDS", 0.0)  # the files below were just written
    files = [tmp_path / "a.csv", tmp_path / "b.csv"]
    for f, text in zip(files, ("1,2,3\n", "4,5,6\n")):
        f.write_text(text)
    by_hand = hashlib.sha256(b"v1\0format2")  # the reader version, then each file's name and digest
    for f in files:
        by_hand.update(f"\0{f.parent.name}/{f.name}\0".encode() + hashlib.sha256(f.read_bytes()).digest())
    known = tmp_path / "sources.json"
    assert model_module.FORMAT_VERSION == 2
    assert cache_module.source_key("v1", files, known) == by_hand.hexdigest()[:24]
    monkeypatch.setattr(Path, "read_bytes", lambda self: pytest.fail(f"{self} read again"))
    assert cache_module.source_key("v1", files, known) == by_hand.hexdigest()[:24]


def test_a_source_file_edited_with_its_size_and_time_kept_is_hashed_again(tmp_path, monkeypatch):
    monkeypatch.setattr(hashing, "RECENT_SECONDS", 0.0)
    f = tmp_path / "a.csv"
    f.write_text("1,2,3\n")
    known = tmp_path / "sources.json"
    first = cache_module.source_key("v1", [f], known)
    st = f.stat()
    f.write_text("1,2,4\n")  # same size
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns))  # and the modification time set back
    assert cache_module.source_key("v1", [f], known) != first
    assert cache_module.source_key("v1", [f]) == cache_module.source_key("v1", [f], known)  # without the record


def test_a_source_file_changed_just_now_is_not_kept(tmp_path):
    f = tmp_path / "a.csv"
    f.write_text("1,2,3\n")  # its change time is now: another write within the same tick could keep it
    known = tmp_path / "sources.json"
    cache_module.source_key("v1", [f], known)
    assert not known.exists()  # nothing kept, so nothing written


# ----------------------------------------------------------------- fragments written beside the run
def test_fragments_are_written_in_a_thread_of_their_own_in_order(tmp_path, monkeypatch):
    store = store_module.ResultStore(tmp_path / "out")
    order, threads = [], set()
    real = store_module.ResultStore.write_task

    def spy(self, task_id, score, predictions):
        threads.add(threading.get_ident())
        order.append(task_id)
        return real(self, task_id, score, predictions)
    monkeypatch.setattr(store_module.ResultStore, "write_task", spy)
    with store_module.TaskWriter(store) as writer:
        for i in range(5):
            writer.write(f"t{i}", {"task_id": f"t{i}", "status": "failed", "n_test": 3}, None)
    assert order == [f"t{i}" for i in range(5)] and threading.get_ident() not in threads
    assert sorted(store.finished()) == [f"t{i}" for i in range(5)]  # every write done when the block ends


def test_a_failed_fragment_write_stops_the_run_at_the_next_task_and_keeps_the_others(tmp_path, monkeypatch):
    store = store_module.ResultStore(tmp_path / "out")
    real = store_module.ResultStore.write_task

    def full_disk(self, task_id, score, predictions):
        if task_id == "t1":
            raise WriteError(self.scores_fragment(task_id), OSError(28, "No space left on device"))
        return real(self, task_id, score, predictions)
    monkeypatch.setattr(store_module.ResultStore, "write_task", full_disk)
    written = []
    with pytest.raises(WriteError, match="t1.scores.parquet"):
        with store_module.TaskWriter(store) as writer:
            for i in range(4):
                writer.write(f"t{i}", {"task_id": f"t{i}", "status": "failed", "n_test": 3}, None)
                written.append(i)
    assert written == [0, 1]  # the write after the failed one raised its error
    assert sorted(store.finished()) == ["t0"]


def test_an_interrupted_run_keeps_the_fragments_of_its_finished_tasks(tmp_path):
    store = store_module.ResultStore(tmp_path / "out")
    with pytest.raises(KeyboardInterrupt):
        with store_module.TaskWriter(store) as writer:
            writer.write("t0", {"task_id": "t0", "status": "failed", "n_test": 3}, None)
            raise KeyboardInterrupt
    assert store.finished() == {"t0": "failed"}


# ----------------------------------------------------------------- package versions in task identities
def test_the_versions_behind_import_names_are_read_once_per_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(identity, "_environment_state", lambda: [["/site", 1]])  # installed long ago
    identity._versions_of.cache_clear()
    tops = ("numpy", "sklearn")
    got = identity._versions_of(tops)
    assert got["scikit-learn"] == metadata.version("scikit-learn") and got["numpy"] == metadata.version("numpy")
    assert got["scipy"] == metadata.version("scipy")  # scikit-learn requires it
    identity._versions_of.cache_clear()  # as a new process
    monkeypatch.setattr(identity, "package_versions", lambda **k: pytest.fail("read again"))
    assert identity._versions_of(tops) == got
    identity._versions_of.cache_clear()


def test_an_environment_changed_since_is_read_again(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    state = [["/site", 1]]
    monkeypatch.setattr(identity, "_environment_state", lambda: state)
    identity._versions_of.cache_clear()
    identity._versions_of(("numpy",))
    state[0][1] = 2  # a distribution installed or removed in /site
    identity._versions_of.cache_clear()
    calls = []
    monkeypatch.setattr(identity, "package_versions", lambda **k: calls.append(k) or {"numpy": "0.0-new"})
    assert identity._versions_of(("numpy",)) == {"numpy": "0.0-new"} and len(calls) == 1
    state[0][1] = time.time_ns()  # changed just now: may change again within the same tick, not kept
    identity._versions_of.cache_clear()
    identity._versions_of(("numpy",))
    identity._versions_of.cache_clear()
    identity._versions_of(("numpy",))
    assert len(calls) == 3
    identity._versions_of.cache_clear()


def test_a_dataset_from_the_cache_is_picklable_and_keeps_its_checksums(tmp_path):
    import pickle

    ds = _cached(tmp_path)
    ds.labelled_checksums("gesture")
    copy = pickle.loads(pickle.dumps(ds))
    assert copy.content_hash == make_dataset(seed=3).content_hash
    assert copy.labelled_checksums("gesture") == _by_hand(copy, "gesture")


def _new_process() -> None:
    """Forget what this process parsed, as a new process would."""
    identity._parse.cache_clear()
    identity._parsed.update(path=None, files={}, changed=False)


def test_a_new_process_parses_only_the_source_files_written_since(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(hashing, "RECENT_SECONDS", 0.0)
    _new_process()
    first = identity.feature_set_identity("msd")
    _new_process()
    monkeypatch.setattr(identity, "_parse", lambda *a: pytest.fail(f"{a[0]} parsed again"))
    assert identity.feature_set_identity("msd") == first
    identity._parsed.update(path=None, files={}, changed=False)


def test_a_source_file_edited_with_its_size_and_time_kept_is_parsed_again(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(hashing, "RECENT_SECONDS", 0.0)
    f = tmp_path / "helper.py"
    f.write_text("import abc\n")
    _new_process()
    digest, imports = identity._file_info(str(f))
    assert digest == hashlib.sha256(b"import abc\n").hexdigest()[:16] and imports == (("abc", (), 0),)
    identity._save_parses()
    st = f.stat()
    f.write_text("import sys\n")  # same size
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns))  # and the modification time set back
    _new_process()
    assert identity._file_info(str(f)) == (hashlib.sha256(b"import sys\n").hexdigest()[:16], (("sys", (), 0),))
    _new_process()
