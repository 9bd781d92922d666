"""SocialTouch (../shared/data/socialtouch): counts, values and time stamps as
the files hold them, the 12 Hz resampling rule, bad input, and per-capture
time stamps in the data model.

Expected values on the real data are computed here with pandas straight from
the gzipped CSVs (groupby over participant, gesture and repetition) and with
``numpy.interp`` for the resampling, not by the reader under test; the small
files' expected values are worked out by hand.
"""

from __future__ import annotations

import gzip
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.errors import DataError
from touchbench.datasets.model import DatasetChangedWarning, SensorSpec, TouchDataset
from touchbench.datasets.socialtouch import build_recorded, build_resampled

RATE = 12.0

# one worker of pytest-xdist runs them all: the module's fixtures read every raw file once
pytestmark = pytest.mark.xdist_group("socialtouch")


@pytest.fixture(scope="module")
def frames_table(real_socialtouch_dir) -> pd.DataFrame:
    """Every row of every raw file, read by pandas alone (its pyarrow parser: the same table, sooner)."""
    parts = [pd.read_csv(f, engine="pyarrow") for f in sorted((real_socialtouch_dir / "raw").glob("*.csv.gz"))]
    return pd.concat(parts, ignore_index=True)


@pytest.fixture(scope="module")
def names(real_socialtouch_dir) -> dict[int, str]:
    g = pd.read_csv(real_socialtouch_dir / "GesturesRated.csv")
    return dict(zip(g["id"], g["gesture_name"]))


def _some_groups(frames_table: pd.DataFrame, start: int, step: int) -> list[tuple[tuple, pd.DataFrame]]:
    """``list(groupby(participant, gesture, repetition))[start::step]`` without building every group's frame."""
    indices = frames_table.groupby(["participantID", "gesture", "repetition"]).indices
    return [(k, frames_table.iloc[indices[k]]) for k in sorted(indices)[start::step]]


def _by_key(ds: TouchDataset) -> dict[tuple[str, str, int], int]:
    m = ds.meta
    return {(s, g, int(r)): i for i, (s, g, r) in enumerate(zip(m["subject"], m["gesture"], m["repetition"]))}


# ------------------------------------------------------------------ real data
@pytest.mark.realdata
@pytest.mark.parametrize("which", ["real_socialtouch", "real_socialtouch_recorded"])
def test_counts_grid_and_values(which, request, frames_table, names):
    ds = request.getfixturevalue(which)
    groups = frames_table.groupby(["participantID", "gesture", "repetition"])
    assert groups.ngroups == 2493 and len(ds) == 2493
    assert ds.meta["subject"].nunique() == 3 == frames_table["participantID"].nunique()
    assert ds.meta["gesture"].nunique() == 32 == len(names)
    assert set(ds.meta["gesture"]) == set(names.values())
    assert ds.sensor.grid == (19, 24) and ds.sensor.value_range == (0.0, 255.0)
    assert all(c.shape[1:] == (19, 24) and c.dtype == np.uint8 for c in ds.captures)
    expected = {(f"p{p}", names[g], r) for p, g, r in groups.groups}
    assert set(_by_key(ds)) == expected
    assert min(int(c.min()) for c in ds.captures) >= 0 and max(int(c.max()) for c in ds.captures) <= 255


@pytest.mark.realdata
def test_recorded_frames_and_times_are_the_files(real_socialtouch_recorded, frames_table, names):
    ds = real_socialtouch_recorded
    index = _by_key(ds)
    pixels = [f"pixel{i}" for i in range(456)]
    groups = frames_table.groupby(["participantID", "gesture", "repetition"])
    assert sorted(ds.n_frames.tolist()) == sorted(groups.size().tolist())
    assert ds.n_frames.min() == 3 and ds.n_frames.max() == 227
    for (p, g, r), rows in _some_groups(frames_table, 0, 97):  # 26 captures spread over the files
        i = index[(f"p{p}", names[g], r)]
        assert ds.captures[i].tolist() == rows[pixels].to_numpy().reshape(-1, 19, 24).tolist()
        assert list(ds.meta["time_ms"][i]) == rows["time"].tolist()
    # the README's step statistics (median 83 ms, 95th percentile 165 ms), from the files
    steps = groups["time"].diff().dropna().to_numpy()  # each capture's steps, in its rows' order
    assert (np.median(steps), np.percentile(steps, 95)) == (83.0, 165.0)
    assert ds.info()["time_steps_ms"]["median"] == 83.0 and ds.info()["time_steps_ms"]["p95"] == 165.0


@pytest.mark.realdata
def test_resampled_is_numpy_interp_on_a_12_hz_grid(real_socialtouch, frames_table, names):
    ds = real_socialtouch
    index = _by_key(ds)
    pixels = [f"pixel{i}" for i in range(456)]
    for (p, g, r), rows in _some_groups(frames_table, 5, 101):
        i = index[(f"p{p}", names[g], r)]
        t = rows["time"].to_numpy()
        n = t[-1] * 12 // 1000 + 1  # integer arithmetic: every k with k * 1000 / 12 <= last time
        grid = np.arange(n) * 1000 / 12
        x = rows[pixels].to_numpy().astype(float)
        want = np.stack([np.interp(grid, t, x[:, c]) for c in range(456)], axis=1)
        # halves up: an exact value's denominator is at most 3 * 417 (the step in thirds of a ms), so a value
        # that is not a half is at least 1 / 2502 away from one, and a half is within float error of it
        tie = np.abs(want - np.floor(want) - 0.5) < 1e-6
        assert ds.captures[i].shape == (n, 19, 24)
        assert np.array_equal(ds.captures[i].reshape(n, 456), np.where(tie, np.floor(want) + 1, np.rint(want)))
        assert np.allclose(ds.meta["time_ms"][i], grid)
        assert list(ds.meta["recorded_time_ms"][i]) == t.tolist()
        assert ds.meta["recorded_frames"][i] == len(rows)
    assert ds.info()["time_steps_ms"]["median"] == pytest.approx(1000 / 12)


@pytest.mark.realdata
def test_data_info_on_the_command_line(real_socialtouch_dir, tb_cache):
    r = CliRunner().invoke(cli, ["data", "info", "socialtouch-recorded", "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    for line in ("captures      2493", "subjects      3", "gestures      32", "19 x 24 at 12 Hz",
                 "frames        3..227 per capture (median 29)", "time steps    median 83 ms, 95th percentile 165 ms"):
        assert line in r.output
    r = CliRunner().invoke(cli, ["data", "info", "socialtouch", "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    assert "captures      2493" in r.output and "resampled to a fixed 12 Hz" in r.output
    assert "time steps median 83 ms, 95th percentile 165 ms" in r.output  # the recorded ones, in the provenance


# ------------------------------------------------------------------ small files, by hand
HEADER = "participantID,gesture,repetition,frameID,time," + ",".join(f"pixel{i}" for i in range(456))


def _row(p: int, g: int, rep: int, fid: int, t: int, cells: dict[int, int]) -> str:
    v = [0] * 456
    for k, x in cells.items():
        v[k] = x
    return ",".join(map(str, [p, g, rep, fid, t, *v]))


def _folder(tmp_path: Path, rows: list[str], name: str = "touch_p0_g1-20_4_16h_00m_00s.csv") -> Path:
    base = tmp_path / "socialtouch"
    (base / "raw").mkdir(parents=True)
    (base / "GesturesRated.csv").write_text("id,gesture_name,Adoration\n0,contact_one_hand,0.1\n1,poke_short,0.2\n")
    (base / "raw" / (name + ".gz")).write_bytes(gzip.compress(("\r\n".join([HEADER + ",", *rows]) + "\r\n").encode()))
    return base


# repetition 0: times 0, 80, 250 ms; cell 0 = the time itself, cell 1 steps 0 -> 100 -> 100,
# cell 455 goes 10 -> 20 -> 190. Repetition 1: two frames 0 and 90 ms. Repetition 2: cell 7 is
# 0, 0, 3 at 0, 50, 250 ms, so at 83.33 ms it is exactly 3 * 33.33 / 200 = 0.5.
SMALL = [
    _row(0, 1, 0, 0, 0, {0: 0, 1: 0, 455: 10}),
    _row(0, 1, 0, 1, 80, {0: 80, 1: 100, 455: 20}),
    _row(0, 1, 0, 2, 250, {0: 250, 1: 100, 455: 190}),
    _row(0, 1, 1, 0, 0, {5: 7}),
    _row(0, 1, 1, 1, 90, {5: 9}),
    _row(0, 1, 2, 0, 0, {7: 0}),
    _row(0, 1, 2, 1, 50, {7: 0}),
    _row(0, 1, 2, 2, 250, {7: 3}),
]


def test_small_file_by_hand(tmp_path):
    base = _folder(tmp_path, SMALL)
    rec = build_recorded(base)
    assert rec.meta[["capture_id", "subject", "gesture", "repetition"]].values.tolist()[:2] == [
        ["p0-poke_short-r00", "p0", "poke_short", 0], ["p0-poke_short-r01", "p0", "poke_short", 1]]
    assert [list(t) for t in rec.meta["time_ms"]] == [[0, 80, 250], [0, 90], [0, 50, 250]]
    assert rec.captures[0][:, 0, 0].tolist() == [0, 80, 250] and rec.captures[0][:, 18, 23].tolist() == [10, 20, 190]
    res = build_resampled(base)
    # 250 ms -> 250 * 12 / 1000 = 3 steps: frames at 0, 83.33, 166.67, 250 ms
    a = res.captures[0]
    assert a.shape == (4, 19, 24)
    assert a[:, 0, 0].tolist() == [0, 83, 167, 250]  # v = t: 83.33 -> 83, 166.67 -> 167
    assert a[:, 0, 1].tolist() == [0, 100, 100, 100]
    # 20 + (83.33 - 80) / 170 * 170 = 23.33 -> 23; 20 + 86.67 = 106.67 -> 107
    assert a[:, 18, 23].tolist() == [10, 23, 107, 190]
    assert a.sum() == a[:, 0, 0].sum() + a[:, 0, 1].sum() + a[:, 18, 23].sum()  # nothing elsewhere
    # 90 ms -> 1 step: frames at 0 and 83.33 ms; 7 + 83.33 / 90 * 2 = 8.85 -> 9
    assert res.captures[1][:, 0, 5].tolist() == [7, 9]
    # 0.5 -> 1 (halves up); 3 * 116.67 / 200 = 1.75 -> 2; 3
    assert res.captures[2][:, 0, 7].tolist() == [0, 1, 2, 3]
    assert res.meta["recorded_frames"].tolist() == [3, 2, 3]
    assert np.allclose(res.meta["time_ms"][0], [0, 1000 / 12, 2000 / 12, 250])


@pytest.mark.parametrize("rows, line, message", [
    (SMALL[:1] + [_row(1, 1, 0, 1, 80, {})], 3, "participantID 1 in a file named for participantID 0"),
    (SMALL[:1] + [_row(0, 1, 0, 2, 80, {})], 3, "frameID jumps from 0 to 2"),
    (SMALL[:2] + [_row(0, 1, 0, 2, 80, {})], 4, "time 80 ms does not follow 80 ms"),
    (SMALL[:1] + [_row(0, 1, 0, 1, 80, {3: 256})], 3, "'pixel3': value above 255"),
    (SMALL[:1] + [_row(0, 1, 0, 1, 80, {}).replace(",0,0", ",0.5,0", 1)], 3, "not a whole number"),
    (SMALL[:2] + SMALL[3:4] + [_row(0, 1, 0, 0, 0, {})], 5, "repetition 0 starts again"),
])
def test_bad_rows_are_refused_with_their_line(tmp_path, rows, line, message):
    base = _folder(tmp_path, rows)
    with pytest.raises(DataError) as e:
        build_recorded(base)
    assert message in str(e.value) and e.value.line == line and Path(e.value.path).name.startswith("touch_p0_g1")


def test_wrong_header_and_unknown_gesture_and_checksum(tmp_path):
    base = _folder(tmp_path / "a", SMALL, name="touch_p0_g7-x.csv")
    with pytest.raises(DataError, match="gesture id 7 is not in GesturesRated.csv"):
        build_recorded(base)
    base = _folder(tmp_path / "b", SMALL)
    f = next((base / "raw").iterdir())
    f.write_bytes(gzip.compress(gzip.decompress(f.read_bytes()).replace(b"frameID", b"frame", 1)))
    with pytest.raises(DataError, match="header column 4 is 'frame', expected 'frameID'") as e:
        build_recorded(base)
    assert e.value.line == 1
    base = _folder(tmp_path / "c", SMALL)
    (base / "SHA256SUMS").write_text("0" * 64 + "  touch_p0_g1-20_4_16h_00m_00s.csv\n")
    with pytest.raises(DataError, match="does not match SHA256SUMS"):
        build_recorded(base)


# ------------------------------------------------------------------ time stamps in the data model
def _tiny(times) -> TouchDataset:
    sensor = SensorSpec("t", (2, 3), 12.0, (0, 255))
    caps = [np.arange(len(t) * 6, dtype=np.uint8).reshape(len(t), 2, 3) for t in times]
    meta = pd.DataFrame({"capture_id": [f"c{i}" for i in range(len(times))], "subject": "s", "gesture": "g",
                         "time_ms": [list(t) for t in times]})
    return TouchDataset("t", caps, meta, sensor)


def test_time_stamps_round_trip_and_enter_the_hash(tmp_path):
    ds = _tiny([[0, 80, 163], [0, 83]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DatasetChangedWarning)
        back = TouchDataset.from_parquet(ds.to_parquet(tmp_path / "t.parquet"), verify=True)
    assert back.content_hash == ds.content_hash
    assert [list(t) for t in back.meta["time_ms"]] == [[0, 80, 163], [0, 83]]
    assert back.subset([1]).meta["time_ms"][0].tolist() == [0, 83]
    assert _tiny([[0, 80, 164], [0, 83]]).content_hash != ds.content_hash  # every value counts
    # steps 80, 160, 83: median 83; 95th percentile (linear) at rank 0.95 * 2 = 1.9: 83 + 0.9 * (160 - 83) = 152.3
    steps = _tiny([[0, 80, 240], [0, 83]]).info()["time_steps_ms"]
    assert steps == {"median": 83.0, "p95": pytest.approx(152.3), "min": 80.0, "max": 160.0}


@pytest.mark.parametrize("times", [[[0, 80], [0, 83]], [[0, 80, 80], [0, 83]]])
def test_time_stamps_must_be_one_increasing_time_per_frame(times):
    sensor = SensorSpec("t", (2, 3), 12.0, (0, 255))
    caps = [np.zeros((3, 2, 3), np.uint8), np.zeros((2, 2, 3), np.uint8)]
    meta = pd.DataFrame({"capture_id": ["a", "b"], "subject": "s", "gesture": "g", "time_ms": times})
    with pytest.raises(ValueError, match="time_ms must hold one increasing time per frame"):
        TouchDataset("t", caps, meta, sensor)


# ------------------------------------------------------------------ the shipped protocols
@pytest.mark.realdata
def test_shipped_protocols_serve_the_sensor_and_two_methods_are_refused(real_socialtouch, tb_cache, monkeypatch,
                                                                         tmp_path):
    """Every method of the two protocols takes the 19 x 24 grid at 12 Hz (3 people; 3 Zhou sets x 7
    classifiers + 17 methods = 38); touch-et-win and the CNN are refused before any work, with why."""
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tb_cache))
    for name, plan in (("socialtouch-loso", "3 fold(s) x 38 method(s) = 114 task(s)"),
                       ("socialtouch-within", "9 fold(s) x 38 method(s) = 342 task(s)")):
        r = CliRunner().invoke(cli, ["protocols", "validate", name])
        assert r.exit_code == 0 and plan in r.output, r.output
    for method, why in (("touch-et-win", "its 2-s windows (24 frames at 12 Hz) are longer than the shortest "
                                         "capture (3 frames)"),
                        ("cnn", "L=30 windows need captures of at least 30 frames (one frame per window); "
                                "the shortest has 3")):
        p = tmp_path / f"{method}.yaml"
        p.write_text(f"name: refused\ndataset: socialtouch\nscheme: loso\nmethods: [{method}]\n")
        r = CliRunner().invoke(cli, ["protocols", "validate", str(p)])
        assert r.exit_code == 3 and "cannot serve sensor 'socialtouch' (19 x 24 at 12 Hz)" in r.output
        assert why in r.output, r.output
