"""Thread limits for deterministic, non-oversubscribed work."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
from typing import Iterator

from threadpoolctl import ThreadpoolController

__all__ = ["available_cpus", "single_thread"]


def available_cpus() -> int:
    """The CPUs this process may run on: its affinity mask where the system has one
    (a container or ``taskset`` limits it), else the machine's count."""
    getaffinity = getattr(os, "sched_getaffinity", None)
    if getaffinity is not None:
        try:
            return max(1, len(getaffinity(0)))
        except OSError:  # pragma: no cover - a system that lists the call but refuses it
            pass
    return os.cpu_count() or 1


@functools.lru_cache(maxsize=1)
def _thread_pools(n_modules: int) -> ThreadpoolController:
    """The native thread pools of the process: found once (a scan of the loaded libraries), again
    when the number of imported modules ``n_modules`` changed (an import may have loaded a library
    with a pool of its own)."""
    return ThreadpoolController()


@contextlib.contextmanager
def single_thread() -> Iterator[None]:
    """BLAS/OpenMP and torch (when already imported) limited to one thread."""
    torch = sys.modules.get("torch")
    prev = torch.get_num_threads() if torch is not None else None
    with _thread_pools(len(sys.modules)).limit(limits=1):
        if torch is not None:
            torch.set_num_threads(1)
        try:
            yield
        finally:
            if torch is not None and prev is not None:
                torch.set_num_threads(prev)
