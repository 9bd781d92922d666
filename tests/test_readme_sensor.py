"""The README's "Bring your own sensor" walkthrough runs as written, and so does every command of
docs/data-formats.md: the example files of docs/formats/ are copied into an empty folder, the
protocol of the README's YAML block is written there, and each ``touchbench`` line of the shell
blocks runs through the CLI."""

from __future__ import annotations

import json
import shlex
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
from click.testing import CliRunner
from helpers import code_blocks as blocks
from helpers import readme_section as section

from touchbench.cli.main import cli
from touchbench.datasets.model import TouchDataset

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "docs" / "formats"


def _commands(shell: str) -> list[list[str]]:
    return [shlex.split(line.split(" #")[0]) for line in shell.splitlines() if line.startswith("touchbench ")]


def _run(cmd: list[str]) -> str:
    r = CliRunner().invoke(cli, cmd[1:], catch_exceptions=False)
    assert r.exit_code == 0, (cmd, r.output)
    return r.output


def test_bring_your_own_sensor_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    text = section("Bring your own sensor")
    (protocol,), (shell,) = blocks(text, "yaml"), blocks(text, "bash")
    (tmp_path / "docs" / "formats").mkdir(parents=True)  # the README names the shipped file by its path
    shutil.copy(EXAMPLES / "my-skin.csv", tmp_path / "docs" / "formats")
    Path("my-skin.yaml").write_text(protocol)
    commands = _commands(shell)
    assert [c[1:3] for c in commands] == [["data", "convert"], ["data", "info"], ["protocols", "validate"],
                                          ["run", "my-skin.yaml"], ["leaderboard", "results/my-skin"],
                                          ["report", "results/my-skin"]]
    outputs = [_run(cmd) for cmd in commands]
    # the rate worked out from the time column: steps of 50 ms (+-3 ms, a dropped frame now and then)
    assert "frame rate estimated from the time column: 20 Hz" in outputs[0]
    ds = TouchDataset.from_parquet(tmp_path / "my-skin.parquet")
    assert ds.sensor.grid == (6, 6) and ds.sensor.value_range == (0.0, 255.0) and len(ds) == 24
    csv = pd.read_csv(EXAMPLES / "my-skin.csv")
    first = csv[csv["take"] == "p1-pat-0"]
    np.testing.assert_array_equal(ds.captures[0].reshape(len(first), 36),
                                  first[[f"r{r}c{c}" for r in range(6) for c in range(6)]].to_numpy())
    assert "captures      24" in outputs[1] and "6 x 6 at 20 Hz" in outputs[1]
    scores = pd.read_parquet(tmp_path / "results" / "my-skin" / "scores.parquet")
    assert (scores["status"] == "ok").all() and len(scores) == 2 * 3  # two methods x three people
    # the methods used the sensor of the data: msd's 12 statistics per cell of a 6 x 6 grid
    cached = {json.loads(f.read_text())["name"]: json.loads(f.read_text())["n_columns"]
              for f in (tmp_path / "cache" / "features").glob("*.json")}
    assert cached["msd"] == 12 * 6 * 6 and "touch-rhythm" in cached
    assert scores.groupby("classifier")["accuracy"].mean().min() > 0.5  # a pat is told from a stroke
    assert "touch-et-fast" in outputs[4] and (tmp_path / "results" / "my-skin-report" / "report.html").is_file()


def test_every_command_of_the_data_formats_page_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    work = tmp_path / "formats"
    shutil.copytree(EXAMPLES, work)
    monkeypatch.chdir(work)
    commands = [c for block in blocks((ROOT / "docs" / "data-formats.md").read_text(), "bash") for c in _commands(block)]
    assert len(commands) == 8
    for cmd in commands:
        _run(cmd)
    cells = TouchDataset.from_parquet(work / "cells.parquet")  # 100 f + 10 r + c, written by hand
    np.testing.assert_array_equal(cells.captures[0], [[[0, 1], [10, 11]], [[100, 101], [110, 111]],
                                                      [[200, 201], [210, 211]]])
    study = TouchDataset.from_parquet(work / "study.parquet")  # a press of 300 on the inner 4 x 4 in frame 2
    assert study.captures[0].shape == (3, 8, 8) and int(study.captures[0][1].sum()) == 300 * 16
    assert int(study.captures[0][[0, 2]].sum()) == 0
    assert len(TouchDataset.from_parquet(work / "cost.parquet")) == 1
    assert len(TouchDataset.from_parquet(work / "sample.parquet")) > 0
