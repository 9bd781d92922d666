"""Shared fixtures. Real-data tests use ``real_haart_dir`` and
``real_socialtouch_dir`` (``real_icmi15_study2``, ``real_inflatable_skin_dir``): they fail (not skip) when
CI=true and ../shared/data/haart (or ../shared/data/socialtouch, icmi15-study2, inflatable-skin) is missing. Plugin tests use
``example_plugin``: it fails (not skips) when CI=true and the example plugin
(examples/touchbench-plugin-example, installed by ``make setup``) is not
installed."""

from __future__ import annotations

import os

import pytest

from touchbench.core.paths import data_dir


def pytest_configure(config):
    """Under ``--dist loadgroup`` (``make test``) pytest-xdist sends the tests of one ``xdist_group`` to
    one worker by appending the group to each test's id; pytest 9.2 keeps the id where pytest-xdist
    3.8 cannot append it, and xdist then ignores every group without a word: the aeon tests compile
    aeon's loops in both workers, the cluster tests run beside each other. Refuse that pair."""
    from importlib.metadata import version

    from packaging.version import Version

    if getattr(config.option, "dist", None) != "loadgroup":
        return
    if Version(pytest.__version__) >= Version("9.2") and Version(version("pytest-xdist")) <= Version("3.8.0"):
        raise pytest.UsageError(f"pytest {pytest.__version__} with pytest-xdist {version('pytest-xdist')}: "
                                "--dist loadgroup would ignore every xdist_group; install the pins of "
                                "constraints.txt (pip install -c constraints.txt -e '.[dev]')")


def _missing(msg: str):
    """Fail under CI=true (CI must have everything), skip elsewhere."""
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(msg)
    pytest.skip(msg)


def _haart_dir():
    d = data_dir() / "haart"
    if not (d / "raw").is_dir():
        _missing(f"real HAART data not found at {d} (set TOUCHBENCH_DATA_DIR)")
    return d


def _icmi15_study2_dir():
    d = data_dir() / "icmi15-study2"
    if not (d / "raw").is_dir():
        _missing(f"real icmi15-study2 data not found at {d} (set TOUCHBENCH_DATA_DIR)")
    return d


def _inflatable_skin_dir():
    d = data_dir() / "inflatable-skin"
    if not (d / "raw").is_dir():
        _missing(f"real inflatable-skin data not found at {d} (set TOUCHBENCH_DATA_DIR)")
    return d


def _socialtouch_dir():
    d = data_dir() / "socialtouch"
    if not (d / "raw").is_dir():
        _missing(f"real SocialTouch data not found at {d} (set TOUCHBENCH_DATA_DIR)")
    return d


EXAMPLE_PLUGIN = "touchbench-plugin-example"


@pytest.fixture(scope="session")
def example_plugin():
    """The example plugin's distribution name and version, when it is installed."""
    from importlib import metadata

    try:
        return EXAMPLE_PLUGIN, metadata.version(EXAMPLE_PLUGIN)
    except metadata.PackageNotFoundError:
        _missing(f"the example plugin is not installed (pip install ./examples/{EXAMPLE_PLUGIN}; make setup does)")


@pytest.fixture(scope="session")
def real_haart_dir():
    return _haart_dir()


@pytest.fixture(scope="session")
def tb_cache(tmp_path_factory):
    """A cache directory shared by the session's tests (not the user's). Under pytest-xdist every
    worker of the run shares it (the run's temporary folder, above the workers' own), so a real
    dataset is converted once per run, not once per worker; two workers converting the same one at
    the same moment both write a whole file under a name of their own and rename it into place
    (tests/test_datasets_haart.py runs that race)."""
    base = tmp_path_factory.getbasetemp()
    d = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "tbcache"
    d.mkdir(exist_ok=True)
    os.environ["TOUCHBENCH_CACHE_DIR"] = str(d)
    return d


@pytest.fixture(scope="session")
def real_haart(real_haart_dir, tb_cache):
    from touchbench.catalog import load_dataset

    return load_dataset("haart", cache_dir=tb_cache)


@pytest.fixture(scope="session")
def real_haart_challenge(real_haart_dir, tb_cache):
    from touchbench.catalog import load_dataset

    return load_dataset("haart-challenge", cache_dir=tb_cache)


@pytest.fixture(scope="session")
def real_icmi15_study2(tb_cache):
    """The HAART organisers' second study, HAART's window (fails under CI=true when the data is missing)."""
    from touchbench.catalog import load_dataset

    _icmi15_study2_dir()
    return load_dataset("icmi15-study2", cache_dir=tb_cache)


@pytest.fixture(scope="session")
def real_inflatable_skin_dir():
    """The inflatable robot skin's recordings (fails under CI=true when the data is missing)."""
    return _inflatable_skin_dir()


@pytest.fixture(scope="session")
def real_socialtouch_dir():
    return _socialtouch_dir()


@pytest.fixture(scope="session")
def real_socialtouch(real_socialtouch_dir, tb_cache):
    """SocialTouch resampled to its fixed 12 Hz (the dataset the protocols use)."""
    from touchbench.catalog import load_dataset

    return load_dataset("socialtouch", cache_dir=tb_cache)


@pytest.fixture(scope="session")
def real_socialtouch_recorded(real_socialtouch_dir, tb_cache):
    """SocialTouch as recorded (irregular frames, ``time_ms``)."""
    from touchbench.catalog import load_dataset

    return load_dataset("socialtouch-recorded", cache_dir=tb_cache)


@pytest.fixture
def engine_env(tmp_path, monkeypatch):
    """For engine tests: a private cache, the test's folder as working
    directory, and the test-only feature sets and classifiers registered."""
    from touchbench.engine.testing import components_for_tests

    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    with components_for_tests():
        yield


@pytest.fixture
def touchbench_warnings(caplog, monkeypatch):
    """``caplog`` holding the warnings touchbench logs (a command run in-process before may have
    stopped its logger passing them on)."""
    import logging

    monkeypatch.setattr(logging.getLogger("touchbench"), "propagate", True)
    caplog.set_level(logging.WARNING, logger="touchbench")
    return caplog
