"""The file-format registry: every format listed once, the commands' choices
and dispatch taken from it, unknown and unwritable formats refused clearly.

Expected values: the format names and options as the readers' documentation
states them (challenge CSV, CoST, HAART raw, table, touchbench Parquet), and
frames written here by hand.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from snapshots.registries import builtin_names, snapshot

from touchbench.cli.main import cli
from touchbench.core.errors import TouchbenchError, UnknownNameError
from touchbench.datasets.formats import FORMATS
from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.deploy.model import TrainedModel
from touchbench.deploy.predict import read_data
from touchbench.deploy.stream import load_replay

SENSOR = SensorSpec("mine", grid=(2, 3), frame_rate=10.0, value_range=(0.0, 255.0))


def _long_csv(path):
    """Two captures in the table format, one row per frame: capture c1 frames 0..3 hold 10 t + cell, c2 frames 0..4 hold 100 + cell."""
    rows, expected = [], {}
    for cid, n, base in (("c1", 4, None), ("c2", 5, 100)):
        frames = []
        for t in range(n):
            cells = [(10 * t if base is None else base) + i for i in range(6)]
            rows.append({"capture_id": cid, "frame": t + 1, "subject": "s1", "gesture": "pat",
                         **{f"cell{i + 1}": v for i, v in enumerate(cells)}})
            frames.append(np.array(cells, dtype=float).reshape(2, 3))
        expected[cid] = np.stack(frames)
    pd.DataFrame(rows).to_csv(path, index=False)
    return expected


class _Model:
    """What the readers use of a trained model: its sensor and the sensor check."""

    sensor = SENSOR
    manifest: dict = {}
    check_sensor = TrainedModel.check_sensor


def test_every_format_is_registered_once_with_its_capabilities():
    assert builtin_names(FORMATS) == snapshot()["file formats"]  # tests/snapshots/registry-names.json
    writers = sorted(e.name for e in FORMATS.entries() if e.obj.writer is not None)
    assert writers == ["challenge-csv", "parquet"]
    assert FORMATS.get("challenge-csv").reads == "file or folder"
    assert [o.flag for o in FORMATS.get("table").options][:3] == ["--grid", "--frame-rate", "--value-range"]
    assert FORMATS.get("table").reads == "file or folder" and FORMATS.get("haart-raw").reads == "folder"
    assert [o.flag for o in FORMATS.get("haart-raw").options] == ["--pattern", "--recording-window", "--recording-seconds",
                                                                   "--frame-rate", "--short-recordings"]
    assert all(not e.obj.options for e in FORMATS.entries() if e.name not in ("table", "haart-raw"))
    assert not any(o.required for e in FORMATS.entries() for o in e.obj.options)
    assert all(e.obj.replay for e in FORMATS.entries())


def test_data_formats_lists_every_format_with_options():
    r = CliRunner().invoke(cli, ["data", "formats"])
    assert r.exit_code == 0, r.output
    for e in FORMATS.entries():
        assert f"{e.name:14s} {e.description}" in r.output
    assert "--grid HxW" in r.output and "--frame-rate" in r.output


def test_command_choices_come_from_the_registry():
    runner = CliRunner()
    assert "[challenge-csv|cost-csv|haart-raw|parquet|table]" in runner.invoke(cli, ["data", "convert", "--help"]).output
    assert "[challenge-csv|parquet]" in runner.invoke(cli, ["data", "export", "--help"]).output
    for cmd in ("predict", "stream"):
        assert "[auto|challenge-csv|cost-csv|haart-raw|parquet|table]" in runner.invoke(cli, [cmd, "--help"]).output


def test_unknown_format_gets_did_you_mean(tmp_path):
    with pytest.raises(UnknownNameError, match="did you mean 'cost-csv'"):
        FORMATS.get("cost-cvs")
    with pytest.raises(UnknownNameError, match="did you mean 'table'"):
        read_data(str(tmp_path / "x.csv"), "tabel")
    (tmp_path / "x.csv").write_text("a\n1\n")
    r = CliRunner().invoke(cli, ["data", "convert", str(tmp_path / "x.csv"), str(tmp_path / "o.parquet"),
                                 "--format", "tabel"])
    assert r.exit_code == 2 and "unknown file format 'tabel'; did you mean 'table'?" in r.output


def test_format_without_writer_is_refused_for_export(tmp_path):
    r = CliRunner().invoke(cli, ["data", "export", "haart-sample", str(tmp_path), "--format", "cost-csv"])
    assert r.exit_code == 2
    assert "touchbench cannot write the cost-csv format (it can: challenge-csv, parquet)" in r.output
    assert list(tmp_path.iterdir()) == []
    ds = TouchDataset("d", [np.zeros((3, 2, 3))], pd.DataFrame({"capture_id": ["c"], "subject": ["s"],
                                                                 "gesture": ["g"]}), SENSOR)
    with pytest.raises(TouchbenchError, match="reads the cost-csv format but does not write it"):
        FORMATS.get("cost-csv").write(ds, tmp_path)


def test_table_format_options_from_the_command_line_or_the_model(tmp_path):
    expected = _long_csv(tmp_path / "mine.csv")
    out = tmp_path / "mine.parquet"
    r = CliRunner().invoke(cli, ["data", "convert", str(tmp_path / "mine.csv"), str(out), "--format", "table",
                                 "--grid", "2x3", "--frame-rate", "10", "--value-range", "0..255"])
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(out)
    assert ds.name == "mine" and ds.sensor.grid == (2, 3) and ds.sensor.frame_rate == 10.0
    assert ds.sensor.value_range == (0.0, 255.0)
    np.testing.assert_array_equal(ds.captures[1], expected["c2"])
    # predict: the model's sensor supplies grid, value range and name; the frame rate is the recording's
    with pytest.raises(TouchbenchError, match="does not say its frame rate: give --frame-rate"):
        read_data(str(tmp_path / "mine.csv"), "table", _Model())
    got = read_data(str(tmp_path / "mine.csv"), "table", _Model(), frame_rate=SENSOR.frame_rate)
    assert got.sensor == SENSOR
    np.testing.assert_array_equal(got.captures[0], expected["c1"])
    # without a model or a time column the frame rate is required; the grid, since cell1..cell6 do not say it
    with pytest.raises(TouchbenchError, match="does not say its frame rate: give --frame-rate"):
        FORMATS.get("table").read(tmp_path / "mine.csv", grid=(2, 3))
    with pytest.raises(TouchbenchError, match="6 cell columns: give the grid"):
        FORMATS.get("table").read(tmp_path / "mine.csv", frame_rate=10.0)
    with pytest.raises(TouchbenchError, match="goes with --format"):
        read_data(str(tmp_path / "mine.csv"), "auto", _Model(), frame_rate=10.0)
    # an option of another format is refused, not ignored
    with pytest.raises(TouchbenchError, match="the cost-csv format takes no option 'grid'"):
        FORMATS.get("cost-csv").read(tmp_path / "mine.csv", grid=(2, 3))


def test_parquet_round_trip_through_the_registry(tmp_path):
    ds = TouchDataset("d", [np.arange(18, dtype=np.uint8).reshape(3, 2, 3)],
                      pd.DataFrame({"capture_id": ["c"], "subject": ["s"], "gesture": ["g"]}), SENSOR)
    (path,) = FORMATS.get("parquet").write(ds, tmp_path)
    assert path == tmp_path / "d.parquet"
    back = FORMATS.get("parquet").read(path, name="renamed")
    assert back.name == "renamed"
    np.testing.assert_array_equal(back.captures[0], ds.captures[0])


def test_stream_replays_a_registered_format(tmp_path):
    expected = _long_csv(tmp_path / "mine.csv")
    frames, rate, what = load_replay(tmp_path / "mine.csv", _Model(), "c2", fmt="table", frame_rate=10.0)
    np.testing.assert_array_equal(frames, expected["c2"])
    assert rate == 10.0 and what == "mine.csv: capture c2"
    frames, _, what = load_replay(tmp_path / "mine.csv", _Model(), None, fmt="table", frame_rate=10.0)
    np.testing.assert_array_equal(frames, np.concatenate([expected["c1"], expected["c2"]]))
    assert what == "mine.csv: 2 captures"
    r = CliRunner().invoke(cli, ["stream", str(tmp_path / "m.joblib"), "-", "--format", "table"])
    assert r.exit_code == 2 and "--format is for files" in r.output
