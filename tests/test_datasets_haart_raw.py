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
    with pytest.raises(TouchbenchError, match="asks for 648 frames of a 10-s recording of 540"):
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
