"""One run at a time per results folder: an operating-system lock on ``.touchbench.lock``.

:func:`hold` holds the lock (``flock``, released by the kernel when the process ends, however it
ends) and writes who holds it into the file; a second run waits for it or says who holds it
(:class:`ResultsBusyError`). :func:`make_results_dir` creates a results folder, naming a dangling
symbolic link on the way.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import socket
import time
from pathlib import Path
from typing import Iterator

from ..core.errors import TouchbenchError, WriteError

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "ResultsBusyError", "hold", "make_results_dir"]

LOCK_NAME = ".touchbench.lock"
LOCK_POLL_SECONDS = 0.5


class ResultsBusyError(TouchbenchError):
    """Another run holds the results folder."""


@contextlib.contextmanager
def hold(root: Path, wait: float = 0.0, command: str = "touchbench run") -> Iterator[None]:
    """Hold the results folder ``root`` for one run; a second run waits up to ``wait`` seconds,
    then :class:`ResultsBusyError` names who holds it (pid, host, start, command).

    The lock is the kernel's (``flock``): it ends with the process that holds it, even one
    killed with SIGKILL, so there is never a stale lock to clear by hand.
    """
    path = root / LOCK_NAME
    fd, writable = _open_lock(path)
    if fd is None:  # a folder this process may only read, without a lock file: nothing can write here
        yield
        return
    try:
        deadline = time.monotonic() + max(0.0, wait)
        while not _try_lock(fd):
            if time.monotonic() >= deadline:
                raise ResultsBusyError(f"{root}: in use by another run ({_holder(path)}); "
                                       "wait for it to end (run with --wait SECONDS) or choose another --out")
            time.sleep(LOCK_POLL_SECONDS)
        if writable:
            holder = {"pid": os.getpid(), "host": socket.gethostname(),
                      "since": time.strftime("%Y-%m-%d %H:%M:%S"), "command": command}
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(holder) + "\n").encode(), 0)
        try:
            yield
        finally:
            if writable:
                os.ftruncate(fd, 0)
    finally:
        os.close(fd)  # closing the descriptor releases the lock


def _dangling_link(path: Path) -> Path | None:
    """``path`` or the first of its parents that is a symbolic link to nothing, else None."""
    for p in (path, *path.parents):
        if p.is_symlink() and not p.exists():
            return p
    return None


def make_results_dir(root: Path) -> None:
    """Create the results folder ``root`` (and its parents); a dangling symbolic link on the way is
    named with its target."""
    link = _dangling_link(root)
    if link is not None:
        raise TouchbenchError(f"{root}: {link} is a dangling symbolic link (to {os.readlink(link)}, which "
                              "does not exist): create its target, or choose another results folder with --out")
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise WriteError(root, e) from None


def _open_lock(path: Path) -> tuple[int | None, bool]:
    """The lock file's descriptor and whether it is writable. In a folder this process may only read,
    the lock file is opened to read (``flock`` still works) or, where there is none, not at all (None):
    a run that finds nothing to do writes nothing, and one that has work fails at its first write."""
    make_results_dir(path.parent)
    try:
        return os.open(path, os.O_RDWR | os.O_CREAT, 0o666), True
    except OSError as e:
        if e.errno not in (errno.EACCES, errno.EPERM, errno.EROFS) or not path.parent.is_dir():
            raise WriteError(path, e) from None
    try:
        return os.open(path, os.O_RDONLY), False
    except OSError:
        return None, False


def _try_lock(fd: int) -> bool:
    if fcntl is None:  # pragma: no cover - no advisory locks on this platform: one run assumed
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


def _holder(path: Path) -> str:
    """Who holds the lock, as its holder wrote it."""
    try:
        h = json.loads(path.read_text() or "{}")
    except (OSError, json.JSONDecodeError):
        h = {}
    if not h:
        return "a process that has not said who it is yet"
    return f"pid {h.get('pid')} on {h.get('host')}, since {h.get('since')}: {h.get('command')}"
