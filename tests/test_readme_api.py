"""The README's "Python API" section runs as written: its Python blocks are
executed in order, in one namespace, in an empty folder with a private
cache. They use data that ships with touchbench (``haart-sample``) and a
synthetic scene, so they need nothing from ../shared/data, under CI=true
or not."""

from __future__ import annotations

import pandas as pd
from helpers import code_blocks, readme_section


def test_python_api_section_runs_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    blocks = code_blocks(readme_section("Python API"), "python")
    assert len(blocks) == 3
    ns: dict = {}
    for i, block in enumerate(blocks):
        exec(compile(block, f"README.md (Python API, block {i + 1})", "exec"), ns)  # noqa: S102

    # block 1: haart-sample's 14 captures of an 8 x 8 grid; msd is 12 statistics per cell
    assert ns["X"].shape == (14, 12 * 8 * 8)
    # block 2: leave-one-subject-out over the tiny scene's 32 captures of 4 subjects
    assert len(ns["ds"]) == 32 and len(ns["folds"]) == ns["ds"].meta["subject"].nunique() == 4
    assert set(ns["test"].meta["subject"]) == {"s01"} and "s01" not in set(ns["train"].meta["subject"])
    assert 0.0 <= ns["accuracy"] <= 1.0
    # block 3: two feature sets x one classifier x four folds, and a leaderboard that ranks them by the
    # mean fold accuracy read back from the results file
    assert ns["result"].n_tasks == 8 and ns["result"].n_failed == 0
    scores = pd.read_parquet(tmp_path / "results" / "api-example" / "scores.parquet")
    mean = scores.groupby("features")["accuracy"].mean().sort_values(ascending=False)
    (board,) = ns["tb"].leaderboard(ns["result"])
    assert list(board.rows["features"]) == list(mean.index)
    assert board.rows["accuracy"].tolist() == mean.tolist()
    assert board.title in capsys.readouterr().out


def test_readme_says_that_ci_run_deletes_the_virtual_environment():
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    script = (root / ".ci" / "run").read_text()
    assert re.search(r"^rm -rf \.venv\b", script, re.M)  # what the README must warn about
    paragraphs = (root / "README.md").read_text().split("\n\n")
    said = [p for p in paragraphs if "`.ci/run`" in p and re.search(r"deletes[^.]*`\.venv/?`", p)]
    assert said, "the README's paragraph on .ci/run must say that it deletes .venv"
