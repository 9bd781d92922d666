"""Files touchbench writes get the mode the user's umask gives, 0o666 less the umask, as the files
of any other program do: a cache or results folder shared between users or workers is as readable as
the user asked for (``umask 022``: 0644; ``umask 077``: 0600)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pytest

from touchbench.core.atomic import atomic_write_bytes, atomic_write_parquet
from touchbench.datasets.tables import write_csv_atomic
from touchbench.engine.runner import run_protocol
from touchbench.protocols.loading import parse_protocol
from touchbench.reports.leaderboard import leaderboard
from touchbench.reports.rendering import write_outputs


@pytest.fixture
def set_umask():
    """Set the process's umask for one test; the previous one is restored after it."""
    previous = os.umask(0o022)
    os.umask(previous)
    yield os.umask
    os.umask(previous)


def modes(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): stat.S_IMODE(p.stat().st_mode) for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_atomic_writes_follow_the_umask(tmp_path, set_umask, umask, mode):
    set_umask(umask)
    atomic_write_bytes(tmp_path / "a.bin", b"data")
    atomic_write_parquet(tmp_path / "b.parquet", pd.DataFrame({"x": [1, 2]}))
    write_csv_atomic([(tmp_path / "c.csv", pa.table({"x": [1]})), (tmp_path / "d.csv", pa.table({"y": [2]}))])
    assert modes(tmp_path) == {"a.bin": mode, "b.parquet": mode, "c.csv": mode, "d.csv": mode}
    assert (tmp_path / "a.bin").read_bytes() == b"data"


def test_a_replaced_file_takes_the_umask_too(tmp_path, set_umask):
    set_umask(0o077)
    atomic_write_bytes(tmp_path / "a.bin", b"old")
    set_umask(0o022)
    atomic_write_bytes(tmp_path / "a.bin", b"new")
    assert modes(tmp_path) == {"a.bin": 0o644}


def test_a_run_writes_every_file_with_the_umask(tmp_path, set_umask, monkeypatch):
    """Results, manifest, task fragments, the feature and dataset caches and the leaderboard files."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    set_umask(0o027)
    protocol = parse_protocol("name: modes\ndataset: scene:tiny\nscheme: loso\nfeatures: [[msd]]\n"
                              "classifiers: [zhou-lda]\nseed: 0\n")
    result = run_protocol(protocol, jobs=1, progress=False)
    write_outputs(leaderboard(result), tmp_path / "board", ["md", "csv", "json"])
    written = modes(tmp_path)
    assert {"results/modes/scores.parquet", "results/modes/manifest.json", "board/leaderboard.md"} <= set(written)
    assert any(k.startswith("cache/features/") for k in written)
    assert {k: m for k, m in written.items() if m != 0o640} == {}
