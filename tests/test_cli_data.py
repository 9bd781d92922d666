"""``touchbench data`` from the command line."""

from __future__ import annotations

import re
import shlex

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.datasets.model import SensorSpec, TouchDataset


def test_data_list_and_sample_info():
    r = CliRunner().invoke(cli, ["data", "list"])
    assert r.exit_code == 0 and "haart-challenge" in r.output and "haart-sample" in r.output
    r = CliRunner().invoke(cli, ["data", "info", "haart-sample"])
    assert r.exit_code == 0, r.output
    assert "captures      14" in r.output and "subjects      2" in r.output


def test_unknown_dataset_suggests():
    r = CliRunner().invoke(cli, ["data", "info", "haart-challange"])
    assert r.exit_code == 3
    assert "did you mean 'haart-challenge'" in r.output


@pytest.mark.realdata
def test_data_info_haart(real_haart, tb_cache):
    r = CliRunner().invoke(cli, ["data", "info", "haart", "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    out = r.output
    assert "captures      830" in out and "subjects      10" in out and "gestures      7" in out
    assert "frames        432..432" in out
    assert "placeholders  10 byte-identical copies found" in out
    assert "140729-5/140729-5foamnonepat.csv.gz = s05-foam-short-pat" in out


@pytest.mark.realdata
def test_cli_export_then_convert_round_trip(real_haart_challenge, tb_cache, tmp_path):
    r = CliRunner().invoke(cli, ["data", "export", "haart-challenge", str(tmp_path), "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    out = tmp_path / "back.parquet"
    r = CliRunner().invoke(cli, ["data", "convert", str(tmp_path), str(out), "--format", "challenge-csv"])
    assert r.exit_code == 0, r.output
    assert real_haart_challenge.content_hash in r.output
    r = CliRunner().invoke(cli, ["data", "info", "haart-challenge", "--cache-dir", str(tb_cache)])
    assert "by split      test: 251, train: 578" in r.output


def test_the_convert_example_runs_and_the_name_is_the_output_file_s(tmp_path, monkeypatch):
    """The example of `data convert --help`, run as shown on a 6 x 6 table written here; the dataset is
    named after the file written (mine.parquet: mine), not after the source."""
    r = CliRunner().invoke(cli, ["data", "convert", "--help"])
    line = re.search(r"Example:\n\s+touchbench (data convert .*)", r.output).group(1)
    args = shlex.split(line)
    assert args[2:4] == ["frames.csv", "mine.parquet"]
    rows = [{"capture_id": f"c{c}", "subject": "s1", "gesture": "pat", "frame": t,
             **{f"cell{i}": 3 * c + t + i for i in range(36)}} for c in range(2) for t in range(1, 4)]
    monkeypatch.chdir(tmp_path)
    pd.DataFrame(rows).to_csv("frames.csv", index=False)
    r = CliRunner().invoke(cli, [*args, "--value-range", "0..255"])
    assert r.exit_code == 0, r.output
    ds = TouchDataset.from_parquet(tmp_path / "mine.parquet")
    assert ds.name == "mine" and ds.sensor.grid == (6, 6) and ds.sensor.frame_rate == 50.0
    assert int(ds.captures[1][2, 5, 5]) == 3 * 1 + 3 + 35  # capture c1, frame 3, cell 35 (row 5, column 5)


def test_info_prints_provenance_lists_one_entry_a_line(tmp_path):
    ds = TouchDataset("p", [np.zeros((2, 1, 1), np.uint8)], pd.DataFrame(
        {"capture_id": ["a"], "subject": ["s1"], "gesture": ["pat"]}), SensorSpec("x", (1, 1), 10.0, (0.0, 255.0)))
    ds.provenance = {"placeholders": [], "cut": ["a.csv: 12 s", "b.csv: 30 s"], "note": "as recorded"}
    ds.to_parquet(tmp_path / "p.parquet")
    r = CliRunner().invoke(cli, ["data", "info", str(tmp_path / "p.parquet")])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert "placeholders  none (no byte-identical copies)" in lines
    assert lines[lines.index("cut           (2)") + 1:][:3] == ["  a.csv: 12 s", "  b.csv: 30 s", "note          as recorded"]
    assert "range 0..255" in r.output and not any(ln.endswith(":") for ln in lines)


def test_the_demo_without_the_data_says_it_ran_the_synthetic_scene(tmp_path, monkeypatch):
    """The run and the leaderboard are stubs here (the demo's own run is tested from a wheel in
    test_packaging.py): what is checked is what the demo says around them."""
    import click

    import touchbench.cli.reports as reports
    import touchbench.cli.run as run

    ran = []
    monkeypatch.setattr(run, "run", click.Command("run", callback=lambda **kw: ran.append(kw["protocol"])))
    monkeypatch.setattr(reports, "leaderboard", click.Command("leaderboard", callback=lambda **kw: click.echo("BOARD")))
    monkeypatch.setenv("TOUCHBENCH_DATA_DIR", str(tmp_path / "nowhere"))
    r = CliRunner().invoke(cli, ["demo", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    assert ran == ["tiny"]
    before, after = r.output.split("BOARD")
    assert "real HAART data not found: running the built-in tiny scene (synthetic data) instead" in before
    assert f"looked for the haart data in {tmp_path / 'nowhere' / 'haart'}" in before
    assert "These results are of the synthetic scene 'tiny', not of real data" in after
    assert "Set TOUCHBENCH_DATA_DIR to the folder that holds haart/" in after


def test_the_demo_prints_its_numbers_once(tmp_path, monkeypatch):
    """The demo's run prints no summary of its own: each method's accuracy is in the leaderboard's
    row for it alone."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_DATA_DIR", str(tmp_path / "nowhere"))
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    r = CliRunner().invoke(cli, ["demo", "--jobs", "1"], env={"COLUMNS": "250"})
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    scores = pd.read_parquet(tmp_path / "results" / "tiny" / "scores.parquet")
    for (feats, clf), acc in scores.groupby(["features", "classifier"])["accuracy"].mean().items():
        rows = [ln for ln in lines if re.search(rf"│ {re.escape(f'{feats} / {clf}')} +│", ln)]
        assert len(rows) == 1 and f"{100 * acc:.1f}" in rows[0], r.output
        # every line that gives this accuracy is a row of the leaderboard's table
        assert all("│" in ln for ln in lines if f" {100 * acc:.1f} " in ln), r.output
