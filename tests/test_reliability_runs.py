"""Interrupted runs, shared results folders, damaged files and careless data: one clear message
each, nothing stale reused, nothing left behind.

Every case here was once a crash, a silent wrong number or a process left running: a truncated
merged ``scores.parquet`` that made every rerun crash, a truncated ``predictions.parquet`` nobody
noticed, a scores fragment copied under another task's name and merged, two runs into one folder
both doing all the work, worker processes alive 20 minutes after their parent was killed, a model
file with its class list reversed labelling silently, tracebacks for a read-only or full disk, bad
Parquet metadata, ``stream --hop 0`` and a truncated ``.csv.gz``, line numbers pointing at the
wrong row, features of 1e150 inputs turning into NaN.
"""

from __future__ import annotations

import errno
import gzip
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers import SUBPROCESS_HANG_S, read_int, wait_for

from touchbench.cli.main import cli
from touchbench.core import atomic
from touchbench.core.errors import DataError, TouchbenchError, WriteError
from touchbench.datasets.challenge_csv import read_challenge_csv
from touchbench.datasets.generic import read_table_dataset
from touchbench.datasets.model import FORMAT_VERSION, SensorSpec, TouchDataset
from touchbench.deploy.model import MODEL_VERSION, TrainedModel, fit_model
from touchbench.deploy.stream import SlidingRecognizer, load_replay
from touchbench.engine import runner
from touchbench.engine.testing import SENSOR, random_dataset
from touchbench.features import FEATURES
from touchbench.features.base import FeatureInputError, make_feature_set
from touchbench.methods import MethodSpec
from touchbench.protocols.loading import parse_protocol
from touchbench.results.locking import ResultsBusyError
from touchbench.results.store import ResultStore
from touchbench.scenes.loading import load_spec

TEXT = "name: small\ndataset: scene:tiny\nscheme: loso\nfeatures: [sd]\nclassifiers: [zhou-lda]\n"
# HAART's recording setting, so that the Gaus sets take their presets from the sensor
PRESSURE_8X8 = SensorSpec(name="pressure-8x8", grid=(8, 8), frame_rate=54.0, value_range=(0.0, 1023.0))


@pytest.fixture
def env(engine_env):
    yield


def run(out: str = "out", **kw):
    return runner.run_protocol(parse_protocol(TEXT, "p.yaml"), out=out, progress=False, **kw)


def invoke(*args):
    return CliRunner().invoke(cli, list(args))


def one_line_error(result, text: str) -> None:
    """A refused command: non-zero exit, the message, and no traceback."""
    assert result.exit_code != 0, result.output
    assert text in result.output, result.output
    assert "Traceback" not in result.output and not isinstance(result.exception, (AssertionError, KeyError))


# ----------------------------------------------------------------- merged files
@pytest.mark.parametrize("name", ["scores.parquet", "predictions.parquet", "confusion.parquet", "confusion_pooled.parquet"])
def test_a_truncated_merged_file_is_rebuilt_from_the_task_results(env, name):
    first = run()
    path = Path("out") / name
    original = path.read_bytes()
    path.write_bytes(original[: len(original) // 2])
    again = run()
    assert again.n_ran == 0  # nothing recomputed: the fragments are intact
    assert f"{name} changed since the run wrote it: merged again from the results of each task" in again.notes
    assert path.read_bytes() == original  # the same bytes as the merge that first wrote it
    assert again.scores["accuracy"].tolist() == first.scores["accuracy"].tolist()
    assert run().notes == first.notes  # and trusted again after that


def test_a_deleted_merged_file_is_rebuilt(env):
    run()
    original = Path("out/predictions.parquet").read_bytes()
    Path("out/predictions.parquet").unlink()
    again = run()
    assert "predictions.parquet is missing: merged again from the results of each task" in again.notes
    assert Path("out/predictions.parquet").read_bytes() == original


def test_a_scores_fragment_copied_under_another_name_is_not_merged(env):
    first = run()
    a, b = sorted(Path("out/fragments").glob("*.scores.parquet"))[:2]
    shutil.copy(a, b)  # b now holds a's task
    again = run()
    assert again.n_ran == 1  # b's task is run again
    holds = [n for n in again.notes if "holds the results of another task" in n]
    assert len(holds) == 1 and holds[0].startswith("the saved results of sd | zhou-lda, fold ")
    merged = pd.read_parquet("out/scores.parquet")
    assert merged["task_id"].tolist() == first.scores["task_id"].tolist()  # each task once, its own
    assert pq.read_table(b).column("task_id")[0].as_py() == b.name.split(".")[0]


@pytest.mark.parametrize("damage, reason", [
    ("truncate", "its predictions file is unreadable"),
    ("drop-row", "rows for"),
    ("delete", "its predictions file is missing"),
    ("truncate-scores", "its scores file is unreadable"),
])
def test_a_damaged_task_is_run_again(env, damage, reason):
    first = run()
    merged = Path("out/predictions.parquet").read_bytes()
    pred = sorted(Path("out/fragments").glob("*.predictions.parquet"))[0]
    tid = pred.name.split(".")[0]
    if damage == "truncate":
        pred.write_bytes(pred.read_bytes()[:100])
    elif damage == "drop-row":
        df = pq.read_table(pred).to_pandas()
        pq.write_table(pa.Table.from_pandas(df.iloc[1:], preserve_index=False), pred)
    elif damage == "delete":
        pred.unlink()
    else:
        scores = Path("out/fragments") / f"{tid}.scores.parquet"
        scores.write_bytes(scores.read_bytes()[:50])
    again = run()
    assert again.n_ran == 1
    assert any(reason in n and n.endswith("; run again") for n in again.notes), again.notes
    assert Path("out/predictions.parquet").read_bytes() == merged  # the task recomputed bit-identically
    assert again.scores["accuracy"].tolist() == first.scores["accuracy"].tolist()
    if damage == "drop-row":  # the row count named is the test fold's, worked out from the scores
        n_test = int(first.scores.set_index("task_id").loc[tid, "n_test"])
        assert any(f"has {n_test - 1} rows for {n_test} test captures" in n for n in again.notes)


# ----------------------------------------------------------------- one run per results folder
def test_a_second_run_is_told_who_holds_the_folder(env):
    run()
    Path("p.yaml").write_text(TEXT)
    with ResultStore("out").lock(command="touchbench run other"):
        with pytest.raises(ResultsBusyError) as e:
            run()
        r = invoke("run", "p.yaml", "--out", "out", "--no-progress")
    msg = str(e.value)
    assert msg.startswith("out: in use by another run (pid ")
    assert f"pid {os.getpid()} on " in msg and ": touchbench run other)" in msg
    assert "wait for it to end (run with --wait SECONDS) or choose another --out" in msg
    one_line_error(r, "in use by another run")


def test_a_second_run_waits_for_the_first(env):
    run()
    held = threading.Event()

    def hold():
        with ResultStore("out").lock():
            held.set()
            time.sleep(1.5)

    t = threading.Thread(target=hold)
    t.start()
    assert held.wait(SUBPROCESS_HANG_S)
    res = run(wait=SUBPROCESS_HANG_S)  # blocks until the holder lets go, then finds everything finished
    t.join()
    assert res.noop


def test_the_lock_of_a_killed_run_is_free_at_once(tmp_path):
    code = ("import sys, time\nfrom touchbench.results.store import ResultStore\n"
            f"with ResultStore({str(tmp_path / 'out')!r}).lock():\n    print('held', flush=True)\n    time.sleep({SUBPROCESS_HANG_S})\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "held"
        with pytest.raises(ResultsBusyError, match=f"pid {p.pid} on "):
            with ResultStore(tmp_path / "out").lock():
                pass
    finally:
        p.kill()
        p.wait()
    with ResultStore(tmp_path / "out").lock():  # no stale lock to clear by hand
        pass


# ----------------------------------------------------------------- workers end with their parent
WORKERS = """\
import os, sys, time
from joblib import delayed
from touchbench.engine.backends import parallel

def work(i, folder):
    # written whole or not at all: a temporary name, then a rename
    tmp = os.path.join(folder, f".w{i}.tmp")
    with open(tmp, "w") as f:
        f.write(str(os.getpid()))
    os.replace(tmp, os.path.join(folder, f"w{i}"))
    time.sleep(300)

for _ in parallel(2)(delayed(work)(i, sys.argv[1]) for i in range(2)):
    pass
"""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    return "\nState:\tZ" not in state  # a zombie has ended; only its exit status is left


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads process states from /proc (Linux)")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_worker_processes_end_with_their_parent(tmp_path, sig):
    script = tmp_path / "workers.py"
    script.write_text(WORKERS)
    p = subprocess.Popen([sys.executable, str(script), str(tmp_path)])
    try:
        pids = [wait_for(lambda: read_int(tmp_path / f"w{i}"), f"worker {i}'s pid") for i in range(2)]
        assert all(_alive(w) for w in pids)
    finally:
        p.send_signal(sig)
        p.wait(timeout=SUBPROCESS_HANG_S)
    wait_for(lambda: not any(_alive(w) for w in pids), "the workers to end")


def test_a_worker_whose_parent_is_already_gone_exits_at_once():
    code = "from touchbench.engine.backends import end_with_parent\nimport time\nend_with_parent(1)\ntime.sleep(60)\n"
    p = subprocess.run([sys.executable, "-c", code], timeout=SUBPROCESS_HANG_S)
    assert os.getpid() != 1 and p.returncode == 1  # its parent is this process, not pid 1: it did not wait


# ----------------------------------------------------------------- read-only and full disks
@pytest.mark.parametrize("code, text", [
    (errno.ENOSPC, "cannot write: no space left on the device (free some space and run again; finished work is kept)"),
    (errno.EACCES, "cannot write: permission denied: the folder is not writable for you (choose another output folder)"),
    (errno.EROFS, "cannot write: the file system is read-only (choose another output folder)"),
])
def test_write_failures_are_one_message_and_leave_no_temporaries(env, monkeypatch, code, text):
    def fail(*a, **k):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(atomic.pq, "write_table", fail)
    with pytest.raises(WriteError) as e:
        run()
    assert str(e.value).startswith("out/fragments/") and str(e.value).endswith(text)
    assert not list(Path("out").rglob("*.tmp"))
    Path("p.yaml").write_text(TEXT)
    one_line_error(invoke("run", "p.yaml", "--out", "out2", "--no-progress"), text)
    assert not list(Path("out2").rglob("*.tmp"))


def test_a_folder_that_cannot_be_created_names_the_file(tmp_path, monkeypatch):
    def fail(*a, **k):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(atomic, "new_temp_file", fail)
    with pytest.raises(WriteError, match=r"x\.bin: cannot write: permission denied"):
        atomic.atomic_write_bytes(tmp_path / "x.bin", b"1")


# ----------------------------------------------------------------- damaged dataset files
def _dataset_with_metadata(path: Path, meta: bytes) -> None:
    random_dataset().to_parquet(path)
    table = pq.read_table(path)
    pq.write_table(table.replace_schema_metadata({**table.schema.metadata, b"touchbench": meta}), path)


@pytest.mark.parametrize("meta, text", [
    (b"{not json", "its touchbench metadata is damaged (JSONDecodeError); convert the data again"),
    (b"[1, 2]", "its touchbench metadata is damaged (AttributeError); convert the data again"),
    (json.dumps({"format_version": FORMAT_VERSION, "name": "x"}).encode(),
     "its touchbench metadata does not describe its frames (KeyError: 'sensor'); convert the data again"),
])
def test_bad_parquet_metadata_is_one_message(tmp_path, meta, text):
    path = tmp_path / "d.parquet"
    _dataset_with_metadata(path, meta)
    with pytest.raises(DataError) as e:
        TouchDataset.from_parquet(path)
    assert str(e.value).startswith(str(path) + ": ") and text in str(e.value)
    one_line_error(invoke("data", "info", str(path)), text)


# ----------------------------------------------------------------- model files
@pytest.fixture
def model_file(tmp_path):
    ds = random_dataset(subjects=("s1", "s2"), per_cell=3)
    model = fit_model(ds, MethodSpec("sd-lda", (("sd", {"preset": "haart"}),), "zhou-lda"))
    return model.save(tmp_path / "m.tbm"), ds


def test_a_model_file_loads_as_saved(model_file):
    path, ds = model_file
    model = TrainedModel.load(path)
    assert list(model.classes) == sorted(set(ds.meta["gesture"]))  # the classes the fit encoded
    assert model.consistency_problems() == []


@pytest.mark.parametrize("edit, text", [
    (lambda b: b[:-10], "bytes off the size touchbench wrote (truncated or edited); nothing was loaded"),
    (lambda b: b[:-10] + bytes(10), "does not match the checksum touchbench wrote with it (damaged or edited)"),
    (lambda b: b.replace(b'"version": %d' % MODEL_VERSION, b'"version": 9', 1),
     "written by another touchbench model format (version 9"),
    (lambda b: b.replace(b'"sha256"', b'"sha2xx"', 1), "the model file's header is damaged (KeyError); train it again"),
    (lambda b: b[len(b"touchbench-model\n"):], "not a touchbench model file, or one written by an older touchbench"),
])
def test_a_damaged_model_file_is_refused_before_unpickling(model_file, edit, text):
    path, _ = model_file
    path.write_bytes(edit(path.read_bytes()))
    with pytest.raises(DataError) as e:
        TrainedModel.load(path)
    assert str(e.value).startswith(f"{path}: ") and text in str(e.value)


def test_a_model_with_its_class_list_reversed_is_refused(model_file):
    path, _ = model_file
    model = TrainedModel.load(path)
    model.fitted.fitted.classes = model.classes[::-1]  # saved again through touchbench: the checksum is fresh
    model.manifest["classes"] = [str(c) for c in model.classes]
    model.save(path)
    with pytest.raises(DataError, match="its class list is not the sorted list of distinct class names the fit "
                                        "encoded"):
        TrainedModel.load(path)


def test_a_model_whose_classes_disagree_with_its_estimator_is_refused(model_file):
    path, _ = model_file
    model = TrainedModel.load(path)
    model.fitted.fitted.classes = np.array(list(model.classes) + ["zzz"], dtype=object)
    model.manifest["classes"] = [str(c) for c in model.classes]
    model.save(path)
    with pytest.raises(DataError, match="the classifier knows 3 classes, the class list names 4"):
        TrainedModel.load(path)


def test_a_model_whose_feature_sets_have_another_sensor_is_refused(model_file):
    path, _ = model_file
    model = TrainedModel.load(path)
    model.manifest["sensor"] = {**model.manifest["sensor"], "frame_rate": 99.0}
    model.save(path)
    with pytest.raises(DataError, match="was built for another sensor"):
        TrainedModel.load(path)


# ----------------------------------------------------------------- stream
def test_stream_hop_zero_is_refused_by_name(model_file):
    path, _ = model_file
    with pytest.raises(TouchbenchError, match="--hop must be a positive number of seconds, got 0"):
        SlidingRecognizer(TrainedModel.load(path), [1.0], hop_s=0)
    one_line_error(invoke("stream", str(path), "-", "--hop", "0"), "--hop must be a positive number of seconds, got 0")


def test_a_truncated_gzip_replay_names_the_file_and_line(model_file, tmp_path):
    path, _ = model_file
    lines = "".join(",".join(str((i + j) % 200) for j in range(16)) + "\n" for i in range(3000))
    gz = tmp_path / "frames.csv.gz"
    gz.write_bytes(gzip.compress(lines.encode())[:-200])
    with pytest.raises(DataError) as e:
        load_replay(gz, TrainedModel.load(path))
    assert str(e.value).startswith(f"{gz}:") and "the compressed file ends before its end marker (truncated?)" in str(e.value)
    assert e.value.line is not None and 1 < e.value.line <= 3001
    r = invoke("stream", str(path), str(gz), "--no-realtime")
    one_line_error(r, "the compressed file ends before its end marker")
    assert "Aborted!" not in r.output


# ----------------------------------------------------------------- line numbers
def _long_csv(path: Path, rows: list[tuple[str, int]], blank_after: int | None = None) -> None:
    lines = ["capture_id,frame,subject,gesture,c1,c2,c3,c4"]
    for k, (cap, fr) in enumerate(rows):
        lines.append(f"{cap},{fr},s1,pat,1,2,3,4")
        if blank_after == k:
            lines.append("")
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("rows, line, text", [
    # line 1 is the header, row k is on line k + 2; rows may come in any order, so a capture's frames
    # are taken in counter order and the error names the row of the frame at fault
    ([("a", 0), ("a", 1), ("a", -1), ("b", 0)], 4, "capture 'a' starts at frame -1; frames count from 0 or 1"),
    ([("a", 0), ("a", 1), ("b", -1), ("b", 0)], 4, "capture 'b' starts at frame -1; frames count from 0 or 1"),
    ([("a", -1), ("a", 0)], 2, "capture 'a' starts at frame -1; frames count from 0 or 1"),
    ([("a", 1), ("a", 2), ("b", 1), ("b", 3)], 5, "capture 'b': frame 3 follows 1 (a frame is missing)"),
    ([("a", 1), ("a", 2), ("a", 2)], 4, "capture 'a': frame 2 given twice"),
])
def test_frame_errors_name_the_row_and_the_value_as_written(tmp_path, rows, line, text):
    path = tmp_path / "t.csv"
    _long_csv(path, rows)
    with pytest.raises(DataError) as e:
        read_table_dataset(path, (2, 2), 10.0)
    assert e.value.line == line and str(e.value) == f"{path}:{line}: {text}"


def test_a_blank_line_does_not_shift_the_line_numbers(tmp_path):
    path = tmp_path / "t.csv"
    _long_csv(path, [("a", 0), ("a", 1), ("a", 2), ("a", 5)], blank_after=0)  # header, a0, blank, a1, a2, a5
    with pytest.raises(DataError) as e:
        read_table_dataset(path, (2, 2), 10.0)
    assert e.value.line == 3  # the blank line itself: a row with no values


def test_blank_lines_at_the_end_are_no_rows(tmp_path):
    path = tmp_path / "t.csv"
    _long_csv(path, [("a", 0), ("a", 1)])
    path.write_text(path.read_text() + "\n\n")
    ds = read_table_dataset(path, (2, 2), 10.0)
    assert len(ds) == 1 and ds.captures[0].shape == (2, 2, 2)


# ----------------------------------------------------------------- extreme values
@pytest.mark.parametrize("scale", [1e150, 1e300, -1e200])
@pytest.mark.parametrize("name", [n for n in FEATURES.names() if n != "raw-window"])
def test_features_are_finite_or_refused_for_values_beyond_the_sensor(name, scale):
    rng = np.random.default_rng(0)
    caps = [rng.random((30, 8, 8)) * scale for _ in range(3)]
    fs = make_feature_set(name, {}, PRESSURE_8X8)
    try:
        with np.errstate(all="raise"):
            X = fs.fit(caps).transform(caps)
    except FeatureInputError as e:
        assert "gives non-finite features: its values reach" in str(e)
        assert "outside the sensor's range [0, 1023]" in str(e) and "capture " in str(e)
    else:
        assert np.isfinite(X).all()


def test_a_padded_raw_window_too_large_is_refused_before_it_is_allocated():
    fs = make_feature_set("raw-window", {"frames": 10**8, "shorter": "pad"}, None)
    cap = [np.zeros((5, 8, 8))]
    with pytest.raises(FeatureInputError, match=r"frames=100000000 on a 8 x 8 grid is 6,400,000,000 values per "
                                                r"capture, above the 16,777,216 a window may hold"):
        fs.fit(cap).transform(cap)
    assert "a window may hold" in fs.check_sensor(SENSOR)


# ----------------------------------------------------------------- YAML beyond protocols
def test_a_scene_file_with_nested_aliases_is_refused(tmp_path):
    laughs = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi"))
    path = tmp_path / "s.yaml"
    path.write_text(laughs)
    with pytest.raises(DataError, match=r"s\.yaml:\d+: "):
        load_spec(path)


# ----------------------------------------------------------------- readers never crash
CELL = st.one_of(st.integers(-5, 1100).map(str), st.sampled_from(["", "x", "nan", "1e400", "3.5", " 7"]))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(st.sampled_from(["a", "b", ""]), st.integers(-2, 4), CELL, CELL), max_size=12),
       blank=st.booleans())
def test_random_long_tables_are_a_dataset_or_one_data_error(tmp_path, rows, blank):
    path = tmp_path / "t.csv"
    lines = ["capture_id,frame,subject,gesture,c1,c2"]
    lines += [f"{c},{f},s1,pat,{v},{w}" for c, f, v, w in rows]
    if blank and lines[1:]:
        lines.insert(2, "")
    path.write_text("\n".join(lines) + "\n")
    try:
        ds = read_table_dataset(path, (1, 2), 10.0)
    except DataError as e:
        assert str(e).startswith(str(path))
        if e.line is not None:
            assert 1 <= e.line <= len(lines)
    else:
        assert sum(c.shape[0] for c in ds.captures) == len(rows)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(body=st.lists(st.lists(CELL, min_size=0, max_size=70), max_size=4))
def test_random_challenge_files_are_a_dataset_or_one_data_error(tmp_path, body):
    path = tmp_path / "testWITHLABELS.csv"
    header = "ParticipantID,Substrate,Cover,Gesture,Sequence," + ",".join(f"cell{i}" for i in range(1, 65))
    path.write_text(header + "\n" + "\n".join("T1,foam,fur,pat," + ",".join(r) for r in body) + "\n")
    try:
        read_challenge_csv(path)
    except DataError as e:
        assert str(e).startswith(str(path))


# ----------------------------------------------------------------- the results folder itself
def _read_only(monkeypatch, root: Path) -> None:
    """Opening a file under ``root`` to write, or writing any file, fails as on a read-only file system."""
    real_open = os.open
    root = root.resolve()

    def ro_open(path, flags, *a, **k):
        if flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT) and Path(path).resolve().is_relative_to(root):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))
        return real_open(path, flags, *a, **k)

    def fail(*a, **k):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(os, "open", ro_open)
    monkeypatch.setattr(atomic, "new_temp_file", fail)


@pytest.mark.parametrize("lock_file", [True, False], ids=["with-lock-file", "without-lock-file"])
def test_a_finished_run_in_a_read_only_folder_has_nothing_to_do(env, monkeypatch, lock_file):
    Path("p.yaml").write_text(TEXT)
    r = invoke("run", "p.yaml", "--out", "out", "--no-progress")
    assert r.exit_code == 0, r.output
    if not lock_file:  # a copy of the results without it
        (Path("out") / ".touchbench.lock").unlink()
    before = {p: p.read_bytes() for p in Path("out").rglob("*") if p.is_file()}
    _read_only(monkeypatch, Path("out"))
    r = invoke("run", "p.yaml", "--out", "out", "--no-progress")
    assert r.exit_code == 0, r.output
    assert "nothing to do: all 4 tasks finished" in r.output  # the tiny scene: 4 people (LOSO folds), one method
    assert {p: p.read_bytes() for p in Path("out").rglob("*") if p.is_file()} == before


def test_a_run_into_a_folder_of_another_protocol_is_refused_and_changes_nothing(env):
    Path("p.yaml").write_text(TEXT)
    Path("q.yaml").write_text(TEXT.replace("name: small", "name: other").replace("zhou-lda", "zhou-tree"))
    assert invoke("run", "p.yaml", "--out", "out", "--no-progress").exit_code == 0
    before = {p: p.read_bytes() for p in Path("out").iterdir() if p.is_file() and p.name != ".touchbench.lock"}
    r = invoke("run", "q.yaml", "--out", "out", "--no-progress")
    one_line_error(r, "out: holds the results of protocol 'small', not of 'other': a run here would replace its "
                      "merged tables; choose another results folder with --out")
    assert r.exit_code == 3
    assert {p: p.read_bytes() for p in before} == before
    assert invoke("run", "q.yaml", "--out", "out-other", "--no-progress").exit_code == 0


@pytest.mark.parametrize("out", ["link", "link/sub"])
def test_a_results_folder_at_a_dangling_symbolic_link_names_the_link_and_its_target(env, out):
    Path("p.yaml").write_text(TEXT)
    os.symlink("gone/away", "link")
    r = invoke("run", "p.yaml", "--out", out, "--no-progress")
    one_line_error(r, f"{out}: link is a dangling symbolic link (to gone/away, which does not exist): create its "
                      "target, or choose another results folder with --out")
    assert r.exit_code == 3 and not Path("gone").exists()
