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
look. A line cut short by a crash (the next append starts on a new line), or
holding a field of the wrong type, is skipped when read, with a warning naming
the file and line (:func:`read_ledger`). :func:`check_final` refuses a second final run on a
test set with other methods than the first final run's, unless forced.

A run is counted once, however many sessions it took: its ``look`` id is
written into its results folder (:data:`RUN_FILE`) when it starts and kept
until it ends, so the session that resumes an interrupted run records the
same id (``resumed``). One ledger serves every results folder of a results
root; ledgers that earlier versions kept deeper in the root (one per folder
of results folders) are merged into it (:func:`merge_ledgers`, each kept as
``ledger.jsonl.merged``) and read until then (:func:`old_ledgers`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from ..core.atomic import atomic_write_bytes
from ..core.errors import TouchbenchError, WriteError
from ..datasets.model import labelled_checksum

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LEDGER_NAME", "RUN_FILE", "FinalRunError", "Looks", "check_final", "end_look", "looks", "merge_ledgers",
           "old_ledgers", "read_ledger", "read_ledgers", "record_look", "start_look", "test_set_hash",
           "test_set_hash_of"]

log = logging.getLogger("touchbench.results")

LEDGER_NAME = "ledger.jsonl"
#: in a results folder, while a run is under way (and after it was interrupted): its look id
RUN_FILE = ".touchbench-run.json"
#: what a ledger merged into its results root's is renamed to (``ledger.jsonl.merged``)
MERGED_SUFFIX = ".merged"
#: how deep below a results root earlier versions kept ledgers (``papers/<profile>/<protocol>-audit/``)
_OLD_LEDGER_DEPTH = 3
#: what a :class:`WriteError` of the ledger says could not be done
_CANNOT_WRITE = "cannot write the ledger of test-set looks"


class FinalRunError(TouchbenchError):
    """A second final run on a test set, with other methods, not forced."""


def test_set_hash(captures: Sequence[np.ndarray], labels: Iterable[Any]) -> str:
    """SHA-256 of a test set: each capture's frames (float64, with their shape) and label, in a
    sorted order, so neither the order nor the capture ids nor the reader change it."""
    return test_set_hash_of(labelled_checksum(c, y) for c, y in zip(captures, labels))


def test_set_hash_of(checksums: Iterable[str]) -> str:
    """:func:`test_set_hash` from each test capture's
    :func:`touchbench.datasets.model.labelled_checksum` (a dataset keeps them:
    :meth:`touchbench.datasets.model.TouchDataset.labelled_checksums`)."""
    return hashlib.sha256("\n".join(sorted(checksums)).encode()).hexdigest()


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[int]:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o666)
    except OSError as e:
        raise WriteError(path, e, _CANNOT_WRITE) from None
    try:
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield fd
    finally:
        os.close(fd)  # releases the lock


def _texts(v: Any) -> bool:
    return isinstance(v, list) and all(isinstance(x, str) for x in v)


#: each field a ledger line may hold: whether a value is of its type, and that type in words
_FIELDS: dict[str, tuple[Callable[[Any], bool], str]] = {
    **dict.fromkeys(("test_set", "time", "protocol", "run_id", "look", "results"),
                    (lambda v: isinstance(v, str), "a string")),
    "evaluation": (lambda v: v is None or isinstance(v, str), "a string or null"),
    "methods": (_texts, "a list of strings"),
    "tasks": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0, "a whole number >= 0"),
    **dict.fromkeys(("final", "forced", "resumed"), (lambda v: isinstance(v, bool), "true or false")),
}
#: the lines of ledgers already warned of in this process (path, line number, text)
_warned: set[tuple[str, int, str]] = set()


def _entry(line: str) -> tuple[dict[str, Any] | None, str]:
    """The entry a ledger line holds, or None and why it is skipped."""
    try:
        entry = json.loads(line)
    except ValueError:
        return None, "not a complete JSON line (cut short by a crash, or edited)"
    if not isinstance(entry, dict) or "test_set" not in entry:
        return None, "not an entry of the ledger (a JSON object with a test_set)"
    for key, (is_type, kind) in _FIELDS.items():
        if key in entry and not is_type(entry[key]):
            return None, f"its {key} is {json.dumps(entry[key])[:40]}, not {kind}"
    return entry, ""


def read_ledger(path: str | Path) -> list[dict[str, Any]]:
    """Every sound entry of the ledger (none when there is no ledger). A line that is not one (cut
    short by a crash, a field of the wrong type: ``"methods": 5``, ``"final": "false"``) is
    skipped with a warning naming the file and line (once per process)."""
    p = Path(path)
    if not p.is_file():
        return []
    out = []
    for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        if not line.strip():
            continue
        entry, why = _entry(line)
        if entry is not None:
            out.append(entry)
        elif (str(p), n, line) not in _warned:
            _warned.add((str(p), n, line))
            log.warning("%s:%d: a line of the ledger of test-set looks was skipped: %s", p, n, why)
    return out


def _key(entry: dict[str, Any]) -> str:
    return json.dumps(entry, sort_keys=True, default=str)


def read_ledgers(paths: Iterable[str | Path]) -> list[dict[str, Any]]:
    """The entries of several ledgers, each entry once (a ledger merged into another but still
    read beside it adds nothing), in the order met."""
    seen: dict[str, dict[str, Any]] = {}
    for p in dict.fromkeys(Path(x) for x in paths):
        for e in read_ledger(p):
            seen.setdefault(_key(e), e)
    return list(seen.values())


def old_ledgers(root: str | Path) -> list[Path]:
    """The ledgers earlier versions kept below results root ``root`` (in a folder of results
    folders), not yet merged into the root's; results folders themselves are not searched."""
    root = Path(root)
    found = []
    for folder, dirs, files in os.walk(root):
        depth = len(Path(folder).relative_to(root).parts)
        if "manifest.json" in files or depth >= _OLD_LEDGER_DEPTH:
            dirs[:] = []
        dirs[:] = [d for d in dirs if not d.startswith(".") and d != "fragments"]
        if depth and LEDGER_NAME in files:
            found.append(Path(folder) / LEDGER_NAME)
    return sorted(found)


def _append(fd: int, p: Path, lines: list[str]) -> None:
    """Append ``lines`` to the locked ledger ``fd`` (of ``p``) in one write, synced to disk."""
    text = "".join(line + "\n" for line in lines)
    try:
        size = os.fstat(fd).st_size
        if size:  # a line cut short by a crash: start on a new line
            os.lseek(fd, size - 1, os.SEEK_SET)
            if os.read(fd, 1) != b"\n":
                text = "\n" + text
        os.write(fd, text.encode())
        os.fsync(fd)
    except OSError as e:
        raise WriteError(p, e, _CANNOT_WRITE) from None


def record_look(path: str | Path, entry: dict[str, Any]) -> None:
    """Append ``entry`` as one line, synced to disk before returning."""
    p = Path(path)
    with _locked(p) as fd:
        _append(fd, p, [_key(entry)])


def merge_ledgers(path: str | Path, others: Sequence[str | Path]) -> int:
    """Move the entries of the ledgers ``others`` into ledger ``path`` (those it lacks, appended
    under its lock and synced), then rename each of ``others`` to ``NAME.merged``: every entry is
    in one of the files at every moment. The number of entries added."""
    p = Path(path)
    with _locked(p) as fd:
        others = [Path(o) for o in others if Path(o).is_file() and Path(o).resolve() != p.resolve()]
        if not others:
            return 0
        have = {_key(e) for e in read_ledger(p)}
        new = [k for k in dict.fromkeys(_key(e) for e in read_ledgers(others)) if k not in have]
        if new:
            _append(fd, p, new)
        for o in others:
            try:
                os.replace(o, o.with_name(o.name + MERGED_SUFFIX))
            except OSError as e:
                raise WriteError(o, e, f"merged into {p}, but cannot be renamed {o.name}{MERGED_SUFFIX}") from None
        return len(new)


def start_look(folder: str | Path, run: dict[str, Any]) -> tuple[str, bool]:
    """The look id of the run ``run`` (what identifies it: plan, methods) starting in results
    folder ``folder``: the id of the same run left unfinished there (resumed: True), else a new
    one, written into the folder before any task runs (call it under the folder's lock)."""
    p = Path(folder) / RUN_FILE
    try:
        left = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        left = None
    if isinstance(left, dict) and left.get("run") == run and left.get("look"):
        return str(left["look"]), True
    look = uuid.uuid4().hex
    atomic_write_bytes(p, json.dumps({"look": look, "run": run}, sort_keys=True).encode())
    return look, False


def end_look(folder: str | Path) -> None:
    """The run under way in ``folder`` ended: the next one is another look."""
    try:
        (Path(folder) / RUN_FILE).unlink(missing_ok=True)
    except OSError as e:
        raise WriteError(Path(folder) / RUN_FILE, e) from None


@dataclass(frozen=True)
class Looks:
    """How a test set was looked at: runs that scored it, methods compared on it, final runs."""

    runs: int
    methods: int
    finals: int

    def describe(self) -> str:
        return (f"this test set was scored by {self.runs} run(s), {self.methods} method(s) compared on it"
                + (f", {self.finals} final run(s)" if self.finals else ""))


def _run(entry: dict[str, Any]) -> str:
    """The run an entry is a session of: its look id (an entry written before runs had one: itself)."""
    return str(entry.get("look") or _key(entry))


def looks(path: str | Path | Sequence[str | Path], test_set: str) -> Looks:
    """The looks at ``test_set`` the ledger (or ledgers) holds: each run once, however many
    sessions it took."""
    paths = [path] if isinstance(path, (str, Path)) else list(path)
    entries = [e for e in read_ledgers(paths) if e.get("test_set") == test_set]
    methods = {m for e in entries for m in e.get("methods", [])}
    return Looks(runs=len({_run(e) for e in entries}), methods=len(methods),
                 finals=len({_run(e) for e in entries if e.get("final")}))


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
