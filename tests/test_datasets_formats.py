"""The challenge CSV, CoST and table readers, on files written
here in exactly the documented formats, quirks included."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.datasets.challenge_csv import export_challenge_csv, read_challenge_csv
from touchbench.datasets.cost import read_cost_csv
from touchbench.datasets.generic import read_table_dataset
from touchbench.datasets.haart import HAART_SENSOR
from touchbench.datasets.model import TouchDataset
from touchbench.core.errors import DataError


def _challenge_like(n_train=2, n_test=2, seed=0) -> TouchDataset:
    rng = np.random.default_rng(seed)
    rows, caps = [], []
    for split, pid, n in (("train", 4, n_train), ("test", 9, n_test)):
        for k, g in enumerate(["pat", "rub", "tickle", "stroke"][:n]):
            label = ("P" if split == "train" else "T") + str(pid)
            rows.append({"capture_id": f"s{pid:02d}-foam-fur-{g}", "subject": f"s{pid:02d}", "substrate": "foam",
                         "cover": "fur", "gesture": g, "split": split, "challenge_label": label})
            caps.append(rng.integers(0, 1024, size=(432, 8, 8)).astype(np.uint16))
    return TouchDataset("haart-challenge", caps, pd.DataFrame(rows), HAART_SENSOR)


# ------------------------------------------------------------ challenge CSV
def test_challenge_csv_round_trip_and_layout(tmp_path):
    ds = _challenge_like()
    export_challenge_csv(ds, tmp_path)
    train = (tmp_path / "training.csv").read_text().splitlines()
    test = (tmp_path / "testWITHLABELS.csv").read_text().splitlines()
    assert train[0].split(",")[:5] == ['"ParticipantID"', '"Substrate"', '"Cover"', '"Gesture"', '"cell1"']
    assert len(train[0].split(",")) == 4 + 64 and len(train) == 1 + 2 * 432
    assert test[0].split(",")[4] == '"Sequence"' and len(test) == 1 + 2 * 432
    # first data row: quoted strings, then frame 0 row-major
    first = train[1].split(",")
    assert first[:4] == ['"P4"', '"foam"', '"fur"', '"pat"']
    assert [int(v) for v in first[4:]] == ds.captures[0][0].reshape(-1).tolist()
    assert test[433].split(",")[4] == "1" and test[432].split(",")[4] == "432"
    back = read_challenge_csv(tmp_path)
    assert back.content_hash == ds.content_hash


def test_challenge_csv_header_variants(tmp_path):
    ds = _challenge_like()
    export_challenge_csv(ds, tmp_path)
    for f in ("training.csv", "testWITHLABELS.csv"):
        p = tmp_path / f
        lines = p.read_text().splitlines()
        names = [n.strip('"') for n in lines[0].split(",")]
        names[0] = "ParticipantNo"
        lines[0] = ", ".join([names[0]] + [f'"{n}"' for n in names[1:]])  # leading spaces, quoted names
        p.write_text("\n".join(lines) + "\n")
    assert read_challenge_csv(tmp_path).content_hash == ds.content_hash


@pytest.mark.parametrize(
    "line, replace, message",
    [
        (5, lambda s: s.replace(",12,", ",x,", 1) if ",12," in s else s.rsplit(",", 1)[0] + ",x", "non-numeric"),
        (7, lambda s: s + ",5", "malformed row"),
        (9, lambda s: s.rsplit(",", 1)[0] + ",1024", "above 1023"),
        (11, lambda s: s.rsplit(",", 3)[0], "missing"),
    ],
)
def test_challenge_csv_bad_rows(tmp_path, line, replace, message):
    export_challenge_csv(_challenge_like(), tmp_path)
    p = tmp_path / "training.csv"
    lines = p.read_text().splitlines()
    lines[line - 1] = replace(lines[line - 1])
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        read_challenge_csv(p)
    assert "training.csv" in str(e.value) and message in str(e.value)
    assert e.value.line == line


def test_challenge_csv_capture_not_432_rows(tmp_path):
    export_challenge_csv(_challenge_like(), tmp_path)
    p = tmp_path / "training.csv"
    lines = p.read_text().splitlines()
    p.write_text("\n".join(lines[:-1]) + "\n")  # the last capture loses a frame
    with pytest.raises(DataError) as e:
        read_challenge_csv(p)
    # header on line 1, the first capture on lines 2-433, the second on 434-864 (its 432nd row gone):
    # the error is where the capture breaks off, and says where it began
    assert e.value.line == 864
    assert "a capture ends after 431 rows (lines 434-864); each capture of this file has 432 rows" in str(e.value)


@pytest.mark.realdata
def test_real_challenge_export_import_same_hash(real_haart_challenge, tmp_path):
    export_challenge_csv(real_haart_challenge, tmp_path)
    back = read_challenge_csv(tmp_path)
    assert len(back) == 829
    assert back.content_hash == real_haart_challenge.content_hash


# --------------------------------------------------------------------- CoST
def _cost_file(path, captures, header=" subject, variant, gesture, frame"):
    """captures: list of (subject, variant, gesture, values (T, 64))."""
    lines = [header + "".join(f", ch{i}" for i in range(1, 65))]
    for s, v, g, vals in captures:
        for f, row in enumerate(vals, start=1):
            lines.append(",".join([str(s), str(v), str(g), str(f)] + [str(int(x)) for x in row]))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cost_reader_lengths_repetitions_missing_and_channel_map(tmp_path):
    rng = np.random.default_rng(0)
    caps = []
    for rep, t in enumerate([10, 37, 1300]):  # variable lengths, as in CoST (75 ms .. 9.6 s at 135 Hz)
        caps.append((3, 2, 4, rng.integers(20, 1024, size=(t, 64))))
    caps.append((3, 2, 12, rng.integers(20, 71, size=(15, 64))))  # one repetition only: others lost
    onehot = np.zeros((1, 64))
    onehot[0, 10] = 999  # ch11: row-major (1, 2) -> transposed (2, 1) -> flipped (5, 1)
    caps.append((31, 3, 14, np.repeat(onehot, 12, axis=0)))
    ds = read_cost_csv(_cost_file(tmp_path / "CoST.csv", caps))
    assert list(ds.n_frames) == [10, 37, 1300, 15, 12]
    assert list(ds.meta["gesture"]) == ["pat", "pat", "pat", "stroke", "tickle"]
    assert list(ds.meta["variant"]) == ["normal"] * 4 + ["rough"]
    assert list(ds.meta["repetition"]) == [1, 2, 3, 1, 1]
    assert list(ds.meta["subject"]) == ["s03"] * 4 + ["s31"]
    assert ds.sensor.frame_rate == 135.0 and ds.sensor.grid == (8, 8)
    grid = ds.captures[4][0]
    assert grid[5, 1] == 999 and grid.sum() == 999
    # a full check of the map against numpy written independently: rot90 of the row-major grid
    vals = caps[0][3]
    np.testing.assert_array_equal(ds.captures[0], np.rot90(vals.reshape(-1, 8, 8), k=1, axes=(1, 2)))


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda L: L[:3] + [L[3].replace("3,2,4,3,", "3,2,4,5,", 1)] + L[4:], "jumps from 2 to 5"),
        (lambda L: L[:2] + [L[2].replace("3,2,4,", "3,2,15,", 1)] + L[3:], "unknown gesture code 15"),
        (lambda L: L[:2] + [L[2].replace("3,2,4,", "3,9,4,", 1)] + L[3:], "unknown variant code 9"),
        (lambda L: L[:4] + [L[4] + ",7"] + L[5:], "malformed row"),
        (lambda L: L[:5] + [L[5].rsplit(",", 1)[0] + ",abc"] + L[6:], "non-numeric"),
        (lambda L: L[:6] + [L[6].rsplit(",", 1)[0] + ",-3"] + L[7:], "below 0"),
    ],
)
def test_cost_bad_input(tmp_path, edit, message):
    rng = np.random.default_rng(1)
    p = _cost_file(tmp_path / "CoST.csv", [(3, 2, 4, rng.integers(20, 1000, size=(8, 64)))])
    p.write_text("\n".join(edit(p.read_text().splitlines())) + "\n")
    with pytest.raises(DataError) as e:
        read_cost_csv(p)
    assert "CoST.csv" in str(e.value) and message in str(e.value)


# ------------------------------------------------------------------ generic
def _long(n_caps=3, grid=(3, 5), first_frame=0, seed=0):
    rng = np.random.default_rng(seed)
    rows = []
    for c in range(n_caps):
        for f in range(4 + c):
            row = {"capture_id": f"c{c}", "frame": f + first_frame, "subject": f"u{c % 2}", "gesture": ["a", "b"][c % 2], "hand": "left"}
            row.update({f"px{i}": float(rng.integers(0, 255)) for i in range(grid[0] * grid[1])})
            rows.append(row)
    return pd.DataFrame(rows)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_generic_reader_any_grid(tmp_path, suffix):
    df = _long()
    p = tmp_path / f"mine{suffix}"
    df.to_csv(p, index=False) if suffix == ".csv" else df.to_parquet(p)
    ds = read_table_dataset(p, (3, 5), 30.0, value_range=(0, 255))
    assert list(ds.n_frames) == [4, 5, 6] and ds.sensor.grid == (3, 5)
    assert list(ds.meta.columns) == ["capture_id", "subject", "gesture", "hand"]
    np.testing.assert_array_equal(ds.captures[1][2].reshape(-1), df[df.capture_id == "c1"].iloc[2][[f"px{i}" for i in range(15)]].to_numpy(float))


def test_generic_reader_bad_input(tmp_path):
    df = _long()
    df.loc[5, "hand"] = "right"
    p = tmp_path / "m.csv"
    df.to_csv(p, index=False)
    with pytest.raises(DataError, match="'hand' changes inside capture 'c1'") as e:
        read_table_dataset(p, (3, 5), 30.0, value_range=(0, 255))
    assert e.value.line == 7
    df = _long()
    df.to_csv(p, index=False)
    with pytest.raises(DataError, match=r"the grid 4x4 \(--grid\) has 16 cells, but the table has 15 cell columns "
                                        r"\(px0..px14\)"):
        read_table_dataset(p, (4, 4), 30.0, value_range=(0, 255))
    df.loc[3, "px2"] = np.nan
    df.to_csv(p, index=False)
    with pytest.raises(DataError, match="NaN") as e:
        read_table_dataset(p, (3, 5), 30.0, value_range=(0, 255))
    assert e.value.line == 5


def test_an_export_without_test_captures_reads_back(tmp_path):
    ds = _challenge_like(n_train=3, n_test=0)
    files = export_challenge_csv(ds, tmp_path)
    assert [p.name for p in files] == ["training.csv", "testWITHLABELS.csv"]
    assert len((tmp_path / "testWITHLABELS.csv").read_text().splitlines()) == 1  # the header alone
    back = read_challenge_csv(tmp_path)
    assert len(back) == 3 and set(back.meta["split"]) == {"train"}
    for a, b in zip(ds.captures, back.captures):
        assert np.array_equal(a, b)


def test_header_only_challenge_files_are_refused_as_no_captures(tmp_path):
    export_challenge_csv(_challenge_like(n_train=2, n_test=0), tmp_path)
    train = tmp_path / "training.csv"
    train.write_text(train.read_text().splitlines()[0] + "\n")
    with pytest.raises(DataError, match="no captures: every file found has a header and no rows"):
        read_challenge_csv(tmp_path)


def test_one_grid_syntax(tmp_path):
    from touchbench.datasets.formats import parse_grid

    assert parse_grid("19x24") == (19, 24) and parse_grid("19X24") == (19, 24) and parse_grid("8,8") == (8, 8)
    with pytest.raises(ValueError, match="expected HxW"):
        parse_grid("19 by 24")
    with pytest.raises(ValueError, match="at least 1"):
        parse_grid("0x4")
