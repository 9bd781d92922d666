"""The examples in these modules' docstrings run as written (doctest), with values worked out by
hand. A listed set, not the whole package: importing every module is slow. The README's "Python
API" examples run in tests/test_readme_api.py."""

from __future__ import annotations

import doctest
import importlib

import pytest

#: the modules whose docstring examples run, and the least number of examples each holds (a module
#: whose examples were lost fails)
MODULES = {
    "touchbench.core.registry": 3,
    "touchbench.core.paramdoc": 3,
    "touchbench.core.hashing": 1,
    "touchbench.core.constraints": 4,
    "touchbench.datasets.windows": 1,
    "touchbench.reports.bootstrap": 4,
    "touchbench.streams.rules": 6,
    "touchbench.features.raw": 4,
    "touchbench.features.live_summary": 7,
    "touchbench.classifiers.two_stage": 11,
    "touchbench.protocols.seeding": 2,
    "touchbench.protocols.entries": 1,
    "touchbench.scenes": 1,
}


@pytest.mark.parametrize("name", sorted(MODULES))
def test_docstring_examples_run(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS, report=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed (run doctest -v)"
    assert result.attempted >= MODULES[name]
