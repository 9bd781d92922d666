"""A protocol run through Ray's joblib backend gives the same predictions and
scores as the local run. Runs where ray is installed (CI installs the
``dist`` extra); a local Ray instance with two CPUs, shut down afterwards,
and a ``faulthandler`` watchdog against hangs.
"""

from __future__ import annotations

import faulthandler

import pytest

ray = pytest.importorskip("ray")

# one worker of pytest-xdist runs the Dask and the Ray tests, one after the other: the Dask cluster is
# started once, and the two never run their own worker processes at the same time
pytestmark = pytest.mark.xdist_group("clusters")

from touchbench.engine import run_protocol  # noqa: E402
from touchbench.engine.backends import supports_generator, use_backend  # noqa: E402
from touchbench.engine.testing import components_for_tests, register_test_components  # noqa: E402

from helpers import SUBPROCESS_HANG_S  # noqa: E402
from test_backends_shared import assert_same_results, env, write_protocol  # noqa: E402,F401  (env: a fixture)


@pytest.fixture(scope="module")
def ray_local():
    faulthandler.dump_traceback_later(SUBPROCESS_HANG_S, exit=True)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield
    finally:
        ray.shutdown()
        faulthandler.cancel_dump_traceback_later()


def test_ray_run_equals_local_run(ray_local, env):
    with components_for_tests():
        proto = write_protocol(env, extra="  - [test-centered]\n")
        local = run_protocol(proto, env / "local", jobs=1)
        with use_backend("ray") as info:
            assert info.name == "ray" and info.n_jobs == 2
            assert not supports_generator()  # results come back as one list
            dist = run_protocol(proto, env / "ray", jobs=info.n_jobs, force=True, worker_setup=register_test_components)
        assert ray.is_initialized()  # a Ray started by the caller is left running
    assert local.n_tasks == dist.n_tasks == dist.n_ran == 3 * 3 * 2
    assert_same_results(env / "local", env / "ray")
