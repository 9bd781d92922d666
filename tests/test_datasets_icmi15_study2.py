"""The ``icmi15-study2`` dataset: a fake folder (participant numbers of any kind, a short recording,
the windows, SHA256SUMS) and the real folder, against counts worked out from its files."""

from __future__ import annotations

import gzip
import hashlib
import logging

import pytest

from touchbench.catalog import load_dataset
from touchbench.core.errors import DataError
from touchbench.datasets.icmi15_study2 import load_icmi15_study2


def _write(raw, name: str, frames: int, value=lambda k: k % 1024) -> bytes:
    """A gzipped recording of ``frames`` frames (ten lines of ten values); value k = 10 * line + column."""
    text = "".join(",".join(str(value(10 * line + j)) for j in range(10)) + "\n" for line in range(10 * frames))
    raw.mkdir(parents=True, exist_ok=True)
    (raw / f"{name}.csv.gz").write_bytes(gzip.compress(text.encode()))
    return text.encode()


def _inner(line: int) -> int:
    """Pressure of the inner cell (row 1, column 1) of the frame starting at 0-based ``line``."""
    return 1023 - ((10 * (line + 1) + 1) % 1024)


@pytest.fixture
def study(tmp_path):
    """Participants 3 and 11 (no 1, 2...): 20-s, 10-s and 6-s recordings at 54 Hz."""
    raw = tmp_path / "icmi15-study2" / "raw"
    _write(raw, "150505-3coverstaticpat", 1080)
    _write(raw, "150505-3nonedynamicnotouch", 540, value=lambda k: 5)
    _write(raw, "150505-3coverdynamicrub", 324, value=lambda k: 9)  # 6 s: shorter than any window below
    _write(raw, "150505-11nonestatictickle", 1080, value=lambda k: 7)
    return raw.parent


def test_the_participants_the_folder_holds_with_haarts_window(study, tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="touchbench.datasets"):
        ds = load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study)
    # sorted by file name: 11 before 3; the 6-s recording left out, said in the warning and the provenance
    assert list(ds.meta["capture_id"]) == ["150505-s11-none-static-tickle", "150505-s03-cover-static-pat",
                                           "150505-s03-none-dynamic-notouch"]
    assert list(ds.meta["subject"]) == ["150505-s11", "150505-s03", "150505-s03"]
    assert list(ds.meta["cover"]) == ["none", "cover", "none"] and list(ds.meta["motion"]) == ["static", "static",
                                                                                              "dynamic"]
    assert [c.shape for c in ds.captures] == [(432, 8, 8)] * 3
    assert ds.captures[1][0, 0, 0] == _inner(540)  # frame 55 (1-based) of the 20-s recording cut to 10 s
    assert ds.captures[1][-1, 0, 0] == _inner(4850)  # frame 486
    assert ds.provenance["left_out"] == ["150505-3coverdynamicrub.csv.gz: 6 s, shorter than the 8-s window"]
    assert "1 left out as shorter than the 8-s window" in caplog.text
    assert "2 of 4 recordings cut to their first 10 s" in caplog.text and "--recording" not in caplog.text  # no CLI hint
    assert ds.provenance["participants"] == "2: 3 (3 recordings), 11 (1 recordings)"
    assert ds.provenance["conditions"] == {"cover / dynamic": 1, "cover / static": 1, "none / dynamic": 1,
                                           "none / static": 1}
    assert ds.provenance["lengths"]["10 s (5400 lines)"] == "1: 150505-3nonedynamicnotouch.csv.gz"
    assert "readme" not in ds.provenance  # the folder's README is right: no fixed sentence about it


def test_first_and_middle_windows_leave_out_and_list_the_short_recordings(study, tmp_path):
    first = load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study, window="first:15")
    # 15 s = 810 frames from frame 0 of each 20-s recording; the 10-s and 6-s ones are left out
    assert [c.shape for c in first.captures] == [(810, 8, 8)] * 2
    assert first.captures[1][0, 0, 0] == _inner(0) and first.captures[1][-1, 0, 0] == _inner(8090)
    assert sorted(first.provenance["left_out"]) == ["150505-3coverdynamicrub.csv.gz: 6 s, shorter than the 15-s window",
                                                    "150505-3nonedynamicnotouch.csv.gz: 10 s, shorter than the 15-s window"]
    middle = load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study, window="middle:12")
    # 12 s = 648 frames: of 1080 the first is (1080 - 648) // 2 = 216
    assert middle.captures[1].shape == (648, 8, 8) and middle.captures[1][0, 0, 0] == _inner(2160)
    with pytest.raises(DataError, match="window 'last:3': expected haart, first:SECONDS, middle:SECONDS"):
        load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study, window="last:3")


def test_a_recording_that_does_not_match_sha256sums_is_refused(study, tmp_path):
    good = hashlib.sha256(_write(study / "raw", "150505-3coverstaticpat", 1080)).hexdigest()
    (study / "SHA256SUMS").write_text(f"{good}  150505-3coverstaticpat.csv\n{'0' * 64}  150505-11nonestatictickle.csv\n")
    with pytest.raises(DataError, match=r"150505-11nonestatictickle.csv.gz: content does not match SHA256SUMS"):
        load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study)
    (study / "SHA256SUMS").write_text(f"{good}  ./150505-3coverstaticpat.csv\n")
    assert len(load_icmi15_study2(cache_dir=tmp_path / "c", data_dir=study)) == 3


def test_the_real_study_as_its_folder_holds_it(real_icmi15_study2, tb_cache):
    ds = real_icmi15_study2
    # counted from the folder's 224 files: 8 participants x 2 covers x 2 motions x 7 gestures
    assert len(ds) == 224
    assert ds.meta["subject"].value_counts().to_dict() == {f"150505-s{p:02d}": 28 for p in range(2, 17, 2)}
    counts = ds.meta.groupby(["cover", "motion", "gesture"]).size()
    assert len(counts) == 2 * 2 * 7 and set(counts) == {8}
    assert {c.shape for c in ds.captures} == {(432, 8, 8)}  # HAART's captures: 432 frames of 8 x 8
    assert ds.provenance["lengths"]["10 s (5400 lines)"].startswith("7: ")  # the 10-s recordings, used
    assert ds.provenance["left_out"] == "none"
    assert not set(ds.meta["subject"]) & {f"s{p:02d}" for p in range(1, 11)}  # never one of HAART's people
    longer = load_dataset("icmi15-study2", cache_dir=tb_cache, window="first:20")
    assert len(longer) == 224 - 7 and len(longer.provenance["left_out"]) == 7
    assert {c.shape for c in longer.captures} == {(1080, 8, 8)}
