"""`make test`'s `--dist loadgroup` keeps each `xdist_group` on one worker: under it, a grouped test's id
carries its group (what pytest-xdist schedules by), and the suite refuses the pytest / pytest-xdist pair
that drops the group (tests/conftest.py)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

import conftest


@pytest.mark.xdist_group("groups-check")
def test_a_grouped_test_carries_its_group_under_loadgroup(request):
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not run under pytest-xdist's --dist loadgroup (make test runs it so)")
    assert request.node.nodeid.endswith("@groups-check"), request.node.nodeid


@pytest.mark.parametrize("pytest_version, refused", [("9.1.1", False), ("9.2.0", True), ("10.0.0", True)])
def test_loadgroup_is_refused_with_a_pytest_that_drops_groups(monkeypatch, pytest_version, refused):
    monkeypatch.setattr(pytest, "__version__", pytest_version)
    monkeypatch.setattr("importlib.metadata.version", lambda name: "3.8.0")
    config = SimpleNamespace(option=SimpleNamespace(dist="loadgroup"))
    if refused:
        with pytest.raises(pytest.UsageError, match="ignore every xdist_group.*constraints.txt"):
            conftest.pytest_configure(config)
    else:
        conftest.pytest_configure(config)
    conftest.pytest_configure(SimpleNamespace(option=SimpleNamespace(dist="load")))  # only loadgroup is checked
