"""`--backend ray` keeps Ray's own log lines out of the run's messages: what ``ray.init`` is given (a stub
Ray, no ray needed), the "ray" logger given back, a connection error still reported; and, where ray is
installed, a real run of ``tiny`` on a local Ray whose standard error holds touchbench's lines only."""

from __future__ import annotations

import logging
import os
import re
import subprocess
import sys
import types

import pytest
from joblib.parallel import BACKENDS as JOBLIB_BACKENDS
from joblib.parallel import SequentialBackend

from helpers import SUBPROCESS_HANG_S
from touchbench.core.errors import TouchbenchError
from touchbench.engine.backends import use_backend


@pytest.fixture()
def ray_logger():
    """The "ray" logger, its level given back (with ``setLevel``, which clears the loggers' caches) after."""
    logger = logging.getLogger("ray")
    level = logger.level
    yield logger
    logger.setLevel(level)


def stub_ray(monkeypatch, cpus=3.0, init_error=None):
    """A ``ray`` module that records what ``ray.init`` is given; its joblib backend runs in the process."""
    calls = {"init": [], "shutdown": 0}
    state = {"up": False}

    def init(**kwargs):
        calls["init"].append(kwargs)
        logging.getLogger("ray").setLevel(kwargs.get("logging_level", logging.INFO))  # first, as ray.init does
        if init_error is not None:
            raise init_error
        state["up"] = True

    def shutdown():
        calls["shutdown"] += 1
        state["up"] = False

    ray = types.ModuleType("ray")
    ray.init, ray.shutdown = init, shutdown
    ray.is_initialized = lambda: state["up"]
    ray.cluster_resources = lambda: {"CPU": cpus}
    util, joblib_mod = types.ModuleType("ray.util"), types.ModuleType("ray.util.joblib")
    joblib_mod.register_ray = lambda: None
    ray.util, util.joblib = util, joblib_mod
    for name, mod in (("ray", ray), ("ray.util", util), ("ray.util.joblib", joblib_mod)):
        monkeypatch.setitem(sys.modules, name, mod)
    monkeypatch.setitem(JOBLIB_BACKENDS, "ray", SequentialBackend)
    return calls


@pytest.mark.parametrize("address, where", [(None, {"num_cpus": 2}), ("10.0.0.5:6379", {"address": "10.0.0.5:6379"})])
def test_ray_init_is_told_to_keep_its_own_lines_quiet(monkeypatch, ray_logger, address, where):
    calls = stub_ray(monkeypatch)
    ray_logger.setLevel(logging.WARNING)
    with use_backend("ray", address, local_workers=2) as info:
        assert (info.name, info.n_jobs) == ("ray", 3)
        assert ray_logger.level == logging.ERROR  # during the run: Ray's INFO and WARNING lines are not shown
    assert calls["init"] == [{**where, "include_dashboard": False, "log_to_driver": False,
                              "configure_logging": True, "logging_level": logging.ERROR}]
    assert calls["shutdown"] == 1
    assert ray_logger.level == logging.WARNING  # given back after the run


def test_a_ray_the_caller_started_keeps_its_settings(monkeypatch, ray_logger):
    calls = stub_ray(monkeypatch)
    sys.modules["ray"].init(num_cpus=1)  # the caller's own Ray, with Ray's default logging
    with use_backend("ray", None, local_workers=2):
        pass
    assert len(calls["init"]) == 1 and calls["shutdown"] == 0
    assert ray_logger.level == logging.INFO  # what the caller's ray.init set


def test_a_connection_error_is_still_reported(monkeypatch, ray_logger):
    stub_ray(monkeypatch, init_error=ConnectionError("could not reach 10.0.0.5:6379"))
    ray_logger.setLevel(logging.INFO)
    with pytest.raises(TouchbenchError, match=r"cannot connect to the Ray cluster '10\.0\.0\.5:6379': could not reach"):
        with use_backend("ray", "10.0.0.5:6379", local_workers=2):
            pass
    assert ray_logger.level == logging.INFO  # given back after the failed start too


# Ray's log format ("2026-11-29 03:34:40,575<TAB>INFO worker.py:2038 -- Started a local Ray instance.")
RAY_LOG_LINE = re.compile(r"\t(DEBUG|INFO|WARNING|ERROR|CRITICAL) \S+\.py:\d+ -- ")
OURS = ("backend ray at a local cluster", "note: Ray's joblib backend")


def foreign_lines(stderr: str) -> list[str]:
    """The lines of ``stderr`` that come from Ray, not from touchbench: Ray's log format, a worker's line
    (``(raylet)``, ``(pid=...)``), or a line naming Ray other than touchbench's two about the backend."""
    return [line for line in stderr.splitlines()
            if RAY_LOG_LINE.search(line) or (re.search(r"\bray|\(pid=\d", line, re.I) and not line.startswith(OURS))]


def test_foreign_lines_are_told_apart():
    ours = "tiny: scene:tiny (32 captures)\nbackend ray at a local cluster: 2 parallel slots\n" \
           "note: Ray's joblib backend returns results when all tasks finish\nran 24 task(s)\n"
    theirs = ["2026-11-29 03:34:40,575\tINFO worker.py:2038 -- Started a local Ray instance.",
              "2026-11-29 03:34:43,902\tWARNING pool.py:602 -- The 'context' argument is not supported using ray.",
              "(raylet) a worker died", "(pid=4242) a worker's print"]
    assert foreign_lines(ours) == []
    assert foreign_lines(ours + "\n".join(theirs)) == theirs


@pytest.mark.xdist_group("clusters")  # never beside the Dask and Ray tests' own worker processes
def test_a_real_ray_run_prints_no_line_of_rays(tmp_path):
    pytest.importorskip("ray")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path), "TOUCHBENCH_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("RAY_ADDRESS", None)  # a local Ray of its own
    r = subprocess.run([sys.executable, "-m", "touchbench.cli.main", "run", "tiny", "--backend", "ray", "--no-progress"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=SUBPROCESS_HANG_S)
    assert r.returncode == 0, r.stderr
    assert "ran 24 task(s), skipped 0 finished, 0 failed" in r.stderr  # 4 subjects x 3 feature sets x 2 classifiers
    assert foreign_lines(r.stderr) == [], r.stderr
