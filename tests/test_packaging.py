"""The package works on its own: built as a wheel, installed (not editable)
into a new virtual environment, and run from an empty folder outside the
repository, it finds its shipped protocols (papers included), its scenes and
its example data."""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent

# one worker of pytest-xdist runs them all: the module's wheel and virtual environment are built once
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("wheel")]


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A new venv with touchbench installed from a freshly built wheel; its bin folder.

    The dependencies come from the test environment through a .pth file (a
    path entry only: the test environment's editable install of touchbench
    is not visible there), so nothing is downloaded.
    """
    root = tmp_path_factory.mktemp("wheel")
    # build from a copy of the sources: setuptools reuses a build/ folder it finds, stale files included
    src = root / "src"
    shutil.copytree(REPO / "touchbench", src / "touchbench", ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (REPO / name).is_file():
            shutil.copy2(REPO / name, src / name)
    wheels = root / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                    "-w", str(wheels), str(src)], check=True, cwd=root)
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    py = bin_dir / "python"
    subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-index",
                    *map(str, wheels.glob("touchbench-*.whl"))], check=True)
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    Path(site, "_test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return bin_dir


def tb(installed: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("TOUCHBENCH_", "PYTHON"))}
    env["TOUCHBENCH_CACHE_DIR"] = str(cwd / "cache")
    env["TOUCHBENCH_DATA_DIR"] = str(cwd / "no-data-here")
    return subprocess.run([str(installed / "touchbench"), *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


@pytest.fixture()
def empty(tmp_path) -> Path:
    d = tmp_path / "elsewhere"
    d.mkdir()
    return d


def test_the_installed_copy_is_the_one_that_runs(installed, empty):
    out = subprocess.run([str(installed / "python"), "-c", "import touchbench; print(touchbench.__file__)"],
                         cwd=empty, capture_output=True, text=True, check=True).stdout
    assert str(installed.parent) in out and str(REPO / "touchbench") not in out


def test_the_wheel_ships_the_type_marker_and_the_license(installed, empty):
    code = ("import pathlib, touchbench; from importlib import metadata; "
            "print((pathlib.Path(touchbench.__file__).parent / 'py.typed').is_file()); "
            "print(sorted(str(f) for f in metadata.files('touchbench') if f.name in ('py.typed', 'LICENSE')))")
    typed, files = subprocess.run([str(installed / "python"), "-c", code], cwd=empty, capture_output=True, text=True,
                                  check=True).stdout.splitlines()
    listed = ast.literal_eval(files)
    assert typed == "True" and len(listed) == 2 and "touchbench/py.typed" in listed
    assert re.fullmatch(r"touchbench-[0-9.]+\.dist-info/licenses/LICENSE", next(f for f in listed if "LICENSE" in f))


def test_protocols_list_shows_every_shipped_protocol(installed, empty):
    r = tb(installed, empty, "protocols", "list")
    assert r.returncode == 0, r.stderr
    shipped = sorted(p.stem for p in (REPO / "touchbench" / "protocols").glob("*.yaml"))
    papers = sorted(p.stem for p in (REPO / "touchbench" / "protocols" / "papers").glob("*.yaml"))
    assert len(shipped) >= 5 and len(papers) >= 10
    for name in shipped:
        assert f"/protocols/{name}.yaml" in r.stdout, name
    for name in papers:
        assert f"/protocols/papers/{name}.yaml" in r.stdout, name


def test_papers_list(installed, empty):
    r = tb(installed, empty, "papers", "list")
    assert r.returncode == 0, r.stderr
    assert "gaus-tables6-7-haart" in r.stdout and "cnn-table2-loso-haart" in r.stdout


def test_run_tiny_and_demo_from_an_empty_folder(installed, empty):
    r = tb(installed, empty, "run", "tiny", "--no-progress")
    assert r.returncode == 0, r.stdout + r.stderr
    assert (empty / "results" / "tiny" / "scores.parquet").is_file()
    r = tb(installed, empty, "demo", "--jobs", "1")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "running the built-in tiny scene" in r.stderr
    assert "zhou-lda" in r.stdout  # the leaderboard of the tiny run
