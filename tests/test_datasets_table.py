"""The ``table`` format from the command line: one row per frame or per cell, a file or a folder,
rows in any order, columns named by the user, value range and frame rate given or worked out.

Expected values: frames written here by hand (each cell's value a formula of capture, frame and
cell), frame rates and ranges worked out from the numbers written, and for the real SocialTouch
file the registered ``socialtouch-recorded`` reader (another reader of the same file).
"""

from __future__ import annotations

import gzip
import logging

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.errors import DataError, TouchbenchError
from touchbench.datasets.formats import FORMATS
from touchbench.datasets.generic import infer_value_range, parse_value_range
from touchbench.datasets.model import TouchDataset

GRID = (2, 3)
STEP_S = 0.02  # 50 Hz


def _value(c: int, t: int, i: int) -> int:
    """Capture c, frame t, cell i (row-major): a 12-bit value."""
    return 1000 * c + 37 * t + 5 * i + 1500 * (c == 2)


def _expected(n_frames=(4, 5, 6)):
    return {f"k{c}": np.array([[_value(c, t, i) for i in range(6)] for t in range(n)]).reshape(n, *GRID)
            for c, n in enumerate(n_frames)}


def _wide(n_frames=(4, 5, 6), dropped=()):
    """One row per frame, 12-bit values, a timestamp in seconds (a frame dropped where asked), rows shuffled."""
    rows = []
    for c, n in enumerate(n_frames):
        t_s = 0.0
        for t in range(n):
            rows.append({"capture": f"k{c}", "timestamp": round(1.5 + t_s, 6), "person": f"u{c % 2}",
                         "gesture": ["pat", "rub"][c % 2], "hand": "left",
                         **{f"ch{i}": _value(c, t, i) for i in range(6)}})
            t_s += 2 * STEP_S if (c, t) in dropped else STEP_S
    return pd.DataFrame(rows).sample(frac=1.0, random_state=3).reset_index(drop=True)


def _long(wide: pd.DataFrame) -> pd.DataFrame:
    """The same frames as a true long table, one row per cell (row, col, value), rows shuffled."""
    rows = [{"capture": r.capture, "timestamp": r.timestamp, "person": r.person, "gesture": r.gesture,
             "hand": r.hand, "row": i // 3, "col": i % 3, "value": r[f"ch{i}"]}
            for _, r in wide.iterrows() for i in range(6)]
    return pd.DataFrame(rows).sample(frac=1.0, random_state=4).reset_index(drop=True)


def convert(*args, catch=True):
    return CliRunner().invoke(cli, ["data", "convert", *map(str, args)], catch_exceptions=catch)


def _by_id(ds: TouchDataset) -> dict[str, np.ndarray]:
    return dict(zip(ds.meta["capture_id"], ds.captures))


COLUMNS = ["--capture-columns", "capture", "--subject-column", "person", "--time-unit", "s"]


def test_a_12_bit_frame_table_with_a_timestamp_from_the_command_line(tmp_path):
    _wide(dropped={(1, 2)}).to_csv(tmp_path / "skin.csv", index=False)
    r = convert(tmp_path / "skin.csv", tmp_path / "skin.parquet", "--format", "table", "--grid", "2x3", *COLUMNS)
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "skin.parquet")
    got, want = _by_id(ds), _expected()
    assert sorted(got) == ["k0", "k1", "k2"]
    for k in want:
        np.testing.assert_array_equal(got[k], want[k])
    # 12-bit: the smallest 2^k - 1 holding the largest value written (3700 at most, above 1023), stated in a warning
    largest = max(int(v.max()) for v in want.values())
    assert 1023 < largest <= 4095
    assert ds.sensor.value_range == (0.0, 4095.0) and ds.captures[0].dtype == np.uint16
    assert "value range not given: inferred 0..4095" in r.output
    # 20 ms steps (one of 40 ms where a frame was dropped): the median step gives 50 Hz
    assert ds.sensor.frame_rate == pytest.approx(50.0)
    assert "frame rate estimated from the time column: 50 Hz" in r.output
    times = dict(zip(ds.meta["capture_id"], ds.meta["time_ms"]))
    np.testing.assert_allclose(times["k1"], [0, 20, 40, 80, 100], atol=1e-6)
    assert list(ds.meta.columns) == ["capture_id", "subject", "gesture", "hand", "time_ms"]
    assert dict(zip(ds.meta["capture_id"], ds.meta["subject"])) == {"k0": "u0", "k1": "u1", "k2": "u0"}


def test_a_true_long_table_gives_the_same_captures_and_its_grid(tmp_path):
    wide = _wide()
    _long(wide).to_csv(tmp_path / "cells.csv.gz", index=False)
    r = convert(tmp_path / "cells.csv.gz", tmp_path / "cells.parquet", "--format", "table", *COLUMNS,
                "--value-range", "0..4095", "--frame-rate", "50")
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "cells.parquet")
    assert ds.sensor.grid == GRID and ds.name == "cells"  # the grid from the row and col columns
    got = _by_id(ds)
    for k, v in _expected().items():
        np.testing.assert_array_equal(got[k], v)
    # one cell index (row-major, from 1) and the grid given
    cells = _long(wide).assign(cell=lambda d: d["row"] * 3 + d["col"] + 1).drop(columns=["row", "col"])
    cells.to_parquet(tmp_path / "index.parquet")
    back = FORMATS.get("table").read(tmp_path / "index.parquet", grid=GRID, frame_rate=50.0,
                                     capture_columns=("capture",), subject_column="person", time_unit="s")
    for k, v in _expected().items():
        np.testing.assert_array_equal(_by_id(back)[k], v)
    with pytest.raises(DataError, match="does not say the grid: give --grid"):
        FORMATS.get("table").read(tmp_path / "index.parquet", frame_rate=50.0, capture_columns=("capture",),
                                  subject_column="person", time_unit="s")


def test_a_folder_of_files_and_a_capture_split_across_two_is_refused(tmp_path):
    wide = _wide()
    folder = tmp_path / "study"
    (folder / "day2").mkdir(parents=True)
    wide[wide.capture == "k0"].to_csv(folder / "a.csv", index=False)
    wide[wide.capture == "k1"].to_parquet(folder / "day2" / "b.parquet")
    with gzip.open(folder / "day2" / "c.csv.gz", "wt") as fh:
        wide[wide.capture == "k2"].to_csv(fh, index=False)
    (folder / "notes.txt").write_text("not a table\n")
    r = convert(folder, tmp_path / "study.parquet", "--format", "table", "--grid", "2x3", "--value-range",
                "0..4095", *COLUMNS)
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "study.parquet")
    assert list(ds.meta["source"]) == ["a.csv", "day2/b.parquet", "day2/c.csv.gz"]
    for k, v in _expected().items():
        np.testing.assert_array_equal(_by_id(ds)[k], v)
    wide[wide.capture == "k2"].head(2).to_csv(folder / "d.csv", index=False)
    r = convert(folder, tmp_path / "x.parquet", "--format", "table", "--grid", "2x3", *COLUMNS)
    assert r.exit_code == 3 and "capture 'k2' is also in" in r.output
    assert not (tmp_path / "x.parquet").exists()


def test_cell_name_patterns(tmp_path):
    wide = _wide()
    named = wide.rename(columns={f"ch{i}": f"r{i // 3 + 1}c{i % 3 + 1}" for i in range(6)})
    named.to_csv(tmp_path / "rc.csv", index=False)
    ds = FORMATS.get("table").read(tmp_path / "rc.csv", cells="r{row}c{col}", value_range=(0, 4095),
                                   capture_columns=("capture",), subject_column="person", time_unit="s")
    assert ds.sensor.grid == GRID  # the names give it: rows 1..2, columns 1..3
    for k, v in _expected().items():
        np.testing.assert_array_equal(_by_id(ds)[k], v)
    # pixel{i} counts from 0 here; other numbered columns beside it do not confuse the pattern
    px = wide.rename(columns={f"ch{i}": f"pixel{i}" for i in range(6)}).assign(**{f"sensor{i}": 1 for i in range(6)})
    px.to_csv(tmp_path / "px.csv", index=False)
    ds = FORMATS.get("table").read(tmp_path / "px.csv", grid=GRID, cells="pixel{i}", value_range=(0, 4095),
                                   capture_columns=("capture",), subject_column="person", time_unit="s")
    np.testing.assert_array_equal(_by_id(ds)["k2"], _expected()["k2"])
    with pytest.raises(DataError, match="cannot tell the 6 cell columns apart"):
        FORMATS.get("table").read(tmp_path / "px.csv", grid=GRID, value_range=(0, 4095),
                                  capture_columns=("capture",), subject_column="person", time_unit="s")
    with pytest.raises(TouchbenchError, match=r"use \{i\} \(one index\) or \{row\} and \{col\}"):
        FORMATS.get("table").read(tmp_path / "px.csv", grid=GRID, cells="pixel{n}", frame_rate=1.0)


def test_a_grid_that_does_not_fit_the_cell_columns_is_refused_with_the_layout_found(tmp_path):
    # cells named by row and column: r1c1..r2c3 lay out 2 rows x 3 columns (GRID), found without --cells
    named = _wide().rename(columns={f"ch{i}": f"r{i // 3 + 1}c{i % 3 + 1}" for i in range(6)})
    named.to_csv(tmp_path / "rc.csv", index=False)
    r = convert(tmp_path / "rc.csv", tmp_path / "rc.parquet", "--format", "table", "--value-range", "0..4095",
                *COLUMNS)
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "rc.parquet")
    assert ds.sensor.grid == GRID
    for k, v in _expected().items():
        np.testing.assert_array_equal(_by_id(ds)[k], v)
    for cells in ((), ("--cells", "r{row}c{col}")):
        r = convert(tmp_path / "rc.csv", tmp_path / "t.parquet", "--format", "table", "--grid", "3x2", *cells, *COLUMNS)
        assert r.exit_code == 3 and "rc.csv:1: the grid 3x2 (--grid) looks transposed: the table's cells are laid out " \
            "as 2 rows x 3 columns (2x3)" in r.output, r.output
    # another cell count: 2 x 4 = 8 cells against the 6 columns, both counts and the grid said
    r = convert(tmp_path / "rc.csv", tmp_path / "t.parquet", "--format", "table", "--grid", "2x4", *COLUMNS)
    assert r.exit_code == 3 and "the grid 2x4 (--grid) has 8 cells, but the table has 6 cell columns (r1c1..r2c3, " \
        "laid out as 2 rows x 3 columns)" in r.output, r.output
    # one index per cell: a count that differs is said the same way (a transposed grid cannot be seen there)
    _wide().to_csv(tmp_path / "ch.csv", index=False)
    r = convert(tmp_path / "ch.csv", tmp_path / "t.parquet", "--format", "table", "--grid", "3x3", *COLUMNS)
    assert r.exit_code == 3 and "the grid 3x3 (--grid) has 9 cells, but the table has 6 cell columns (ch0..ch5)" \
        in r.output, r.output
    # a true long table's row and col columns show the layout too
    _long(_wide()).to_csv(tmp_path / "cells.csv", index=False)
    r = convert(tmp_path / "cells.csv", tmp_path / "t.parquet", "--format", "table", "--grid", "3x2", *COLUMNS)
    assert r.exit_code == 3 and "the grid 3x2 (--grid) looks transposed: the table's cells are laid out as 2 rows x " \
        "3 columns (2x3)" in r.output, r.output
    assert not (tmp_path / "t.parquet").exists()


def test_value_ranges_given_or_inferred():
    # worked out from the rule: whole numbers from 0 -> 2^k - 1 for the smallest ADC width that holds them
    assert infer_value_range(0, 255, True)[0] == (0.0, 255.0)
    assert infer_value_range(3, 256, True)[0] == (0.0, 1023.0)
    assert infer_value_range(0, 4000, True)[0] == (0.0, 4095.0)
    assert infer_value_range(0, 1, True)[0] == (0.0, 1.0)
    assert infer_value_range(0.0, 0.73, False)[0] == (0.0, 1.0)  # normalised data is not a 0..1023 sensor
    assert infer_value_range(-2.5, 7.25, False)[0] == (-2.5, 7.25)
    assert parse_value_range("0..4095") == (0.0, 4095.0) and parse_value_range("-1,1") == (-1.0, 1.0)
    for bad in ("4095", "5..1", "a..b"):
        with pytest.raises(ValueError):
            parse_value_range(bad)


def test_normalised_data_gets_a_0_to_1_sensor_and_gaus_bmh_sees_its_contacts(tmp_path, caplog):
    wide = _wide()
    for i in range(6):
        wide[f"ch{i}"] = wide[f"ch{i}"] / 4095.0
    wide.to_csv(tmp_path / "norm.csv", index=False)
    with caplog.at_level(logging.WARNING, logger="touchbench"):
        ds = FORMATS.get("table").read(tmp_path / "norm.csv", grid=GRID, capture_columns=("capture",),
                                       subject_column="person", time_unit="s")
    assert ds.sensor.value_range == (0.0, 1.0) and ds.captures[0].dtype == np.float64
    assert "inferred 0..1 (values within 0..1" in caplog.text


BAD = [
    # (what is done to the table, the words of the one error, the line it names)
    (lambda w: w.rename(columns={"timestamp": "stamp"}), "no frame counter or time column", 1),
    (lambda w: w.assign(hand=["left"] * 14 + ["right"]), "metadata column 'hand' changes inside capture", 16),
    (lambda w: w.assign(ch3=[1] * 5 + [5000] + [1] * 9), "column 'ch3': value above 4095", 7),
    (lambda w: w.assign(ch0=[1] * 9 + ["x"] + [1] * 5), "column 'ch0': missing, non-numeric", 11),
    (lambda w: pd.concat([w, w.iloc[[4]]], ignore_index=True), "does not increase", 17),
]


@pytest.mark.parametrize("edit, words, line", BAD)
def test_bad_frame_tables_get_one_error_naming_the_line(tmp_path, edit, words, line):
    edit(_wide()).to_csv(tmp_path / "bad.csv", index=False)
    r = convert(tmp_path / "bad.csv", tmp_path / "out.parquet", "--format", "table", "--grid", "2x3",
                "--value-range", "0..4095", *COLUMNS)
    assert r.exit_code == 3, r.output
    errors = [ln for ln in r.output.splitlines() if ln.startswith("error:")]
    assert len(errors) == 1 and words in errors[0] and f"bad.csv:{line}:" in errors[0], r.output
    assert not (tmp_path / "out.parquet").exists()


def test_column_and_unit_errors(tmp_path):
    _wide().to_csv(tmp_path / "w.csv", index=False)
    table = FORMATS.get("table")
    with pytest.raises(DataError, match=r"time column 'timestamp' does not say its unit: give --time-unit s or ms or "
                                        r"us \(its values run 1.5..1.6\)"):
        table.read(tmp_path / "w.csv", grid=GRID, capture_columns=("capture",), subject_column="person")
    with pytest.raises(DataError, match=r"no capture column \(expected one of \['take'\]; found \['capture', "):
        table.read(tmp_path / "w.csv", grid=GRID, capture_columns=("take",), subject_column="person")
    with pytest.raises(DataError, match="no subject column"):
        table.read(tmp_path / "w.csv", grid=GRID, capture_columns=("capture",), time_unit="s")
    with pytest.raises(DataError, match=r"the grid 2x2 \(--grid\) has 4 cells, but the table has 6 cell columns "
                                        r"\(ch0..ch5\)"):
        table.read(tmp_path / "w.csv", grid=(2, 2), frame_rate=50.0, cells="ch{i}", capture_columns=("capture",),
                   subject_column="person", time_unit="s")
    r = convert(tmp_path / "w.csv", tmp_path / "o.parquet", "--format", "table", "--grid", "2-3")
    assert r.exit_code == 2 and "expected HxW (rows x columns) such as 19x24" in r.output
    r = convert(tmp_path / "w.csv", tmp_path / "o.parquet", "--format", "table", "--value-range", "4095")
    assert r.exit_code == 2 and "expected LO..HI such as 0..4095" in r.output
    r = convert(tmp_path / "nowhere", tmp_path / "o.parquet", "--format", "table")
    assert r.exit_code == 2 and "does not exist" in r.output


def test_a_long_table_missing_a_cell_or_repeating_one(tmp_path):
    cells = _long(_wide())
    cells.drop(index=10).to_csv(tmp_path / "missing.csv", index=False)
    with pytest.raises(DataError, match=r"of capture 'k\d': 5 cells for a 2 x 3 grid"):
        FORMATS.get("table").read(tmp_path / "missing.csv", frame_rate=50.0, value_range=(0, 4095),
                                  capture_columns=("capture",), subject_column="person", time_unit="s")
    twice = pd.concat([cells, cells.iloc[[10]]], ignore_index=True)
    twice.to_csv(tmp_path / "twice.csv", index=False)
    with pytest.raises(DataError, match="7 cells for a 2 x 3 grid"):
        FORMATS.get("table").read(tmp_path / "twice.csv", frame_rate=50.0, value_range=(0, 4095),
                                  capture_columns=("capture",), subject_column="person", time_unit="s")


def test_a_real_socialtouch_file_through_the_table_format(real_socialtouch_dir, real_socialtouch_recorded, tmp_path):
    """The table reader, told the SocialTouch file's columns, reads what the dedicated reader reads."""
    path = sorted((real_socialtouch_dir / "raw").glob("touch_p1_g7-*"))[0]
    r = convert(path, tmp_path / "p1g7.parquet", "--format", "table", "--grid", "19x24", "--value-range", "0..255",
                "--capture-columns", "participantID,gesture,repetition", "--subject-column", "participantID",
                "--frame-column", "frameID", "--time-column", "time", "--time-unit", "ms", "--cells", "pixel{i}")
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "p1g7.parquet")
    ref = real_socialtouch_recorded
    mine = ref.meta.index[ref.meta["source"].astype(str).str.startswith(path.name.removesuffix(".gz"))]
    assert len(ds) == len(mine) > 0
    for i, j in enumerate(mine):
        np.testing.assert_array_equal(ds.captures[i], ref.captures[j])
        np.testing.assert_array_equal(ds.meta["time_ms"][i], ref.meta["time_ms"][j])
    assert ds.captures[0].dtype == np.uint8


# ---------------------------------------------------------------- small tables written by hand
HEADER = "capture_id,subject,gesture,frame,c0,c1,c2,c3"


def _table(tmp_path, *rows, name="t.csv"):
    """A 2 x 2 table written line by line (the header is line 1, ``rows[i]`` is line ``i + 2``)."""
    path = tmp_path / name
    path.write_text("\n".join([HEADER, *rows]) + "\n")
    return path


def _read(path, **kw):
    return FORMATS.get("table").read(path, grid=(2, 2), frame_rate=kw.pop("frame_rate", 10.0),
                                     value_range=kw.pop("value_range", (0, 255)), **kw)


def test_ids_are_text_as_written(tmp_path):
    # subjects 007 and 7 are two people; captures 01 and 1 two captures of one frame each
    ds = _read(_table(tmp_path, "01,007,pat,1,1,2,3,4", "1,7,pat,1,5,6,7,8"))
    assert dict(zip(ds.meta["capture_id"], ds.meta["subject"])) == {"01": "007", "1": "7"}
    assert ds.meta["subject"].nunique() == 2
    np.testing.assert_array_equal(_by_id(ds)["1"], [[[5, 6], [7, 8]]])


BAD_LINES = [
    # (the rows of the table, the words of the one error, the line it names)
    (["a,s1,pat,1,1,2,3,4", "a,s1,pat,2,1_0,2,3,4"], "column 'c0': missing, non-numeric", 3),
    (["a,s1,pat,1,1,2,3,4", "b,,pat,1,1,2,3,4"], "empty subject (column 'subject')", 3),
    (["a,s1,pat,1,1,2,3,4", "b,s1, ,1,1,2,3,4"], "empty gesture (column 'gesture')", 3),
    (["a,s1,pat,1,1,2,3,4", HEADER, "b,s1,pat,1,1,2,3,4"], "repeats the header row", 3),
]


@pytest.mark.parametrize("rows, words, line", BAD_LINES)
def test_bad_cells_and_labels_are_refused_at_their_line(tmp_path, rows, words, line):
    path = _table(tmp_path, *rows)
    with pytest.raises(DataError) as e:
        _read(path)
    assert words in str(e.value) and f"t.csv:{line}:" in str(e.value)


def test_a_text_time_stamp_is_named_at_its_line(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("capture_id,subject,gesture,time_ms,c0,c1,c2,c3\n"
                    "a,s1,pat,0,1,2,3,4\na,s1,pat,10,1,2,3,4\na,s1,pat,ten,1,2,3,4\n")
    with pytest.raises(DataError, match=r"t.csv:4: column 'time_ms': not a number \('ten'\)"):
        _read(path)
    # a long table: the line of the cell row that holds the stamp, not of the frame's position among frames
    path.write_text("capture_id,subject,gesture,time_ms,cell,value\n"
                    + "".join(f"a,s1,pat,0,{k},1\n" for k in range(4))
                    + "".join(f"a,s1,pat,x,{k},1\n" for k in range(4)))
    with pytest.raises(DataError, match=r"t.csv:6: column 'time_ms': not a number \('x'\)"):
        _read(path)


@pytest.mark.parametrize("option, value", [("--frame-rate", "inf"), ("--frame-rate", "0"), ("--frame-rate", "-5"),
                                           ("--frame-rate", "nan"), ("--value-range", "0..1e400"),
                                           ("--value-range", "nan..1")])
def test_frame_rate_and_value_range_must_be_finite_and_positive(tmp_path, option, value):
    path = _table(tmp_path, "a,s1,pat,1,1,2,3,4")
    args = {"--frame-rate": "10", "--value-range": "0..255", option: value}
    r = convert(path, tmp_path / "o.parquet", "--format", "table", "--grid", "2x2", *[x for kv in args.items() for x in kv])
    assert r.exit_code == 2 and f"{option} must be" in r.output, r.output
    assert not (tmp_path / "o.parquet").exists()


@pytest.mark.parametrize("value", ["0...255", "0..255..", ".5..1", "0..", "0 255", "0..2..3"])
def test_a_malformed_value_range_is_refused_naming_the_option(tmp_path, value):
    path = _table(tmp_path, "a,s1,pat,1,1,2,3,4")
    r = convert(path, tmp_path / "o.parquet", "--format", "table", "--grid", "2x2", "--frame-rate", "10",
                "--value-range", value)
    assert r.exit_code == 2 and "Invalid value for '--value-range': expected LO..HI such as 0..4095" in r.output
    assert f"got {value!r}" in r.output
    assert not (tmp_path / "o.parquet").exists()


def test_a_value_range_the_data_use_a_vanishing_part_of_is_refused(tmp_path):
    # values 1..200 in 0..1e308: a share of 199 / 1e308 = 2e-306
    path = _table(tmp_path, "a,s1,pat,1,1,2,3,200")
    r = convert(path, tmp_path / "o.parquet", "--format", "table", "--grid", "2x2", "--frame-rate", "10",
                "--value-range", "0..1e308")
    assert r.exit_code != 0 and "Traceback" not in r.output, r.output
    assert "--value-range 0..1e+308: the data's values span only 1..200, 2e-306 of that range" in r.output
    assert not (tmp_path / "o.parquet").exists()
    # a millionth is still used: values 1..200 in 0..1.99e8 pass
    r = convert(path, tmp_path / "o.parquet", "--format", "table", "--grid", "2x2", "--frame-rate", "10",
                "--value-range", "0..1.99e8")
    assert r.exit_code == 0, r.output


def test_frame_rate_and_value_range_from_python_are_checked_alike(tmp_path):
    path = _table(tmp_path, "a,s1,pat,1,1,2,3,4")
    with pytest.raises(TouchbenchError, match="--frame-rate must be a finite number of frames per second above 0"):
        _read(path, frame_rate=float("inf"))
    with pytest.raises(TouchbenchError, match="--value-range must be two finite numbers"):
        _read(path, value_range=(0.0, float("inf")))
    with pytest.raises(TouchbenchError, match="--value-range: the range's low end must be below its high end"):
        _read(path, value_range=(5.0, 5.0))
