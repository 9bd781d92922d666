"""Reference results: a finished run saved under a name, placed beside another run's methods by
``leaderboard --reference`` only where the test sets have the same content."""

from __future__ import annotations

import errno
import json
import os
import shutil
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.engine import run_protocol
from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol
from touchbench.reports import reference as reference_module
from touchbench.results.store import read_results_table, write_results_table


def _run(tmp_path, out: str, seed: int = 4, classifiers: str = "[test-logreg]"):
    data = tmp_path / f"data-{seed}.parquet"
    if not data.exists():
        random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=seed).to_parquet(data)
    p = parse_protocol(f"name: x\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\n"
                       f"classifiers: {classifiers}\nseed: 1\n", tmp_path / "x.yaml")
    run_protocol(p, out=tmp_path / out, progress=False)
    return tmp_path / out


@pytest.fixture
def refs(engine_env, tmp_path, monkeypatch):
    store = tmp_path / "refs"
    monkeypatch.setenv("TOUCHBENCH_REFERENCE_DIR", str(store))
    return store


def _invoke(*args):
    return CliRunner().invoke(cli, list(map(str, args)))


def test_a_reference_is_placed_beside_a_run_on_the_same_test_set(refs, tmp_path):
    saved = _run(tmp_path, "saved", classifiers="[test-logreg, zhou-lda]")
    r = _invoke("reference", "save", saved, "--name", "mine", "--to", refs)
    assert r.exit_code == 0, r.output
    index = json.loads((refs / "mine" / "reference.json").read_text())
    assert index["protocol"] == "x" and index["touchbench_version"] and index["machine"]
    new = _run(tmp_path, "new")  # only test-logreg: zhou-lda comes from the reference
    r = _invoke("leaderboard", new, "--reference", "mine", "--json")
    assert r.exit_code == 0, r.output
    assert "beside reference mine" in r.stderr
    rows = {row["classifier"]: row for row in json.loads(r.stdout)["tables"][0]["rows"]}
    assert set(rows) == {"test-logreg", "test-logreg (reference mine)", "zhou-lda (reference mine)"}
    scores = pd.read_parquet(saved / "scores.parquet")
    lda = scores[scores["classifier"] == "zhou-lda"]["accuracy"].mean()
    assert rows["zhou-lda (reference mine)"]["accuracy"] == pytest.approx(lda)


def test_a_reference_on_other_captures_is_refused(refs, tmp_path):
    _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine", "--to", refs)
    other = _run(tmp_path, "other", seed=5)  # another random dataset: other frames
    r = _invoke("leaderboard", other, "--reference", "mine")
    assert r.exit_code != 0
    assert "none of its 1 test set(s) has the content" in r.output


def test_an_unknown_reference_names_the_saved_ones(refs, tmp_path):
    _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine", "--to", refs)
    r = _invoke("leaderboard", tmp_path / "saved", "--reference", "mines")
    assert r.exit_code != 0 and "did you mean 'mine'" in r.output and "saved: mine" in r.output
    r = _invoke("reference", "list")
    assert r.exit_code == 0 and r.output.startswith("mine")


def test_an_unfinished_run_is_not_saved(refs, tmp_path):
    saved = _run(tmp_path, "saved")
    m = json.loads((saved / "manifest.json").read_text())
    m["finished_at"] = None
    (saved / "manifest.json").write_text(json.dumps(m))
    r = _invoke("reference", "save", saved, "--name", "mine", "--to", refs)
    assert r.exit_code != 0 and "not finished" in r.output
    assert not (refs / "mine").exists()


def _edit_scores(folder, accuracy: float) -> None:
    """Every accuracy of ``folder``'s scores set to ``accuracy``, in the file's own format."""
    scores = read_results_table(folder / "scores.parquet")
    assert (scores["accuracy"] != accuracy).all()  # a change, not the run's own values
    write_results_table(folder / "scores.parquet", scores.assign(accuracy=accuracy))


def test_a_reference_edited_after_it_was_saved_is_named_beside_the_run(refs, tmp_path):
    assert _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine", "--to", refs).exit_code == 0
    new = _run(tmp_path, "new")
    r = _invoke("leaderboard", new, "--reference", "mine", "--json")
    assert r.exit_code == 0 and "changed since" not in r.stderr  # as saved: nothing to say
    _edit_scores(refs / "mine" / "x", 0.25)
    r = _invoke("leaderboard", new, "--reference", "mine", "--json")
    assert r.exit_code == 0, r.output
    said = (f"{refs / 'mine' / 'x'}: scores.parquet changed since the run wrote it (its SHA-256 is not the one "
            "manifest.json records)")
    assert f"warning: {said}" in r.stderr
    table = json.loads(r.stdout)["tables"][0]
    assert any(n.startswith(said) for n in table["notes"])
    rows = {row["classifier"]: row["accuracy"] for row in table["rows"]}
    assert rows["test-logreg (reference mine)"] == pytest.approx(0.25)  # shown as it is now, with the note


def test_a_run_edited_after_it_ran_is_not_saved_as_a_reference(refs, tmp_path):
    saved = _run(tmp_path, "saved")
    _edit_scores(saved, 0.25)
    r = _invoke("reference", "save", saved, "--name", "mine", "--to", refs)
    assert r.exit_code != 0 and "Traceback" not in r.output
    assert f"{saved}: scores.parquet changed since the run wrote it: not saved as a reference" in r.output
    assert not (refs / "mine").exists()


def test_the_shipped_tiny_reference_is_what_this_code_computes(tmp_path, monkeypatch):
    """A fresh run of the shipped ``tiny`` protocol matches the shipped reference's test set and
    reproduces its accuracies (when it does not, `make reference-results` saves them again)."""
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("TOUCHBENCH_REFERENCE_DIR", str(tmp_path / "no-user-references"))
    r = _invoke("run", "tiny", "--out", tmp_path / "tiny", "--no-progress")
    assert r.exit_code == 0, r.output
    r = _invoke("leaderboard", tmp_path / "tiny", "--reference", "tiny", "--json")
    assert r.exit_code == 0, r.output
    assert "changed since" not in r.stderr and "missing" not in r.stderr  # the shipped files are as saved
    rows = json.loads(r.stdout)["tables"][0]["rows"]
    mine = {row["classifier"] + "/" + row["features"]: row["accuracy"] for row in rows if "(reference" not in row["classifier"]}
    ref = {row["classifier"].replace(" (reference tiny)", "") + "/" + row["features"]: row["accuracy"]
           for row in rows if "(reference tiny)" in row["classifier"]}
    assert mine and mine == ref


# -- names, destinations and replacement ------------------------------------------------------------

def _files(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (hidden ones too): relative path -> content."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.fixture
def shipped(tmp_path, monkeypatch):
    """A stand-in for the package's shipped references (a copy of the shipped ``tiny``), so that no
    test writes into the package whatever the code under test does."""
    folder = tmp_path / "shipped"
    shutil.copytree(Path(reference_module.__file__).parent.parent / "data" / "reference" / "tiny", folder / "tiny")
    monkeypatch.setattr(reference_module, "SHIPPED", folder)
    return folder


def _test_set(results: Path) -> str:
    return json.loads((results / "manifest.json").read_text())["ledger"]["test_set"]


@pytest.mark.parametrize("name", ["..", ".", "", "a/b", "ABSOLUTE", "two\nlines", "x" * 300, ".hidden", "-x",
                                  "caf\u00e9"])
def test_a_name_that_is_not_one_folder_is_refused_and_nothing_is_deleted(refs, shipped, tmp_path, name):
    box = tmp_path / "box"
    dest = box / "refs"
    assert _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "other", "--to", dest).exit_code == 0
    (box / "keep.txt").write_text("mine")
    before, shipped_before = _files(box), _files(shipped)
    name = str(tmp_path / "abs") if name == "ABSOLUTE" else name
    r = _invoke("reference", "save", tmp_path / "saved", "--name", name, "--to", dest)
    assert r.exit_code == 2 and isinstance(r.exception, SystemExit), r.output  # a usage error, no traceback
    assert "Invalid value for '--name'" in r.output and "not a valid reference name" in r.output
    assert "starting with a letter or a digit" in r.output
    assert _files(box) == before  # the folder above, the other reference: all still there
    assert not (tmp_path / "abs").exists() and _files(shipped) == shipped_before


def test_the_longest_name_and_every_allowed_character_are_saved(refs, shipped, tmp_path):
    name = "A9_b-c." + "z" * 57  # 64 characters
    r = _invoke("reference", "save", _run(tmp_path, "saved"), "--name", name)
    assert r.exit_code == 0, r.output
    assert (refs / name / "reference.json").is_file()
    r = _invoke("reference", "save", tmp_path / "saved", "--name", name + "z")  # 65
    assert r.exit_code == 2 and "not a valid reference name" in r.output


def test_a_name_that_is_not_one_folder_reaches_no_reference(refs, shipped, tmp_path):
    """`leaderboard --reference` does not follow a path out of the folders of references, and `list`
    shows only folders a valid name reaches (not a leftover temporary folder, not a name with a newline)."""
    saved = _run(tmp_path, "saved")
    outside = tmp_path / "outside"
    assert _invoke("reference", "save", saved, "--name", "secret", "--to", outside).exit_code == 0
    r = _invoke("leaderboard", saved, "--reference", "../outside/secret")
    assert r.exit_code != 0 and "'../outside/secret' is not a valid reference name" in r.output, r.output
    assert "Traceback" not in r.output
    refs.mkdir(parents=True, exist_ok=True)
    shutil.copytree(outside / "secret", refs / "bad\nname")
    shutil.copytree(outside / "secret", refs / ".mine.0123456789ab.tmp")
    shutil.copytree(outside / "secret", refs / "mine")
    r = _invoke("reference", "list", "--json")
    assert r.exit_code == 0, r.output
    assert [e["name"] for e in json.loads(r.stdout)] == ["mine", "tiny"]


@pytest.mark.skipif(sys.platform != "linux", reason="the user's data directory is $XDG_DATA_HOME on Linux only")
def test_save_writes_into_the_user_data_folder_never_the_package(engine_env, shipped, tmp_path, monkeypatch):
    monkeypatch.delenv("TOUCHBENCH_REFERENCE_DIR", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    before = _files(shipped)
    r = _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "mine")
    assert r.exit_code == 0, r.output
    user = tmp_path / "xdg" / "touchbench" / "reference"
    assert json.loads((user / "mine" / "reference.json").read_text())["protocol"] == "x"
    assert _files(shipped) == before
    r = _invoke("reference", "list", "--json")
    assert {(e["name"], e["origin"]) for e in json.loads(r.stdout)} == {("mine", "user"), ("tiny", "shipped")}
    r = _invoke("leaderboard", tmp_path / "saved", "--reference", "mine")
    assert r.exit_code == 0 and "beside reference mine" in r.output, r.output


def test_replacing_a_saved_reference_needs_force(refs, shipped, tmp_path):
    first, second = _run(tmp_path, "first"), _run(tmp_path, "second", seed=5)
    assert _invoke("reference", "save", first, "--name", "mine").exit_code == 0
    before = _files(refs / "mine")
    r = _invoke("reference", "save", second, "--name", "mine")
    assert r.exit_code == 3 and r.output.startswith("error: ") and r.output.count("\n") == 1, r.output
    assert "a reference named 'mine' exists" in r.output and "add --force to replace it" in r.output
    assert _files(refs / "mine") == before
    r = _invoke("reference", "save", second, "--name", "mine", "--force")
    assert r.exit_code == 0, r.output
    index = json.loads((refs / "mine" / "reference.json").read_text())
    assert [e["test_set"] for e in index["evaluations"]] == [_test_set(second)] != [_test_set(first)]
    assert sorted(p.name for p in refs.iterdir()) == ["mine"]  # nothing left beside it


def test_a_folder_that_is_not_a_reference_is_never_replaced(refs, shipped, tmp_path):
    (refs / "photos").mkdir(parents=True)
    (refs / "photos" / "holiday.jpg").write_bytes(b"jpeg")
    r = _invoke("reference", "save", _run(tmp_path, "saved"), "--name", "photos", "--force")
    assert r.exit_code == 3 and "is not a saved reference: it is left as it is" in r.output, r.output
    assert _files(refs) == {"photos/holiday.jpg": b"jpeg"}


def test_a_shipped_name_is_refused_outside_the_shipped_folder(refs, shipped, tmp_path):
    before = _files(shipped)
    saved = _run(tmp_path, "saved")
    for extra in ([], ["--force"], ["--to", tmp_path / "elsewhere", "--force"]):
        r = _invoke("reference", "save", saved, "--name", "tiny", *extra)
        assert r.exit_code == 3, r.output
        assert "'tiny' is the name of a shipped reference (shipped references are read-only)" in r.output
    assert _files(shipped) == before and not refs.exists() and not (tmp_path / "elsewhere").exists()
    # the maintainers' way (make reference-results): --to the shipped folder itself, with --force
    r = _invoke("reference", "save", saved, "--name", "tiny", "--to", shipped)
    assert r.exit_code == 3 and "add --force to replace it" in r.output and _files(shipped) == before
    r = _invoke("reference", "save", saved, "--name", "tiny", "--to", shipped, "--force")
    assert r.exit_code == 0, r.output
    assert json.loads((shipped / "tiny" / "reference.json").read_text())["protocol"] == "x"
    assert sorted(p.name for p in shipped.iterdir()) == ["tiny"]


def test_a_user_reference_hides_a_shipped_one_of_its_name(refs, shipped, tmp_path):
    """A user reference saved before a shipped one took its name keeps its meaning; the list says so."""
    saved = _run(tmp_path, "saved")
    assert _invoke("reference", "save", saved, "--name", "mine").exit_code == 0
    shutil.copytree(refs / "mine", refs / "tiny")
    r = _invoke("reference", "list", "--json")
    listed = {e["name"]: (e["origin"], e["hides_shipped"], e["path"]) for e in json.loads(r.stdout)}
    assert listed == {"mine": ("user", False, str(refs / "mine")), "tiny": ("user", True, str(refs / "tiny"))}
    r = _invoke("reference", "list")
    assert "hides the shipped one of this name" in r.output.splitlines()[1]
    r = _invoke("leaderboard", saved, "--reference", "tiny")  # the user's (protocol x): its test set matches
    assert r.exit_code == 0 and "beside reference tiny: protocol x" in r.output, r.output


@pytest.mark.parametrize("failure", ["disk full while writing", "the final rename"])
def test_a_failed_replacement_leaves_the_old_reference_whole(refs, shipped, tmp_path, monkeypatch, failure):
    first, second = _run(tmp_path, "first"), _run(tmp_path, "second", seed=5)
    assert _invoke("reference", "save", first, "--name", "mine").exit_code == 0
    before = _files(refs)
    if failure == "disk full while writing":
        def copyfile(src, dst, **kw):
            raise OSError(errno.ENOSPC, "No space left on device")
        monkeypatch.setattr(shutil, "copyfile", copyfile)
        reason = "no space left on the device"
    else:
        rename = os.rename

        def failing_rename(src, dst, **kw):
            if Path(src).name.endswith(".tmp") and Path(dst) == refs / "mine":
                raise OSError(errno.EACCES, "Permission denied")
            return rename(src, dst, **kw)
        monkeypatch.setattr(os, "rename", failing_rename)
        reason = "permission denied"
    r = _invoke("reference", "save", second, "--name", "mine", "--force")
    assert r.exit_code == 3 and isinstance(r.exception, SystemExit), r.output
    assert r.output.startswith(f"error: {refs / 'mine'}: cannot write: {reason}") and r.output.count("\n") == 1
    assert _files(refs) == before and sorted(p.name for p in refs.iterdir()) == ["mine"]


@pytest.mark.parametrize("text, said", [
    ("{not json", "not JSON"), ("", "not JSON"), ("[1, 2]", "a JSON list where a mapping"),
    ('{"evaluations": {"a": 1}}', "'evaluations' must be a list of mappings"),
    ('{"evaluations": [{"folder": "x"}]}', "'evaluations' must be a list of mappings"),
])
def test_a_damaged_reference_index_is_one_error_naming_it(refs, shipped, tmp_path, text, said):
    saved = _run(tmp_path, "saved")
    (refs / "mine").mkdir(parents=True)
    (refs / "mine" / "reference.json").write_text(text)
    for args in (["reference", "list"], ["leaderboard", saved, "--reference", "mine"]):
        r = _invoke(*args)
        assert r.exit_code == 3 and isinstance(r.exception, SystemExit), r.output
        assert r.output.startswith(f"error: {refs / 'mine' / 'reference.json'}: damaged reference index")
        assert said in r.output and "Traceback" not in r.output


def test_a_folder_of_references_that_is_a_file_is_named(engine_env, shipped, tmp_path, monkeypatch):
    store = tmp_path / "refs.txt"
    store.write_text("not a folder")
    monkeypatch.setenv("TOUCHBENCH_REFERENCE_DIR", str(store))
    for args in (["reference", "save", _run(tmp_path, "saved"), "--name", "mine"], ["reference", "list"]):
        r = _invoke(*args)
        assert r.exit_code == 3, r.output
        assert f"{store}: the folder of references ($TOUCHBENCH_REFERENCE_DIR" in r.output
        assert "is a file, not a folder" in r.output and "File exists" not in r.output
    assert store.read_text() == "not a folder"


def _tables(r) -> list[set[str]]:
    assert r.exit_code == 0, r.output
    return [{row["classifier"] for row in t["rows"]} for t in json.loads(r.stdout)["tables"]]


def test_two_evaluations_on_the_same_captures_stay_two(refs, tmp_path):
    """Two evaluations of one dataset test the same captures (one content hash) under two schemes:
    the reference keeps both, and a run of one of them is placed beside that evaluation's rows
    (one table, the user's scheme), never the other's (a table of their own)."""
    data = tmp_path / "same.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2, seed=4).to_parquet(data)
    text = (f"name: two\ndataset: {data}\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\nseed: 1\n"
            "evaluations:\n  - {name: first, scheme: loso}\n  - {name: second, scheme: {name: kfold, k: 2}}\n")
    run_protocol(parse_protocol(text, tmp_path / "two.yaml"), out=tmp_path / "saved", progress=False)
    assert _invoke("reference", "save", tmp_path / "saved", "--name", "two", "--to", refs).exit_code == 0
    assert "2 evaluation(s)" in _invoke("reference", "list").output
    beside = {"test-logreg", "test-logreg (reference two)"}
    for evaluation in ("first", "second"):
        assert _tables(_invoke("leaderboard", tmp_path / "saved" / evaluation, "--reference", "two",
                               "--json")) == [beside], evaluation
    # an index saved before the evaluation's name was recorded: the folder names it
    index = json.loads((refs / "two" / "reference.json").read_text())
    for e in index["evaluations"]:
        del e["evaluation"]
    (refs / "two" / "reference.json").write_text(json.dumps(index))
    for evaluation in ("first", "second"):
        assert _tables(_invoke("leaderboard", tmp_path / "saved" / evaluation, "--reference", "two",
                               "--json")) == [beside], evaluation


def test_the_shipped_touch_all_reference_lists_its_seven_evaluations(refs):
    r = _invoke("reference", "list")
    line = next(x for x in r.output.splitlines() if x.startswith("touch-all "))
    assert line.endswith("7 evaluation(s)")
