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
from helpers import SUBPROCESS_HANG_S

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
    # with TB_TEST_CORE_ONLY set, the extras' packages cannot be imported: touchbench installed alone
    Path(site, "_tb_core_only.py").write_text(CORE_ONLY_FINDER.format(names=EXTRA_PACKAGES))
    Path(site, "_tb_core_only.pth").write_text("import _tb_core_only\n")
    return bin_dir


#: the packages of the extras (peers, deep, dist, xgboost), which a core install lacks
EXTRA_PACKAGES = ("aeon", "torch", "xgboost", "dask", "distributed", "ray", "tsml_eval")
#: an import hook that finds none of them (as if not installed) when TB_TEST_CORE_ONLY is set
CORE_ONLY_FINDER = """import os, sys


class _NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {names!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


if os.environ.get("TB_TEST_CORE_ONLY"):
    sys.meta_path.insert(0, _NotInstalled())
"""


def tb(installed: Path, cwd: Path, *args: str, core_only: bool = False) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("TOUCHBENCH_", "PYTHON"))}
    env.update({"TB_TEST_CORE_ONLY": "1"} if core_only else {})
    env["TOUCHBENCH_CACHE_DIR"] = str(cwd / "cache")
    env["TOUCHBENCH_DATA_DIR"] = str(cwd / "no-data-here")
    return subprocess.run([str(installed / "touchbench"), *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=SUBPROCESS_HANG_S)


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


@pytest.fixture(scope="module")
def tiny_ran(installed, tmp_path_factory) -> Path:
    """A folder outside the repository, empty before touchbench alone (no extra importable) ran ``tiny``
    there: the run the demo and the report tests below start from (``tiny`` is run once for the module)."""
    d = tmp_path_factory.mktemp("elsewhere")
    r = tb(installed, d, "run", "tiny", "--no-progress", core_only=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return d


def test_run_tiny_from_an_empty_folder_with_touchbench_alone(installed, tiny_ran):
    blocked = subprocess.run([str(installed / "python"), "-c", "import aeon"], cwd=tiny_ran, capture_output=True,
                             text=True, env={**os.environ, "TB_TEST_CORE_ONLY": "1"})
    assert blocked.returncode != 0 and "ModuleNotFoundError" in blocked.stderr  # the extras are out of reach
    assert (tiny_ran / "results" / "tiny" / "scores.parquet").is_file()


def test_demo_from_the_folder(installed, tiny_ran):
    r = tb(installed, tiny_ran, "demo", "--jobs", "1")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "running the built-in tiny scene" in r.stderr
    assert "zhou-lda" in r.stdout  # the leaderboard of the tiny run


def test_report_and_the_shipped_references_with_touchbench_alone(installed, tiny_ran):
    r = tb(installed, tiny_ran, "report", "results/tiny", "--out", "report", core_only=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (tiny_ran / "report" / "report.html").is_file()
    r = tb(installed, tiny_ran, "reference", "list", core_only=True)
    assert r.returncode == 0 and {"tiny", "demo-haart", "haart-loso-msd-rf"} <= {
        line.split()[0] for line in r.stdout.splitlines()}, r.stdout + r.stderr
    r = tb(installed, tiny_ran, "leaderboard", "results/tiny", "--reference", "tiny", "--json", core_only=True)
    assert r.returncode == 0 and "beside reference tiny" in r.stderr, r.stdout + r.stderr
