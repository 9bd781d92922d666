"""Run a protocol's tasks on an existing distributed engine (Dask or Ray) through joblib.

The run engine (:mod:`touchbench.engine.runner`) runs its independent tasks
-- one per (repetition, fold, feature combination, classifier) -- and the
chunks of the feature cache with ``joblib.Parallel``. :func:`use_backend`
makes joblib send them to a cluster instead of local processes:

``dask``
    ``distributed.Client(address)`` (a running scheduler, e.g.
    ``tcp://10.0.0.5:8786``; without an address a ``LocalCluster`` of worker
    processes on 127.0.0.1 is started) and ``joblib.parallel_config(
    backend="dask")``. Parallelism: every worker thread of the cluster.
``ray``
    ``ray.init(address=...)`` (``auto``, ``ray://host:10001`` or
    ``host:6379``; without an address a local Ray instance) and
    ``ray.util.joblib.register_ray()`` + ``parallel_config(backend="ray")``.
    Parallelism: the cluster's CPUs. Ray's joblib backend cannot stream
    results back as they finish, so :func:`supports_generator` tells the
    engine to collect them in one list. Ray's own INFO and WARNING lines are
    kept out of the run's messages (``_RAY_QUIET``); its errors still show.

Same results as a local run: a task's classifier seed is derived from its
identity and every task runs single-threaded (``tasks.single_thread``), so
no prediction depends on where or in which order a task ran.

Shared files: a worker reads the dataset's Parquet copy and the feature
cache from the paths the client gives (``TOUCHBENCH_CACHE_DIR``), so on a
cluster of several machines that folder must be on a shared file system
mounted at the same path, and touchbench (same version) installed on every
worker. :func:`check_dask_workers` verifies both before any work.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

from joblib import Parallel, parallel_config
from joblib.parallel import BACKENDS as JOBLIB_BACKENDS
from joblib.parallel import get_active_backend

from ..core.errors import TouchbenchError
from ..core.threads import available_cpus
from ..core.version import __version__

__all__ = ["BACKENDS", "BackendInfo", "backend_for_run", "backend_options", "check_dask_workers", "check_jobs",
           "end_with_parent", "is_local_backend", "local_jobs", "parallel", "run_setup", "supports_generator", "use_backend"]

BACKENDS = ("local", "dask", "ray")


@dataclass
class BackendInfo:
    name: str
    address: str | None
    n_jobs: int | None  # parallel slots the backend offers (None: local, use --jobs)
    notes: list[str] = field(default_factory=list)


_SETUP_DONE: set = set()

PARENT_POLL_SECONDS = 0.5


def parallel(n_jobs: int, *, ordered: bool = True) -> Parallel:
    """The one ``joblib.Parallel`` of the engine: results streamed back when the backend can
    (in order, or as they finish with ``ordered=False``); with loky (the local backend), worker processes
    that end with the process that started them (:func:`end_with_parent`)."""
    kwargs: dict = {}
    if type(get_active_backend()[0]) is JOBLIB_BACKENDS.get("loky"):  # exactly loky: Ray's pool derives from
        kwargs = {"initializer": end_with_parent, "initargs": (os.getpid(),)}  # a local backend
    if not supports_generator():
        return Parallel(n_jobs=n_jobs, return_as="list", **kwargs)
    return Parallel(n_jobs=n_jobs, return_as="generator" if ordered else "generator_unordered", **kwargs)


def end_with_parent(parent: int) -> None:
    """Start-up of a local worker process: end it as soon as its parent ``parent`` is gone.

    joblib's worker processes outlive a parent killed with SIGKILL or SIGTERM (they wait for
    work for minutes, holding the dataset in memory). Run by loky in each worker before it takes
    any task: a worker whose parent already died exits at once; otherwise a daemon thread polls
    the parent's pid and exits the worker when it changes (the worker was re-parented). Dask and
    Ray workers are not children of the run and get no such start-up."""
    if os.getppid() != parent:
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_POLL_SECONDS)
        os._exit(1)

    threading.Thread(target=watch, name="touchbench-parent-watch", daemon=True).start()


def run_setup(setup: Callable[[], None] | None) -> None:
    """Call a worker set-up function once per process (a picklable module-level function, e.g.
    registering plug-in components)."""
    if setup is None:
        return
    key = (getattr(setup, "__module__", ""), getattr(setup, "__qualname__", repr(setup)))
    if key not in _SETUP_DONE:
        setup()
        _SETUP_DONE.add(key)


def check_jobs(jobs: int) -> None:
    """Refuse a number of parallel tasks that means nothing (0, or below -1)."""
    if not isinstance(jobs, int) or isinstance(jobs, bool) or jobs == 0 or jobs < -1:
        raise TouchbenchError(f"--jobs must be a positive number of parallel tasks, or -1 for one per CPU; got {jobs!r}")


def local_jobs(jobs: int) -> tuple[int, str | None]:
    """``--jobs`` for local worker processes: ``(jobs to use, warning or None)``.

    -1 is one per CPU available to this process (its affinity mask); more
    than those is capped to them, with a warning (each worker is a process
    with its own copy of the libraries: more workers than CPUs add memory,
    not speed)."""
    check_jobs(jobs)
    n = available_cpus()
    if jobs == -1:
        return n, None
    if jobs > n:
        return n, f"--jobs {jobs} is more than the {n} CPU(s) available to this process: running {n} at a time"
    return jobs, None


def is_local_backend() -> bool:
    """Whether joblib's active backend runs on this machine (processes or threads, not a cluster)."""
    backend, _ = get_active_backend()
    local = tuple(JOBLIB_BACKENDS[n] for n in ("loky", "multiprocessing", "threading", "sequential") if n in JOBLIB_BACKENDS)
    return isinstance(backend, local)


def supports_generator() -> bool:
    """Whether the active joblib backend can return results as they finish
    (``return_as="generator"`` / ``"generator_unordered"``)."""

    backend, _ = get_active_backend()
    return bool(getattr(backend, "supports_return_generator", True))


def _probe(cache_root: str) -> dict:
    """Run on a worker: its touchbench version and whether it sees the cache folder."""

    p = Path(cache_root)
    return {"version": __version__, "cache_visible": p.is_dir() and os.access(p, os.W_OK)}


def check_dask_workers(client, cache_root: str | Path) -> None:
    """Refuse a cluster whose workers lack touchbench, run another version, or
    do not see the shared cache folder (raises :class:`TouchbenchError`)."""

    root = str(Path(cache_root).resolve())
    Path(root).mkdir(parents=True, exist_ok=True)
    try:
        answers = client.run(_probe, root)
    except Exception as e:  # an ImportError on the worker side comes back here
        raise TouchbenchError(f"the Dask workers cannot run touchbench ({type(e).__name__}: {e}); "
                              "install the same touchbench on every worker") from None
    if not answers:
        raise TouchbenchError("the Dask cluster has no workers")
    for worker, a in sorted(answers.items()):
        if a["version"] != __version__:
            raise TouchbenchError(f"Dask worker {worker} runs touchbench {a['version']}, this client "
                                  f"{__version__}; install the same version everywhere")
        if not a["cache_visible"]:
            raise TouchbenchError(f"Dask worker {worker} cannot write the cache folder {root}: put "
                                  "TOUCHBENCH_CACHE_DIR on a file system shared by the client and every worker, "
                                  "at the same path")


@contextlib.contextmanager
def use_backend(name: str = "local", address: str | None = None, *, cache_root: str | Path | None = None,
                timeout: float = 60.0, local_workers: int = 2) -> Iterator[BackendInfo]:
    """Route joblib's parallel calls inside the block to backend ``name``.

    ``address``: the Dask scheduler or Ray cluster address (None: start a
    local one: ``local_workers`` Dask worker processes on 127.0.0.1, or a
    local Ray instance). ``cache_root``: checked to be visible from the Dask
    workers. Clusters started here are shut down on exit; a cluster given by
    address is only disconnected from.
    """
    if name not in BACKENDS:
        raise TouchbenchError(f"unknown backend {name!r} (known: {', '.join(BACKENDS)})")
    if name == "local":
        if address:
            raise TouchbenchError("--scheduler/--address need --backend dask or ray")
        yield BackendInfo("local", None, None)
    elif name == "dask":
        with _use_dask(address, cache_root, timeout, local_workers) as info:
            yield info
    else:
        with _use_ray(address, local_workers) as info:
            yield info


def _dask_client(address: str | None, timeout: float, local_workers: int):
    """A Dask client of the scheduler at ``address``, or of a local cluster started here (then also returned)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise TouchbenchError("--backend dask needs the dist extra: pip install 'touchbench[dist]'") from None
    cluster = None
    try:
        if address:
            client = Client(address, timeout=timeout)
        else:
            cluster = LocalCluster(n_workers=local_workers, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address=None)
            client = Client(cluster, timeout=timeout)
    except OSError as e:
        if cluster is not None:
            cluster.close()
        raise TouchbenchError(f"cannot connect to the Dask scheduler {address!r}: {e}") from None
    return client, cluster


@contextlib.contextmanager
def _use_dask(address: str | None, cache_root: str | Path | None, timeout: float,
              local_workers: int) -> Iterator[BackendInfo]:
    """:func:`use_backend` on Dask: the workers checked, the client (and a cluster started here) closed on exit."""
    client, cluster = _dask_client(address, timeout, local_workers)
    done = False
    try:
        client.wait_for_workers(1, timeout=timeout)
        if cache_root is not None:
            check_dask_workers(client, cache_root)
        n = sum(client.nthreads().values())
        with parallel_config(backend="dask"):
            yield BackendInfo("dask", client.scheduler.address, n)
        done = True
    finally:
        client.close()
        if cluster is not None:
            with _quiet_worker_kills(done):
                cluster.close()


class _WorkerKillFilter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith("Worker process still alive after")


@contextlib.contextmanager
def _quiet_worker_kills(active: bool) -> Iterator[None]:
    """After a run that ended well, the local cluster's shutdown does not report the worker processes its
    nannies end when they take more than their 4 s to exit (a loaded machine): the work is done and saved.
    After a failure, every message is kept."""
    nanny = logging.getLogger("distributed.nanny")
    quiet = _WorkerKillFilter()
    if active:
        nanny.addFilter(quiet)
    try:
        yield
    finally:
        nanny.removeFilter(quiet)


# What ray.init is given when touchbench starts or joins a Ray: no dashboard, the workers' output kept in
# Ray's log files (a failed task's error still comes back as an exception), and the driver's "ray" logger
# at ERROR: Ray's own INFO and WARNING lines (the local instance started, token authentication, the
# multiprocessing pool's unsupported 'context') stay out of the run's messages; its errors still show.
_RAY_QUIET = {"include_dashboard": False, "log_to_driver": False, "configure_logging": True,
             "logging_level": logging.ERROR}


@contextlib.contextmanager
def _use_ray(address: str | None, local_workers: int) -> Iterator[BackendInfo]:
    """:func:`use_backend` on Ray: a Ray instance started here (none if one runs) is shut down on exit, and
    the "ray" logger's level, which ``ray.init`` sets, is given back."""
    try:
        import ray
        from ray.util.joblib import register_ray
    except ImportError:
        raise TouchbenchError("--backend ray needs the dist extra: pip install 'touchbench[dist]'") from None
    started = not ray.is_initialized()
    ray_logger = logging.getLogger("ray")
    level = ray_logger.level
    if started:
        where = {"address": address} if address else {"num_cpus": local_workers}
        try:
            ray.init(**where, **_RAY_QUIET)
        except (ConnectionError, RuntimeError, ValueError) as e:
            ray_logger.setLevel(level)
            raise TouchbenchError(f"cannot connect to the Ray cluster {address!r}: {e}") from None
    try:
        register_ray()
        n = int(ray.cluster_resources().get("CPU", 1))
        with parallel_config(backend="ray"):
            yield BackendInfo("ray", address, n, ["Ray's joblib backend returns results when all tasks finish"])
    finally:
        if started:
            ray.shutdown()
            ray_logger.setLevel(level)


@contextlib.contextmanager
def backend_for_run(backend: str, scheduler: str | None, address: str | None, cache_root: str | Path | None,
                    jobs: int) -> Iterator[int]:
    """The ``touchbench run`` options -> an active backend; yields the ``jobs`` to run with.

    With a cluster, ``jobs`` is the cluster's parallelism (at least 2, so
    that the engine goes through joblib even on a one-worker cluster).
    """
    if scheduler and backend != "dask":
        raise TouchbenchError("--scheduler is the Dask scheduler's address: use it with --backend dask")
    if address and backend != "ray":
        raise TouchbenchError("--address is the Ray cluster's address: use it with --backend ray")
    import click

    with use_backend(backend, scheduler or address, cache_root=cache_root) as info:
        if info.n_jobs is None:
            jobs, warning = local_jobs(jobs)
            if warning:
                click.echo(f"warning: {warning}", err=True)
            yield jobs
            return

        click.echo(f"backend {info.name} at {info.address or 'a local cluster'}: {info.n_jobs} parallel slots", err=True)
        for n in info.notes:
            click.echo(f"note: {n}", err=True)
        yield max(2, info.n_jobs)


def backend_options(f):
    """The ``--backend``, ``--scheduler`` and ``--address`` options of ``touchbench run``."""
    import click

    f = click.option("--address", default=None, metavar="ADDRESS",
                     help="Ray cluster address for --backend ray (auto, ray://HOST:10001 or HOST:6379; "
                          "default: a local Ray).")(f)
    f = click.option("--scheduler", default=None, metavar="ADDRESS",
                     help="Dask scheduler address for --backend dask (tcp://HOST:8786; default: a local cluster).")(f)
    f = click.option("--backend", type=click.Choice(BACKENDS), default="local", show_default=True,
                     help="Where tasks run: local processes (--jobs), a Dask or a Ray cluster (the cluster's size).")(f)
    return f
