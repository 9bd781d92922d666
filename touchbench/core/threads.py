"""Thread limits for deterministic, non-oversubscribed work."""

from __future__ import annotations

import contextlib
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


_CONTROLLER: list = [None, -1]  # the thread pools found, and how many modules were imported then


def _thread_pools() -> ThreadpoolController:
    """The native thread pools of the process: found once (a scan of the loaded libraries), again
    when a module was imported since (it may have loaded a library with a pool of its own)."""
    if _CONTROLLER[0] is None or _CONTROLLER[1] != len(sys.modules):
        _CONTROLLER[:] = [ThreadpoolController(), len(sys.modules)]
    return _CONTROLLER[0]


@contextlib.contextmanager
def single_thread() -> Iterator[None]:
    """BLAS/OpenMP and torch (when already imported) limited to one thread."""
    torch = sys.modules.get("torch")
    prev = torch.get_num_threads() if torch is not None else None
    with _thread_pools().limit(limits=1):
        if torch is not None:
            torch.set_num_threads(1)
        try:
            yield
        finally:
            if torch is not None and prev is not None:
                torch.set_num_threads(prev)
