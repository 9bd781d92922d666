"""The ``haart-raw`` format from the command line: a folder of another study's recordings in the
HAART organisers' raw format.

Expected values: real HAART recordings copied and renamed as another study and participant, their
frames computed here with numpy from the text (ten lines a frame, inner 8 x 8, 1023 - raw) and
compared with the registered ``haart`` / ``haart-challenge`` readers; small recordings written by
hand for the edge cases.
"""

from __future__ import annotations

import gzip
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.errors import DataError, TouchbenchError
from touchbench.datasets.formats import FORMATS
from touchbench.datasets.model import TouchDataset

SOURCES = [("140729-3", "foamfurpat"), ("140729-3", "foamfurstroke"), ("140729-10", "curvefurtickle")]


def _by_hand(path) -> np.ndarray:
    """The corrected window computed from the text: frames 55..486 (1-based), rows/cols 2..9, 1023 - v."""
    raw = np.loadtxt(gzip.open(path, "rt"), delimiter=",", dtype=np.int64)
    frames = raw[:5400].reshape(540, 10, 10)
    return 1023 - frames[54:486, 1:9, 1:9]


@pytest.fixture
def study(real_haart_dir, tmp_path):
    """Three HAART recordings renamed as study 150301's participants 21 and 22."""
    out = tmp_path / "study"
    for i, (folder, stem) in enumerate(SOURCES):
        p = 21 + (i == 2)
        (out / f"150301-{p}").mkdir(parents=True, exist_ok=True)
        shutil.copy(real_haart_dir / "raw" / folder / f"{folder}{stem}.csv.gz",
                    out / f"150301-{p}" / f"150301-{p}{stem}.csv.gz")
    return out


def convert(*args):
    return CliRunner().invoke(cli, ["data", "convert", *map(str, args)])


def test_another_study_from_the_command_line(study, real_haart_dir, real_haart, tmp_path):
    r = convert(study, tmp_path / "study.parquet", "--format", "haart-raw")
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "study.parquet")
    assert list(ds.meta["capture_id"]) == ["150301-s21-foam-fur-pat", "150301-s21-foam-fur-stroke",
                                           "150301-s22-curve-fur-tickle"]
    assert list(ds.meta["subject"]) == ["150301-s21", "150301-s21", "150301-s22"]
    assert list(ds.meta["study"]) == ["150301"] * 3 and list(ds.meta["gesture"]) == ["pat", "stroke", "tickle"]
    assert list(ds.meta["substrate"]) == ["foam", "foam", "curve"] and list(ds.meta["participant"]) == ["21", "21", "22"]
    assert ds.sensor.grid == (8, 8) and ds.sensor.frame_rate == 54.0 and ds.sensor.value_range == (0.0, 1023.0)
    ids = list(real_haart.meta["capture_id"])
    for i, (folder, stem) in enumerate(SOURCES):
        want = _by_hand(real_haart_dir / "raw" / folder / f"{folder}{stem}.csv.gz")
        np.testing.assert_array_equal(ds.captures[i], want)
        subject = f"s{int(folder.split('-')[1]):02d}"
        same = ids.index(real_haart_id(subject, stem))
        np.testing.assert_array_equal(ds.captures[i], real_haart.captures[same])


def real_haart_id(subject: str, stem: str) -> str:
    for sub in ("curve", "foam", "none"):
        if stem.startswith(sub):
            rest = stem[len(sub):]
            for cover in ("fur", "long", "none", "short"):
                if rest.startswith(cover):
                    return f"{subject}-{sub}-{cover}-{rest[len(cover):]}"
    raise ValueError(stem)


def test_windows(study, real_haart_challenge, tmp_path):
    fmt = FORMATS.get("haart-raw")
    ch = fmt.read(study, recording_window="challenge")
    ref = dict(zip(real_haart_challenge.meta["capture_id"], real_haart_challenge.captures))
    np.testing.assert_array_equal(ch.captures[0], ref["s03-foam-fur-pat"])  # the organisers' window, bug included
    whole = fmt.read(study, recording_window="whole")
    assert [c.shape for c in whole.captures] == [(540, 8, 8)] * 3
    mid = fmt.read(study, recording_window="middle:2")  # 108 frames in the middle of 540: 216..323 (0-based)
    np.testing.assert_array_equal(mid.captures[0], whole.captures[0][216:324])
    assert "frames 217..324 (1-based)" in mid.provenance["window"]
    with pytest.raises(TouchbenchError, match=r"a 10-s recording \(540 frames\) is shorter than the 12-s window "
                                              r"\(--recording-window middle:12 asks for 648 frames\)"):
        fmt.read(study, recording_window="middle:12")
    with pytest.raises(TouchbenchError, match="10-s recordings at 54 Hz only"):
        fmt.read(study, recording_window="challenge", recording_seconds=12.0)
    r = convert(study, tmp_path / "x.parquet", "--format", "haart-raw", "--recording-window", "first")
    assert r.exit_code == 2 and "expected middle, middle:SECONDS, challenge or whole" in r.output


def _recording(path, lines: int, value=lambda k: 1000 - k % 7):
    rows = [",".join(str(value(k * 10 + j)) for j in range(10)) for k in range(lines)]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(rows) + "\n")


def test_longer_and_shorter_recordings_as_haart_long_files(tmp_path):
    folder = tmp_path / "s"
    _recording(folder / "7-1nonenonepat.csv", 5600)  # 20 lines more than 10 s: cut to 5400
    _recording(folder / "7-1nonenonerub.csv", 5400, value=lambda k: k % 1024)
    ds = FORMATS.get("haart-raw").read(folder)
    assert ds.provenance["cut"] == ["7-1nonenonepat.csv: 5600 lines, the first 5400 used"]
    assert [c.shape for c in ds.captures] == [(432, 8, 8)] * 2
    # value k = 10 * line + column (0-based): the inner cell (row 1, col 1) of frame 54 is line 541, column 1
    assert ds.captures[1][0, 0, 0] == 1023 - (5411 % 1024)
    _recording(folder / "7-2nonenonepat.csv", 5000)
    with pytest.raises(DataError, match=r"7-2nonenonepat.csv:5001: truncated recording: 5000 lines, a recording "
                                        r"has 5400 \(540 frames of 10 lines\)"):
        FORMATS.get("haart-raw").read(folder)
    whole = FORMATS.get("haart-raw").read(folder, recording_window="whole")
    assert sorted(c.shape[0] for c in whole.captures) == [500, 540, 560]  # every frame, whatever the length
    _recording(folder / "7-3nonenonepat.csv", 75)
    with pytest.raises(DataError, match=r"7-3nonenonepat.csv:71: 75 lines is not a whole number of 10-line frames"):
        FORMATS.get("haart-raw").read(folder, recording_window="whole")


def test_names_patterns_and_placeholders(tmp_path):
    folder = tmp_path / "s"
    _recording(folder / "p1" / "9-1nonefurpat.csv", 5400)
    _recording(folder / "p1" / "9-1nonefurrub.csv", 5400)  # byte-identical: a placeholder copy
    (folder / "p1" / "note.txt").write_text("nonefurrub is nonefurpat\n")
    ds = FORMATS.get("haart-raw").read(folder)
    assert list(ds.meta["capture_id"]) == ["9-s01-none-fur-pat"]
    assert ds.provenance["placeholders"][0]["capture_id"] == "9-s01-none-fur-rub"
    _recording(folder / "p1" / "session2-patting.csv", 5400, value=lambda k: 3)
    r = convert(folder, tmp_path / "x.parquet", "--format", "haart-raw")
    assert r.exit_code == 3 and "the file name 'session2-patting' does not match the recording pattern" in r.output
    assert "give --pattern" in r.output
    # a study of its own naming: participant and gesture, any other group a metadata column
    other = tmp_path / "o"
    _recording(other / "P04_stroke_s1.csv", 5400)
    _recording(other / "P04_stroke_s2.csv", 5400, value=lambda k: 5)
    r = convert(other, tmp_path / "o.parquet", "--format", "haart-raw", "--pattern",
                r"P(?P<participant>\d+)_(?P<gesture>[a-z]+)_s(?P<session>\d)")
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "o.parquet")
    assert list(ds.meta["capture_id"]) == ["s04-stroke-1", "s04-stroke-2"] and list(ds.meta["session"]) == ["1", "2"]
    r = convert(other, tmp_path / "o.parquet", "--format", "haart-raw", "--pattern", r"P(?P<who>\d+)_(?P<gesture>.+)")
    assert r.exit_code == 3 and "--pattern needs the named group(s) (?P<participant>...)" in r.output
    r = convert(tmp_path / "o" / "P04_stroke_s1.csv", tmp_path / "o.parquet", "--format", "haart-raw")
    assert r.exit_code == 3 and "the haart-raw format reads a folder of recordings" in r.output


def _inner(line: int) -> int:
    """Pressure of the inner cell (row 1, column 1) of the frame starting at 0-based ``line``, for
    ``_recording(..., value=lambda k: k % 1024)``: value k = 10 * line + column."""
    return 1023 - ((10 * (line + 1) + 1) % 1024)


def _lengths_folder(tmp_path):
    """Recordings of 10, 20 and 40 s at 54 Hz (540, 1080 and 2160 frames of ten lines)."""
    folder = tmp_path / "long"
    for gesture, frames in (("pat", 540), ("rub", 1080), ("tickle", 2160)):
        _recording(folder / f"8-1nonenone{gesture}.csv", 10 * frames, value=lambda k: k % 1024)
    return folder


def test_middle_seconds_is_the_middle_of_each_recording_whatever_its_length(tmp_path):
    folder = _lengths_folder(tmp_path)
    (folder / "8-1nonenonepat.csv").unlink()  # 20 and 40 s
    ds = FORMATS.get("haart-raw").read(folder, recording_window="middle:12")
    # 12 s = 648 frames: of 1080 the first is (1080 - 648) // 2 = 216, of 2160 it is (2160 - 648) // 2 = 756
    assert [c.shape for c in ds.captures] == [(648, 8, 8)] * 2
    assert ds.captures[0][0, 0, 0] == _inner(216 * 10) and ds.captures[1][0, 0, 0] == _inner(756 * 10)
    assert ds.captures[1][-1, 0, 0] == _inner((756 + 647) * 10)
    assert ds.provenance["cut"] == "none"


def test_recording_seconds_reads_a_folder_of_mixed_lengths_and_says_what_it_did(tmp_path):
    folder = _lengths_folder(tmp_path)
    r = convert(folder, tmp_path / "l.parquet", "--format", "haart-raw", "--recording-seconds", "20")
    assert r.exit_code == 0, r.output
    assert "1 of 3 recordings cut to their first 20 s (median length 40 s)" in r.output
    assert "1 of 3 recordings shorter than 20 s, used whole (median length 10 s)" in r.output
    ds = TouchDataset.from_parquet(tmp_path / "l.parquet")
    # the middle 8 s (432 frames): of 540 from frame 54, of 1080 (the 40-s one cut to 20 s too) from 324
    assert [c.shape for c in ds.captures] == [(432, 8, 8)] * 3
    assert [int(c[0, 0, 0]) for c in ds.captures] == [_inner(540), _inner(3240), _inner(3240)]
    # by default (HAART's protocol) the two long ones are cut to 10 s, and the conversion says so
    r = convert(folder, tmp_path / "d.parquet", "--format", "haart-raw")
    assert r.exit_code == 0 and "2 of 3 recordings cut to their first 10 s (median length 30 s)" in r.output
    info = CliRunner().invoke(cli, ["data", "info", str(tmp_path / "d.parquet")])
    assert info.exit_code == 0, info.output
    assert "recordings    3 read: 2 of 3 recordings cut to their first 10 s" in info.output
    assert "  8-1nonenonerub.csv: 10800 lines, the first 5400 used" in info.output
    assert "['" not in info.output and "placeholders  none" in info.output


def test_the_challenge_study_keeps_the_registered_haart_ids(tmp_path):
    folder = tmp_path / "ids"
    _recording(folder / "140729-4nonenonepat.csv", 5400)
    _recording(folder / "150301-4nonenonepat.csv", 5400, value=lambda k: 7)
    ds = FORMATS.get("haart-raw").read(folder)
    assert list(ds.meta["subject"]) == ["s04", "150301-s04"]  # the challenge's participant 4 as haart names them
    assert list(ds.meta["capture_id"]) == ["s04-none-none-pat", "150301-s04-none-none-pat"]


def test_haart_files_as_named_give_the_haart_subjects_and_captures(real_haart_dir, real_haart, tmp_path):
    src = real_haart_dir / "raw" / "140729-4"
    for f in sorted(src.glob("140729-4foam*"))[:2]:
        shutil.copy(f, tmp_path / f.name)
    ds = FORMATS.get("haart-raw").read(tmp_path)
    ref = dict(zip(real_haart.meta["capture_id"], real_haart.captures))
    subjects = dict(zip(real_haart.meta["capture_id"], real_haart.meta["subject"]))
    assert len(ds) == 2
    for cid, subject, cap in zip(ds.meta["capture_id"], ds.meta["subject"], ds.captures):
        assert subject == subjects[cid] == "s04"
        np.testing.assert_array_equal(cap, ref[cid])


def test_an_empty_recording_is_called_empty(tmp_path):
    import warnings

    (tmp_path / "e").mkdir()
    (tmp_path / "e" / "7-1nonenonepat.csv").write_text("\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(DataError, match=r"7-1nonenonepat.csv: empty recording"):
            FORMATS.get("haart-raw").read(tmp_path / "e")


def test_a_frame_rate_of_zero_is_refused_not_ignored(tmp_path):
    _recording(tmp_path / "z" / "7-1nonenonepat.csv", 5400)
    r = convert(tmp_path / "z", tmp_path / "z.parquet", "--format", "haart-raw", "--frame-rate", "0")
    assert r.exit_code == 2 and "--frame-rate must be a finite number of frames per second above 0" in r.output
    for rate in (0.0, float("nan"), float("inf")):
        with pytest.raises(TouchbenchError, match="--frame-rate must be"):
            FORMATS.get("haart-raw").read(tmp_path / "z", frame_rate=rate)
    assert not (tmp_path / "z.parquet").exists()


def test_short_recordings_leave_out_lists_what_a_window_refuses(tmp_path):
    folder = _lengths_folder(tmp_path)  # 10, 20 and 40 s
    r = convert(folder, tmp_path / "m.parquet", "--format", "haart-raw", "--recording-window", "middle:15")
    assert r.exit_code == 3 and "choose a shorter window, or --short-recordings leave-out" in r.output
    r = convert(folder, tmp_path / "m.parquet", "--format", "haart-raw", "--recording-window", "middle:15",
                "--short-recordings", "leave-out")
    assert r.exit_code == 0, r.output
    assert "1 left out as shorter than the 15-s window" in r.output
    ds = TouchDataset.from_parquet(tmp_path / "m.parquet")
    assert [c.shape for c in ds.captures] == [(810, 8, 8)] * 2  # 15 s at 54 Hz of the 20- and 40-s ones
    assert ds.provenance["left_out"] == ["8-1nonenonepat.csv: 10 s, shorter than the 15-s window"]
    assert ds.provenance["lengths"] == {"10 s (5400 lines)": "1: 8-1nonenonepat.csv",
                                        "20 s (10800 lines)": "1: 8-1nonenonerub.csv",
                                        "40 s (21600 lines)": "1: 8-1nonenonetickle.csv"}
    r = convert(folder, tmp_path / "m.parquet", "--format", "haart-raw", "--short-recordings", "skip")
    assert r.exit_code == 2 and "--short-recordings must be refuse or leave-out, got 'skip'" in r.output
