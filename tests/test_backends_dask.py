"""A protocol run on a real Dask cluster (separate worker processes on
127.0.0.1) gives the same predictions and scores as the local run.

The cluster is started once for the module and always shut down; a
watchdog (``faulthandler``) ends the test process if anything hangs for
more than ten minutes.
"""

from __future__ import annotations

import faulthandler

import pytest
from click.testing import CliRunner

distributed = pytest.importorskip("distributed")

# one worker of pytest-xdist runs the Dask and the Ray tests, one after the other: the Dask cluster is
# started once, and the two never run their own worker processes at the same time
pytestmark = pytest.mark.xdist_group("clusters")

from touchbench.cli.main import cli  # noqa: E402
from touchbench.engine import run_protocol  # noqa: E402
from touchbench.engine.backends import supports_generator, use_backend  # noqa: E402
from touchbench.engine.testing import components_for_tests, register_test_components  # noqa: E402
from touchbench.core.errors import TouchbenchError  # noqa: E402
from test_backends_shared import PROTOCOL, assert_same_results, env, write_protocol  # noqa: E402,F401  (env: a fixture)
from touchbench.protocols.loading import parse_protocol  # noqa: E402
from helpers import SUBPROCESS_HANG_S  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    faulthandler.dump_traceback_later(SUBPROCESS_HANG_S, exit=True)
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None, worker_dashboard_address=None)
    try:
        yield lc.scheduler_address
    finally:
        lc.close(timeout=SUBPROCESS_HANG_S)
        faulthandler.cancel_dump_traceback_later()


def test_dask_run_equals_local_run(cluster, env):
    with components_for_tests():
        # test-centered learns from the training fold: fold-dependent features on the workers too
        proto = write_protocol(env, extra="  - [test-centered]\n")
        local = run_protocol(proto, env / "local", jobs=1)
        with use_backend("dask", cluster, cache_root=env / "cache") as info:
            assert info.name == "dask" and info.n_jobs == 2
            assert supports_generator()
            dist = run_protocol(proto, env / "dask", jobs=info.n_jobs, force=True, worker_setup=register_test_components)
    assert local.n_tasks == dist.n_tasks == dist.n_ran == 3 * 3 * 2
    assert_same_results(env / "local", env / "dask")


def test_cli_run_against_a_scheduler(cluster, env):
    write_protocol(env)
    res = CliRunner().invoke(cli, ["run", str(env / "p.yaml"), "--out", str(env / "local")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["run", str(env / "p.yaml"), "--out", str(env / "dask"), "--backend", "dask",
                                   "--scheduler", cluster], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    assert f"backend dask at {cluster}" in res.stderr
    assert_same_results(env / "local", env / "dask")


def test_backend_option_errors(env):
    write_protocol(env)
    res = CliRunner().invoke(cli, ["run", str(env / "p.yaml"), "--scheduler", "tcp://127.0.0.1:8786"])
    assert res.exit_code == 3 and "--scheduler is the Dask scheduler's address" in res.output
    with pytest.raises(TouchbenchError, match="unknown backend"):
        with use_backend("spark"):
            pass


def test_dask_workers_see_installed_plugins(cluster, env, example_plugin):
    # no worker_setup: the workers load the plugin by themselves, like the command line does
    text = PROTOCOL.replace("features:\n  - [msd]\n  - [{{name: sd, params: {{preset: haart}}}}, {{name: bmh, params: {{preset: haart}}}}]\n",
                           "features:\n  - [example-pressure-stats]\n")
    text = text.replace("  - zhou-knn\n", "  - example-nearest-centroid\n")
    (env / "p.yaml").write_text(text.format(data=env / "data.parquet", extra=""))
    proto = parse_protocol((env / "p.yaml").read_text(), env / "p.yaml")
    assert [c.name for c in proto.classifier_entries()] == ["gaus-rf", "example-nearest-centroid"]
    local = run_protocol(proto, env / "local", jobs=1)
    with use_backend("dask", cluster, cache_root=env / "cache") as info:
        dist = run_protocol(proto, env / "dask", jobs=info.n_jobs, force=True)
    assert local.n_tasks == dist.n_tasks == dist.n_ran == 3 * 2
    assert_same_results(env / "local", env / "dask")


class _SlowToExit(distributed.diagnostics.plugin.WorkerPlugin):
    """Keeps a worker's shutdown busy past its nanny's 4 s, as a loaded machine does."""

    def teardown(self, worker):
        import time

        time.sleep(6)


def test_a_successful_run_closes_its_local_cluster_without_messages(env):
    import logging

    class Collect(logging.Handler):
        def emit(self, record):
            said.append(record.getMessage())

    said: list[str] = []
    handler = Collect()
    logging.getLogger("distributed.nanny").addHandler(handler)  # what it prints on stderr
    try:
        write_protocol(env)
        with use_backend("dask", None, cache_root=env / "cache") as info:
            distributed.default_client().register_plugin(_SlowToExit())
            res = run_protocol(env / "p.yaml", env / "dask", jobs=info.n_jobs)
    finally:
        logging.getLogger("distributed.nanny").removeHandler(handler)
    assert res.n_failed == 0 and res.n_ran == res.n_tasks > 0
    assert not [m for m in said if "still alive" in m], said
