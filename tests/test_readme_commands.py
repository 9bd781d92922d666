"""The README's example commands that name files shipped in the repository run as written: each runs
through the CLI in an empty folder holding a copy of the shipped files it names, at the same paths."""

from __future__ import annotations

import shlex
import shutil
import subprocess
from pathlib import Path

from click.testing import CliRunner
from helpers import code_blocks

from touchbench.cli.main import cli
from touchbench.datasets.model import TouchDataset

ROOT = Path(__file__).resolve().parents[1]


def tracked_paths(root: Path = ROOT) -> set[str]:
    """Every file git tracks under ``root`` and every folder above one (``a/b/c.csv`` gives ``a``,
    ``a/b`` and ``a/b/c.csv``): what a fresh clone holds, whatever the README's commands wrote since."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True, check=True).stdout
    paths = set()
    for f in listed.decode("utf-8").split("\0"):
        parts = f.split("/")
        paths.update("/".join(parts[:i]) for i in range(1, len(parts) + 1) if f)
    return paths


def shipped_commands(readme: str, tracked: set[str]) -> list[tuple[list[str], list[str]]]:
    """(command, the shipped paths it names) of every ``touchbench`` line of the README's shell blocks
    that names a file or folder git tracks (``tracked``): the README's own outputs (``out/``,
    ``results/...``) are untracked, so they never add a command."""
    found = []
    for block in code_blocks(readme, "bash"):
        for line in block.splitlines():
            if not line.startswith("touchbench "):
                continue
            cmd = shlex.split(line.split(" #")[0])
            paths = [a for a in cmd[1:] if "/" in a and a.rstrip("/") in tracked]
            if paths:
                found.append((cmd, paths))
    return found


def test_commands_are_picked_by_the_tracked_paths_alone():
    readme = "```bash\ntouchbench data export x --out out/\ntouchbench data convert out/ b.parquet\n" \
             "touchbench data convert docs/formats/study s.parquet  # comment/with a slash\n```\n"
    # out/ is what the first command writes: on disk after following the README, never tracked
    picked = shipped_commands(readme, {"docs", "docs/formats", "docs/formats/study"})
    assert picked == [(["touchbench", "data", "convert", "docs/formats/study", "s.parquet"], ["docs/formats/study"])]
    assert shipped_commands(readme, {"docs"}) == []
    tracked = tracked_paths()
    assert {"README.md", "docs", "docs/formats", "docs/formats/study"} <= tracked and "results/README.md" in tracked


def test_readme_commands_on_shipped_files_run_as_written(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    commands = shipped_commands((ROOT / "README.md").read_text(encoding="utf-8"), tracked_paths())
    picked = [(" ".join(c), paths) for c, paths in commands]
    assert [c[1:4] for c, _ in commands] == [["data", "convert", "docs/formats/study"],
                                             ["data", "convert", "docs/formats/my-skin.csv"]], (
        f"the README's commands that name a path git tracks (picked for this test): {picked}; "
        "only the shipped study recording and the own-sensor example are expected: a new README command on a shipped file "
        "belongs in this list, with what it should write checked below")
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


def written_paths(readme: str) -> list[str]:
    """What the README's ``touchbench`` lines write in the folder they run in: every ``--out``/``-o``
    value, ``data convert``'s second path and ``data export``'s folder."""
    written = []
    for block in code_blocks(readme, "bash"):
        for line in block.splitlines():
            if not line.startswith("touchbench "):
                continue
            cmd = shlex.split(line.split(" #")[0])
            written += [cmd[i + 1] for i, a in enumerate(cmd[:-1]) if a in ("--out", "-o")]
            positional = [a for a in cmd[3:] if not a.startswith("-")]
            if cmd[1:3] == ["data", "convert"]:
                written.append(positional[1])
            if cmd[1:3] == ["data", "export"]:
                written.append(positional[-1])
    return written


def test_what_the_readme_writes_is_ignored_by_git():
    written = written_paths((ROOT / "README.md").read_text(encoding="utf-8"))
    assert {"out/", "back.parquet", "report/", "live.tbm", "gaus.joblib"} <= set(written)
    listed = subprocess.run(["git", "check-ignore", "--no-index", *written], cwd=ROOT, capture_output=True,
                            text=True).stdout.split()
    assert sorted(set(written) - set(listed)) == [], "README outputs that `git status` would show"
    # the shipped figures and example files stay tracked
    shipped = ["docs/figures/stream-haart-trade.png", "docs/formats/my-skin.csv", "results/README.md"]
    assert subprocess.run(["git", "check-ignore", "--no-index", *shipped], cwd=ROOT).returncode == 1
