"""How much memory touchbench lets one thing it makes take: the one place that reads the
available memory, so that a stream's buffer, a synthetic scene and an augmented training set
are refused up front, before any of it is made, rather than pushing the machine into swap.

The available memory is the smallest that the system says: ``MemAvailable`` of
``/proc/meminfo`` (Linux: free memory plus the page cache it can drop), else the free pages
(``os.sysconf``), and the room left under the process's control group limit (cgroup v2
``memory.max`` less ``memory.current``, v1 ``memory.limit_in_bytes`` less
``memory.usage_in_bytes``), where there is one: a container's limit is usually far below the
machine's memory, and a process that runs into it stalls rather than fails; and the room left
under the process's address-space limit (``ulimit -v``, ``RLIMIT_AS``: the soft limit less the
process's virtual size, ``VmSize`` of ``/proc/self/status``), where there is one: past it an
allocation fails with a MemoryError.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["FALLBACK_BYTES", "available_memory", "describe_bytes", "memory_limit"]

#: what :func:`memory_limit` allows where the system says nothing about its memory
FALLBACK_BYTES = 2 * 2**30
#: the share of the available memory one thing may take (its copies while it is written out,
#: and everything else the process holds, need the rest)
SHARE = 4

_CGROUPS = (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
            ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"))


def _read_int(path: str) -> int | None:
    try:
        text = Path(path).read_text().strip()
    except (OSError, ValueError):
        return None
    return int(text) if text.isdigit() else None  # "max": no limit


def _meminfo_available() -> int | None:
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _free_pages() -> int | None:
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # not every system says
        return None


def _cgroup_room() -> int | None:
    for limit_path, usage_path in _CGROUPS:
        limit, usage = _read_int(limit_path), _read_int(usage_path)
        if limit is not None and usage is not None and limit < 2**60:  # v1 writes a huge number for no limit
            return max(0, limit - usage)
    return None


def _virtual_size() -> int | None:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _address_space_room() -> int | None:
    """The bytes the process may still map under its address-space limit (``RLIMIT_AS``), None
    where there is no limit (or no ``resource`` module: Windows)."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, AttributeError, OSError, ValueError):
        return None
    if soft == resource.RLIM_INFINITY or soft < 0:
        return None
    used = _virtual_size()
    return max(0, soft - (used or 0))


def available_memory() -> int | None:
    """Bytes of memory available to this process now (module docstring), None where the system
    does not say."""
    system = _meminfo_available()
    if system is None:
        system = _free_pages()
    known = [v for v in (system, _cgroup_room(), _address_space_room()) if v is not None]
    return min(known) if known else None


def memory_limit(at_most: int | None = None) -> int:
    """The most bytes one thing may take: a quarter of :func:`available_memory`
    (:data:`FALLBACK_BYTES` where the system does not say), or ``at_most`` when that is less."""
    available = available_memory()
    limit = FALLBACK_BYTES if available is None else available // SHARE
    return int(limit if at_most is None else min(at_most, limit))


def describe_bytes(n: int) -> str:
    """``n`` bytes as a refusal says it: in bytes below a MiB, else in MiB, GiB or TiB."""
    if n < 2**20:
        return f"{n:,} bytes"
    unit = next(u for u in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20)) if n >= u[1])
    return f"{n / unit[1]:,.1f} {unit[0]}" if unit[0] != "MiB" else f"{n / unit[1]:,.0f} MiB"
