"""The README's "Bring your own sensor" section runs as written: its Python
block makes the dataset, its YAML block is the protocol, its shell block's
``touchbench`` lines run (in an empty folder, through the CLI)."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import pandas as pd
from click.testing import CliRunner
from helpers import code_blocks as blocks
from helpers import readme_section as section

from touchbench.cli.main import cli


def test_bring_your_own_sensor_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    text = section("Bring your own sensor")
    (python,), (protocol,), (shell,) = blocks(text, "python"), blocks(text, "yaml"), blocks(text, "bash")
    exec(compile(python, "README.md", "exec"), {})
    Path("my-skin.yaml").write_text(protocol)
    commands = [shlex.split(line.split("#")[0]) for line in shell.splitlines() if line.startswith("touchbench ")]
    assert [c[1] for c in commands] == ["protocols", "run", "leaderboard"]
    for cmd in commands:
        r = CliRunner().invoke(cli, cmd[1:], catch_exceptions=False)
        assert r.exit_code == 0, r.output
    scores = pd.read_parquet(tmp_path / "results" / "my-skin" / "scores.parquet")
    assert (scores["status"] == "ok").all() and len(scores) == 2 * 3  # two methods x three people
    # the methods used the sensor of the data: msd's 12 statistics per cell of a 6 x 6 grid
    cached = {json.loads(f.read_text())["name"]: json.loads(f.read_text())["n_columns"]
              for f in (tmp_path / "cache" / "features").glob("*.json")}
    assert cached["msd"] == 12 * 6 * 6 and "touch-rhythm" in cached
    assert scores.groupby("classifier")["accuracy"].mean().min() > 0.5  # a pat is told from a stroke
