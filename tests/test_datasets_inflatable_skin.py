"""The ``inflatable-skin`` dataset: small recordings written here (segments, sessions by timestamp,
SHA256SUMS, a frame of another shape or value) and the real folder, against the counts of its
README and the files themselves read with ``json``."""

from __future__ import annotations

import gzip
import hashlib
import json

import numpy as np
import pytest
from click.testing import CliRunner

from touchbench.catalog import load_dataset
from touchbench.cli.main import cli
from touchbench.core.errors import DataError
from touchbench.datasets.inflatable_skin import load_inflatable_skin
from touchbench.streams.timeline import recorded_streams


def _grid(k: int, shape=(2, 3)) -> list[list[float]]:
    """Frame ``k``'s grid: cell (r, c) = 1.5 * (k + r * W + c), a multiple of 1.5 as the source stores."""
    return [[1.5 * (k + r * shape[1] + c) for c in range(shape[1])] for r in range(shape[0])]


def _write(raw, name: str, labels: list[str], own: str = "Tap", grids=None, gz: bool = True) -> bytes:
    """A recording ``<name>_annotated.json[.gz]`` with one frame per label; its original bytes."""
    grids = grids or [_grid(k) for k in range(len(labels))]
    doc = {"id": name, "label": own, "timestamp": name.rsplit("_", 1)[1],
           "frames": [{"frame_index": k, "label": g, "data": grids[k]} for k, g in enumerate(labels)]}
    data = json.dumps(doc).encode()
    raw.mkdir(parents=True, exist_ok=True)
    path = raw / f"{name}_annotated.json{'.gz' if gz else ''}"
    path.write_bytes(gzip.compress(data) if gz else data)
    return data


def _sums(folder, contents: dict[str, bytes]) -> None:
    (folder / "SHA256SUMS").write_text("".join(f"{hashlib.sha256(b).hexdigest()}  {n}_annotated.json\n"
                                               for n, b in contents.items()))


@pytest.fixture
def skin(tmp_path):
    """Two recordings of one sitting, SHA256SUMS listing both (one plain, one gzipped)."""
    folder = tmp_path / "inflatable-skin"
    contents = {"Unknown_20250101100000": _write(folder / "raw", "Unknown_20250101100000",
                                                 ["None", "None", "Tap", "Tap", "None", "Tap"], own="Unknown"),
                "hug_20250101101500": _write(folder / "raw", "hug_20250101101500", ["hug", "hug", "None"], own="hug",
                                             gz=False)}
    _sums(folder, contents)
    return folder


def test_each_run_of_one_label_is_a_capture_with_its_recording_and_first_frame(skin, tmp_path):
    ds = load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=skin)
    # runs of Unknown_...: None x2 (0), Tap x2 (2), None (4), Tap (5); of hug_...: hug x2 (0), None (2)
    assert list(ds.meta["capture_id"]) == ["Unknown_20250101100000@0", "Unknown_20250101100000@2",
                                           "Unknown_20250101100000@4", "Unknown_20250101100000@5",
                                           "hug_20250101101500@0", "hug_20250101101500@2"]
    assert list(ds.meta["gesture"]) == ["idle", "Tap", "idle", "Tap", "hug", "idle"]
    assert list(ds.meta["start_frame"]) == [0, 2, 4, 5, 0, 2]
    assert list(ds.meta["recording_gesture"]) == ["Unknown"] * 4 + ["hug"] * 2
    assert list(ds.meta["recording"]) == ["Unknown_20250101100000"] * 4 + ["hug_20250101101500"] * 2
    assert list(ds.n_frames) == [2, 2, 1, 1, 2, 1]
    assert set(ds.meta["session"]) == set(ds.meta["subject"]) == {"2025-01-01-1"}  # 15 minutes apart
    assert list(ds.meta.columns) == ["capture_id", "subject", "session", "recording", "recording_gesture",
                                     "start_frame", "gesture"]
    assert ds.sensor.grid == (2, 3) and ds.sensor.frame_rate == 10.0 and ds.sensor.value_range == (0.0, 255.0)
    assert ds.sensor.name == "inflatable-skin" and ds.sensor.higher_is_more_pressure
    # frame 2 of Unknown_..., cell (1, 2): 1.5 * (2 + 1 * 3 + 2) = 10.5, kept exactly (not rounded)
    assert ds.captures[1][0, 1, 2] == 10.5 and ds.captures[1].dtype == np.float32
    assert "ASSUMPTION" in ds.provenance["frame rate"] and "leave one session out" in ds.provenance["subjects"]
    assert "mdethmers/Social-Touch-Research, commit 0ea7cf5" in ds.provenance["source"]


def test_data_info_says_the_frame_rate_is_assumed_and_what_the_folder_holds(skin, tmp_path):
    r = CliRunner().invoke(cli, ["data", "info", "inflatable-skin", "--data-dir", str(skin), "--cache-dir",
                                 str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    assert "10 Hz is an ASSUMPTION: the files carry no frame times" in r.output
    assert "2025-01-01-1: 2 recordings: Unknown_20250101100000, hug_20250101101500" in r.output
    # frames per label: idle 3 + 1, Tap 3, hug 2; segments: 4 in the first recording, 2 in the other
    assert "  idle: 4\n  Tap: 3\n  hug: 2" in r.output
    assert "segments      6 (runs of one label; 2..4 per recording)" in r.output
    assert "Unknown_20250101100000: 6 frames, 4 segments" in r.output
    assert "2 of 2 recordings verified against" in r.output


def test_sessions_split_by_day_and_by_more_than_an_hour_between_recordings(tmp_path):
    folder = tmp_path / "skin"
    names = ["Grab_20250101100000",   # day 1, first sitting
             "Tap_20250101110000",    # 60 min later: not more than 60, same sitting
             "Punch_20250101120100",  # 61 min later: second sitting
             "hug_20250101235500",    # 11 h later: third sitting
             "Grab_20250102000500",   # 10 min later but the next day: its first sitting
             "Tap_20250102010600"]    # 61 min later: the next day's second sitting
    for n in reversed(names):  # written in another order than time: sorted by the names' timestamps
        _write(folder / "raw", n, ["None", n.split("_")[0]])
    ds = load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=folder)
    by_rec = dict(zip(ds.meta["recording"], ds.meta["session"]))
    assert by_rec == {names[0]: "2025-01-01-1", names[1]: "2025-01-01-1", names[2]: "2025-01-01-2",
                      names[3]: "2025-01-01-3", names[4]: "2025-01-02-1", names[5]: "2025-01-02-2"}
    assert ds.provenance["checksums"].startswith("not checked: no SHA256SUMS file")


def test_a_recording_that_does_not_match_sha256sums_is_refused_naming_it(skin, tmp_path):
    _write(skin / "raw", "Unknown_20250101100000", ["None", "None", "Tap", "Tap", "None", "None"], own="Unknown")
    with pytest.raises(DataError, match=r"Unknown_20250101100000_annotated.json.gz: content does not match SHA256SUMS"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=skin)


def test_a_listed_recording_that_is_absent_is_refused_and_one_not_listed_is_said(skin, tmp_path):
    (skin / "raw" / "hug_20250101101500_annotated.json").unlink()
    with pytest.raises(DataError, match=r"1 file\(s\) listed in SHA256SUMS are missing from the folder: "
                                        r"hug_20250101101500_annotated.json"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=skin)
    _write(skin / "raw", "hug_20250101101500", ["hug", "hug", "None"], own="hug", gz=False)
    _write(skin / "raw", "Tap_20250101102000", ["Tap"])
    ds = load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=skin)
    assert "Tap_20250101102000" in set(ds.meta["recording"])
    assert ("2 of 3 recordings verified against" in ds.provenance["checksums"]
            and "1 read but not listed, so not checked: Tap_20250101102000_annotated.json" in ds.provenance["checksums"])


def test_a_frame_of_another_shape_or_value_is_refused_naming_the_file_and_frame(tmp_path):
    folder = tmp_path / "skin"
    grids = [_grid(0), _grid(1), _grid(2, shape=(3, 2))]
    _write(folder / "raw", "Tap_20250101100000", ["Tap"] * 3, grids=grids)
    with pytest.raises(DataError, match=r"Tap_20250101100000_annotated.json.gz: frame 2: data of shape 3 x 2, "
                                        r"not the 2 x 3 of the recording's first frame"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=folder)
    grids[2] = _grid(2)
    grids[2][1][0] = 256.0
    _write(folder / "raw", "Tap_20250101100000", ["Tap"] * 3, grids=grids)
    with pytest.raises(DataError, match=r"_annotated.json.gz: frame 2: value 256 at row 1, column 0 is outside "
                                        r"0..255"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=folder)
    grids[2] = [[1.5, 3.0], [4.5]]  # rows of unequal length
    _write(folder / "raw", "Tap_20250101100000", ["Tap"] * 3, grids=grids)
    with pytest.raises(DataError, match=r"frame 2: data is not a grid of numbers"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=folder)


def test_a_grid_other_than_the_first_recordings_is_refused(tmp_path):
    folder = tmp_path / "skin"
    _write(folder / "raw", "Tap_20250101100000", ["Tap"])
    _write(folder / "raw", "Tap_20250101100100", ["Tap"], grids=[_grid(0, shape=(3, 2))])
    with pytest.raises(DataError, match=r"Tap_20250101100100_annotated.json.gz: frames of 3 x 2, not the 2 x 3 of "
                                        r"Tap_20250101100000_annotated.json.gz"):
        load_inflatable_skin(cache_dir=tmp_path / "c", data_dir=folder)


# ---------------------------------------------------------------- the real recordings
#: the data folder's README: frames per label (None -> idle), sessions with their recordings
README_FRAMES = {"idle": 1441, "Grab": 581, "Stroke": 604, "Squeez": 463, "Tickle": 371, "Tap": 366, "hug": 253,
                 "Punch": 244}
README_SESSIONS = {"2025-05-21-1": 4, "2025-05-28-1": 7, "2025-06-03-1": 5}


@pytest.fixture(scope="module")
def real_skin(real_inflatable_skin_dir, tb_cache):
    return load_dataset("inflatable-skin", cache_dir=tb_cache)


def _files(folder) -> dict[str, dict]:
    """Every recording of the real folder, read with json: name -> the JSON object."""
    return {p.name.removesuffix("_annotated.json.gz"): json.loads(gzip.decompress(p.read_bytes()))
            for p in sorted((folder / "raw").glob("*_annotated.json.gz"))}


def test_the_real_recordings_have_the_readme_counts(real_skin):
    ds = real_skin
    n = ds.n_frames
    assert ds.meta["recording"].nunique() == 16 and int(n.sum()) == 4323
    assert {g: int(n[(ds.meta["gesture"] == g).to_numpy()].sum()) for g in README_FRAMES} == README_FRAMES
    assert set(ds.meta["gesture"]) == set(README_FRAMES)
    assert ds.meta.groupby("session")["recording"].nunique().to_dict() == README_SESSIONS
    assert (ds.meta["subject"] == ds.meta["session"]).all()
    per_rec = ds.meta.assign(n=n).groupby("recording")["n"].agg(["sum", "size"])
    assert per_rec["sum"].min() == 126 and per_rec["sum"].max() == 448  # recording lengths
    assert per_rec["size"].min() == 3 and per_rec["size"].max() == 55  # runs of one label per recording
    assert ds.sensor.grid == (19, 27) and ds.sensor.frame_rate == 10.0 and ds.sensor.value_range == (0.0, 255.0)
    assert "Grab_20250521150749@0" in set(ds.meta["capture_id"])
    assert set(ds.meta.loc[ds.meta["recording"].str.startswith("Unknown_"), "recording_gesture"]) == {"Unknown"}


def test_a_recordings_segments_put_back_together_are_its_file(real_skin, real_inflatable_skin_dir):
    ds = real_skin
    for name, doc in _files(real_inflatable_skin_dir).items():
        rows = ds.meta.index[ds.meta["recording"] == name]
        order = rows[np.argsort(ds.meta.loc[rows, "start_frame"].to_numpy())]
        frames = np.concatenate([ds.captures[i] for i in order])
        np.testing.assert_array_equal(frames, np.array([f["data"] for f in doc["frames"]], dtype=np.float64))
        truth = np.concatenate([[ds.meta.at[i, "gesture"]] * len(ds.captures[i]) for i in order])
        assert list(truth) == ["idle" if f["label"] == "None" else f["label"] for f in doc["frames"]], name
        assert set(ds.meta.loc[rows, "recording_gesture"]) == {doc["label"]}


def test_recorded_streams_are_the_recordings_without_a_conversion(real_skin, real_inflatable_skin_dir):
    ds = real_skin
    streams = recorded_streams(ds.meta, ds.n_frames, np.arange(len(ds)))
    lengths = {name: len(doc["frames"]) for name, doc in _files(real_inflatable_skin_dir).items()}
    assert {s.name: s.n_frames for s in streams} == lengths
    assert all(s.source == "recorded" and s.subject == s.session for s in streams)
    assert {s.session for s in streams} == set(README_SESSIONS)
