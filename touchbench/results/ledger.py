"""The ledger of looks at test sets: every run that scores a test set, in the results root.

Choosing among methods by their test accuracy is itself a fit to the test
set: the more methods compared on one test set, and the more often it was
scored, the more optimistic its best number. The ledger lets a reader judge
that. ``<results root>/ledger.jsonl`` holds one JSON line per run that
scored a test set: time, protocol and evaluation, the test set (a SHA-256
of its captures' frames and labels: the same captures are the same test set
whatever the protocol calls them), the methods and whether it was the
``final`` run (``forced`` when a second final run was forced).

A line is appended, under an exclusive ``flock``, and synced to disk
*before* the run computes anything, so an interrupted run still counts as a
look. A line cut short by a crash is skipped when read (and the next append
starts on a new line). :func:`check_final` refuses a second final run on a
test set with other methods than the first final run's, unless forced.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

from ..core.errors import TouchbenchError, WriteError

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LEDGER_NAME", "FinalRunError", "Looks", "check_final", "looks", "read_ledger", "record_look",
           "test_set_hash"]

LEDGER_NAME = "ledger.jsonl"


class FinalRunError(TouchbenchError):
    """A second final run on a test set, with other methods, not forced."""


def test_set_hash(captures: Sequence[np.ndarray], labels: Iterable[Any]) -> str:
    """SHA-256 of a test set: each capture's frames (float64, with their shape) and label, in a
    sorted order, so neither the order nor the capture ids nor the reader change it."""
    items = sorted(hashlib.sha256(f"{np.shape(c)}|{y}".encode() + np.ascontiguousarray(c, dtype=np.float64).tobytes())
                   .hexdigest() for c, y in zip(captures, labels))
    return hashlib.sha256("\n".join(items).encode()).hexdigest()


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[int]:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o666)
    except OSError as e:
        raise WriteError(f"{path}: cannot open the ledger of test-set looks: {e.strerror or e}") from None
    try:
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield fd
    finally:
        os.close(fd)  # releases the lock


def read_ledger(path: str | Path) -> list[dict[str, Any]]:
    """Every complete entry of the ledger (none when there is no ledger); a line cut short by a
    crash is skipped."""
    p = Path(path)
    if not p.is_file():
        return []
    out = []
    for line in p.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            entry = json.loads(line)
        except ValueError:
            continue
        if isinstance(entry, dict) and "test_set" in entry:
            out.append(entry)
    return out


def record_look(path: str | Path, entry: dict[str, Any]) -> None:
    """Append ``entry`` as one line, synced to disk before returning."""
    p = Path(path)
    line = json.dumps(entry, sort_keys=True, default=str)
    with _locked(p) as fd:
        try:
            size = os.fstat(fd).st_size
            if size:  # a line cut short by a crash: start on a new line
                os.lseek(fd, size - 1, os.SEEK_SET)
                if os.read(fd, 1) != b"\n":
                    line = "\n" + line
            os.write(fd, (line + "\n").encode())
            os.fsync(fd)
        except OSError as e:
            raise WriteError(f"{p}: cannot write the ledger of test-set looks: {e.strerror or e}") from None


@dataclass(frozen=True)
class Looks:
    """How a test set was looked at: runs that scored it, methods compared on it, final runs."""

    runs: int
    methods: int
    finals: int

    def describe(self) -> str:
        return (f"this test set was scored by {self.runs} run(s), {self.methods} method(s) compared on it"
                + (f", {self.finals} final run(s)" if self.finals else ""))


def looks(path: str | Path, test_set: str) -> Looks:
    """The looks at ``test_set`` the ledger holds."""
    entries = [e for e in read_ledger(path) if e.get("test_set") == test_set]
    methods = {m for e in entries for m in e.get("methods", [])}
    return Looks(runs=len(entries), methods=len(methods), finals=sum(bool(e.get("final")) for e in entries))


def check_final(path: str | Path, test_set: str, methods: Sequence[str], force: bool = False) -> list[str]:
    """Refuse a final run on ``test_set`` when an earlier final run compared other methods there
    (unless ``force``); the notes of a forced one."""
    finals = [e for e in read_ledger(path) if e.get("test_set") == test_set and e.get("final")]
    differing = [e for e in finals if sorted(e.get("methods", [])) != sorted(methods)]
    if not differing:
        return []
    first = differing[0]
    added = sorted(set(methods) - set(first.get("methods", [])))
    dropped = sorted(set(first.get("methods", [])) - set(methods))
    what = "; ".join(x for x in (f"added {', '.join(added)}" if added else "",
                                 f"dropped {', '.join(dropped)}" if dropped else "") if x)
    msg = (f"this test set already had a final run ({first.get('protocol')}"
           f"{'/' + first['evaluation'] if first.get('evaluation') else ''}, {first.get('time')}) with other "
           f"methods ({what}): a second final run would choose among methods by the test set")
    if not force:
        raise FinalRunError(f"{msg}; run without --final, or pass --force-final (it is recorded in {path})")
    return [f"forced: {msg}"]
