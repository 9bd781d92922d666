"""The README's example commands that name files shipped in the repository run as written: each runs
through the CLI in an empty folder holding a copy of the shipped files it names, at the same paths."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

from click.testing import CliRunner
from helpers import code_blocks

from touchbench.cli.main import cli
from touchbench.datasets.model import TouchDataset

ROOT = Path(__file__).resolve().parents[1]


def shipped_commands() -> list[tuple[list[str], list[str]]]:
    """(command, the shipped paths it names) of every ``touchbench`` line of the README's shell blocks
    that names a file or folder of the repository."""
    found = []
    for block in code_blocks((ROOT / "README.md").read_text(encoding="utf-8"), "bash"):
        for line in block.splitlines():
            if not line.startswith("touchbench "):
                continue
            cmd = shlex.split(line.split(" #")[0])
            paths = [a for a in cmd[1:] if "/" in a and (ROOT / a).exists()]
            if paths:
                found.append((cmd, paths))
    return found


def test_readme_commands_on_shipped_files_run_as_written(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    commands = shipped_commands()
    assert [c[1:4] for c, _ in commands] == [["data", "convert", "docs/formats/study"]]
    for cmd, paths in commands:
        for p in paths:
            src, dst = ROOT / p, tmp_path / p
            dst.parent.mkdir(parents=True, exist_ok=True)
            (shutil.copytree if src.is_dir() else shutil.copy)(src, dst)
        r = CliRunner().invoke(cli, cmd[1:])
        assert r.exit_code == 0, (cmd, r.output)
    # the shipped recording (docs/formats/make_examples.py): 3 frames, a press of 300 on the inner
    # 4 x 4 cells in the second frame only, kept whole (it is far shorter than HAART's 10 s)
    study = TouchDataset.from_parquet(tmp_path / "study.parquet")
    assert len(study) == 1 and study.captures[0].shape == (3, 8, 8)
    assert int(study.captures[0][1].sum()) == 300 * 16 and int(study.captures[0][[0, 2]].sum()) == 0
