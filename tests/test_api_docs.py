"""The API reference builds with pdoc without a single warning (``make api-docs``; the ``dev`` extra
installs pdoc), and documents the user-level names on the package's page."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import SUBPROCESS_HANG_S

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "docs" / "build_api_docs.py"


def _builder():
    spec = importlib.util.spec_from_file_location("build_api_docs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_reference_builds_without_warnings(tmp_path):
    if importlib.util.find_spec("pdoc") is None:
        msg = "pdoc is not installed (pip install -e '.[dev]'; make setup does)"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(msg)
        pytest.skip(msg)
    out = tmp_path / "api"
    r = subprocess.run([sys.executable, str(SCRIPT), str(out)], capture_output=True, text=True,
                       timeout=SUBPROCESS_HANG_S, check=False)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    page = (out / "touchbench.html").read_text(encoding="utf-8")
    for name in ("load_dataset", "make_feature_set", "run_protocol", "leaderboard", "FeaturePipeline"):
        assert f'id="{name}"' in page, name
    # every public module has its page, private ones none
    assert (out / "touchbench" / "features" / "gaus_sd.html").is_file()
    assert (out / "touchbench" / "engine" / "runner.html").is_file()
    assert not list(out.rglob("_util.html"))


def test_any_problem_fails_the_build(tmp_path, monkeypatch, capsys):
    builder = _builder()
    monkeypatch.setattr(builder, "build", lambda out: ["x.py:3: UserWarning: something pdoc said"])
    assert builder.main([str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "x.py:3: UserWarning: something pdoc said" in err and "1 warning(s)" in err


def test_modules_a_package_walk_reaches_are_not_named_twice():
    """pdoc walks a package's submodules unless its ``__all__`` leaves them out."""
    specs = _builder().specs(["touchbench", "touchbench.cli", "touchbench.cli.run", "touchbench.features",
                              "touchbench.features.gaus_sd"])
    # touchbench.__all__ and touchbench.features.__all__ name no submodule; touchbench.cli has no __all__
    assert specs == ["touchbench", "touchbench.cli", "touchbench.features", "touchbench.features.gaus_sd"]
