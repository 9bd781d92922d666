"""A folder of recordings against its SHA256SUMS: a listed file the folder lacks is refused (never left
out silently), a file the list does not cover is read and said, and a missing, empty or partly
unreadable list says that nothing (or not everything) was checked. Small fake folders of the
``haart``, ``icmi15-study2`` and ``haart-raw`` layouts."""

from __future__ import annotations

import gzip
import hashlib
import json
import logging

import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.errors import DataError
from touchbench.datasets.haart import build_haart
from touchbench.datasets.haart_raw import read_haart_raw
from touchbench.datasets.icmi15_study2 import load_icmi15_study2

from helpers import random_recording, write_recording

NAMES = ["140729-1foamfurpat", "140729-1foamfurrub", "140729-1nonenonetickle"]


@pytest.fixture
def haart(tmp_path):
    """``haart/raw/140729-1/`` with three gzipped recordings; returns (the haart folder, name -> sha256)."""
    raw = tmp_path / "haart" / "raw" / "140729-1"
    raw.mkdir(parents=True)
    digests = {}
    for i, name in enumerate(NAMES):
        lines = random_recording(i)
        write_recording(raw / name, lines, gz=True)
        digests[name] = hashlib.sha256(("\n".join(lines) + "\n").encode()).hexdigest()
    return tmp_path / "haart", digests


def _sums(folder, digests, extra=""):
    (folder / "SHA256SUMS").write_text("".join(f"{d}  ./140729-1/{n}\n" for n, d in digests.items()) + extra)


def test_a_listed_recording_missing_from_the_folder_is_refused(haart):
    folder, digests = haart
    _sums(folder, digests)
    (folder / "raw" / "140729-1" / "140729-1foamfurrub.gz").unlink()
    with pytest.raises(DataError) as e:
        build_haart(folder / "raw")
    assert "1 file(s) listed in SHA256SUMS are missing from the folder: 140729-1/140729-1foamfurrub" in str(e.value)


def test_many_missing_files_are_named_up_to_five_then_counted(haart):
    folder, digests = haart
    gone = {f"140729-2/140729-2foamfur{g}": "0" * 64 for g in ("pat", "rub", "stroke", "tickle", "scratch", "notouch",
                                                                 "constant")}
    _sums(folder, digests, "".join(f"{d}  ./{n}\n" for n, d in gone.items()))
    with pytest.raises(DataError) as e:
        build_haart(folder / "raw")
    msg = str(e.value)
    assert "7 file(s) listed in SHA256SUMS are missing" in msg and msg.count("140729-2/") == 5 and "and 2 more" in msg


def test_a_listed_file_that_is_no_recording_but_is_there_is_fine(haart):
    folder, digests = haart
    (folder / "raw" / "140729-1" / "note.txt").write_text("a note\n")
    _sums(folder, digests, f"{hashlib.sha256(b'a note').hexdigest()}  ./140729-1/note.txt\n")
    ds = build_haart(folder / "raw")
    assert len(ds) == 3 and ds.provenance["checksums"].startswith("3 of 3 recordings verified against")


def test_a_recording_the_list_does_not_cover_is_read_and_said(haart, caplog):
    folder, digests = haart
    _sums(folder, {n: d for n, d in digests.items() if n != "140729-1nonenonetickle"})
    with caplog.at_level(logging.WARNING, logger="touchbench.datasets"):
        ds = build_haart(folder / "raw")
    assert len(ds) == 3
    assert "1 recording(s) not listed in SHA256SUMS read unchecked: 140729-1/140729-1nonenonetickle" in caplog.text
    prov = ds.provenance["checksums"]
    assert prov.startswith("2 of 3 recordings verified against")
    assert "1 read but not listed, so not checked: 140729-1/140729-1nonenonetickle" in prov


@pytest.mark.parametrize("content,why", [
    (None, "no SHA256SUMS file"),
    ("", "lists no file"),
    ("not a checksum line\n", "lists no file (1 unreadable line(s), the first line 1)"),
    (b"\xff\xfe\x00garbage", "is unreadable (UnicodeDecodeError)"),
])
def test_a_missing_empty_or_unreadable_list_says_nothing_was_checked(haart, caplog, content, why):
    folder, _ = haart
    if isinstance(content, bytes):
        (folder / "SHA256SUMS").write_bytes(content)
    elif content is not None:
        (folder / "SHA256SUMS").write_text(content)
    with caplog.at_level(logging.WARNING, logger="touchbench.datasets"):
        ds = build_haart(folder / "raw")
    assert len(ds) == 3
    assert ds.provenance["checksums"].startswith("not checked: ") and why in ds.provenance["checksums"]
    assert "recordings not checked" in caplog.text and why in caplog.text


def test_a_partly_unreadable_list_checks_the_lines_it_can_and_says_so(haart, caplog):
    folder, digests = haart
    good = "".join(f"{d}  ./140729-1/{n}\n" for n, d in digests.items())
    (folder / "SHA256SUMS").write_text("garbage\n" + good + "abc  ./140729-1/x\n")
    with caplog.at_level(logging.WARNING, logger="touchbench.datasets"):
        ds = build_haart(folder / "raw")
    prov = ds.provenance["checksums"]
    assert prov.startswith("3 of 3 recordings verified") and "2 line(s) of" in prov and "the first: line 1" in prov
    assert "2 line(s) of" in caplog.text


def test_data_info_shows_what_was_not_checked(haart, tmp_path, monkeypatch):
    folder, digests = haart
    _sums(folder, {n: d for n, d in digests.items() if n != "140729-1foamfurpat"})
    monkeypatch.setenv("TOUCHBENCH_DATA_DIR", str(tmp_path))
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    res = CliRunner().invoke(cli, ["data", "info", "haart", "--json"])
    assert res.exit_code == 0, res.output
    info = json.loads(res.output[res.output.index("{"):])
    assert "1 read but not listed, so not checked: 140729-1/140729-1foamfurpat" in info["provenance"]["checksums"]


def _study(tmp_path):
    raw = tmp_path / "icmi15-study2" / "raw"
    raw.mkdir(parents=True)
    sums = {}
    for shift, name in enumerate(("150505-3coverstaticpat", "150505-3nonestaticrub")):  # two different recordings
        text = "".join(",".join(str((10 * line + j + shift) % 1024) for j in range(10)) + "\n" for line in range(5400))
        (raw / f"{name}.csv.gz").write_bytes(gzip.compress(text.encode()))
        sums[f"{name}.csv"] = hashlib.sha256(text.encode()).hexdigest()
    return raw.parent, sums


def test_icmi15_study2_refuses_a_listed_recording_it_lacks_and_says_an_unchecked_folder(tmp_path):
    study, sums = _study(tmp_path)
    ds = load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study)
    assert ds.provenance["checksums"].startswith("not checked: no SHA256SUMS file")
    (study / "SHA256SUMS").write_text("".join(f"{d}  {n}\n" for n, d in sums.items())
                                      + f"{'0' * 64}  150505-3nonestaticstroke.csv\n")
    with pytest.raises(DataError, match="1 file.s. listed in SHA256SUMS are missing from the folder: "
                                        "150505-3nonestaticstroke.csv"):
        load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study)


def test_haart_raw_checksums_option_says_the_unlisted_files(tmp_path):
    study, sums = _study(tmp_path)
    (tmp_path / "sums").write_text(f"{sums['150505-3coverstaticpat.csv']}  150505-3coverstaticpat.csv\n")
    ds = read_haart_raw(study / "raw", pattern=r"150505-(?P<participant>\d+)(?P<cover>cover|none)(?P<motion>static)"
                                              r"(?P<gesture>[a-z]+)", checksums=tmp_path / "sums")
    assert len(ds) == 2
    assert ds.provenance["checksums"].startswith("1 of 2 recordings verified")
    assert "1 read but not listed, so not checked: 150505-3nonestaticrub.csv" in ds.provenance["checksums"]
