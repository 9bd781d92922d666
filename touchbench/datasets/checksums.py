"""A folder of recordings checked against its ``SHA256SUMS`` file (``sha256  ./name`` lines, names
relative to the folder of recordings, without ``.gz``), saying what was not checked.

- a file whose content does not match its line is refused, naming it;
- a file the list names but the folder lacks (neither ``name`` nor ``name.gz``) is refused, naming
  up to :data:`NAMED` of them and counting the rest: a recording is never left out silently;
- a recording read that the list does not name is read, and said: a warning naming them and the
  dataset's provenance (``checksums``);
- a missing, empty or unreadable list checks nothing, and says so (a warning, provenance "not
  checked"); lines that are not ``digest  name`` are counted and the first named.

:func:`verify_checksums` returns the provenance entry; the readers (``haart``, ``icmi15-study2``,
``socialtouch``, ``inflatable-skin``, the ``haart-raw`` format's ``checksums``) put it in the dataset's provenance.
"""

from __future__ import annotations

import gzip
import logging
import re
from pathlib import Path

from ..core.errors import DataError

__all__ = ["NAMED", "read_bytes", "verify_checksums"]

log = logging.getLogger("touchbench.datasets")

#: the files a message names before it counts the rest
NAMED = 5
_LINE = re.compile(r"^([0-9a-fA-F]{64})\s+\*?(.+)$")


def read_bytes(path: Path) -> bytes:
    """A recording's original bytes (those its line lists), plain or gzipped."""
    data = path.read_bytes()
    if data[:2] == b"\x1f\x8b":
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError) as e:
            raise DataError(f"corrupt gzip file ({e})", path) from None
    return data


def _names(names: list[str]) -> str:
    more = f" and {len(names) - NAMED} more" if len(names) > NAMED else ""
    return ", ".join(names[:NAMED]) + more


def _read_sums(sums: Path) -> tuple[dict[str, str], str]:
    """The list's digests by name, and why it could not be read (whole or in part; "" when it could)."""
    try:
        text = sums.read_text(encoding="utf-8")
    except FileNotFoundError:
        return {}, f"no {sums.name} file ({sums})"
    except (OSError, UnicodeDecodeError) as e:
        return {}, f"{sums} is unreadable ({type(e).__name__})"
    expected, bad = {}, []
    for i, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        m = _LINE.match(line.strip())
        if m is None:
            bad.append(i)
            continue
        expected[m[2].strip().removeprefix("./")] = m[1].lower()
    if not expected:
        return {}, f"{sums} lists no file" + (f" ({len(bad)} unreadable line(s), the first line {bad[0]})" if bad else "")
    why = f"{len(bad)} line(s) of {sums} are unreadable (the first: line {bad[0]})" if bad else ""
    return expected, why


def _folder_of(files: list[tuple[str, Path, str]]) -> Path | None:
    """The folder the names are relative to, from the first file (``path`` less the name's parts)."""
    if not files:
        return None
    name, path, _ = files[0]
    return path.parents[len(Path(name).parts) - 1]


def verify_checksums(sums: Path, files: list[tuple[str, Path, str]], folder: Path | None = None) -> dict[str, str]:
    """Check each ``(name, path, sha256)`` read against the SHA-256 list ``sums`` (module docstring);
    ``folder``: the folder the names are relative to (default: found from the first file). Returns
    the provenance entry ``{"checksums": ...}`` saying what was checked; a mismatch, or a listed
    file the folder lacks, is one :class:`DataError`."""
    sums = Path(sums)
    expected, problem = _read_sums(sums)
    if not expected:
        log.warning("%s: recordings not checked: %s", sums.parent, problem)
        return {"checksums": f"not checked: {problem}"}
    for name, path, digest in files:
        if name in expected and expected[name] != digest:
            raise DataError(f"content does not match {sums.name} (corrupted copy?)", path)
    read = {name for name, _, _ in files}
    base = folder if folder is not None else _folder_of(files)
    missing = sorted(n for n in expected if n not in read and not (
        base is not None and ((base / n).exists() or (base / f"{n}.gz").exists())))
    if missing:
        raise DataError(f"{len(missing)} file(s) listed in {sums.name} are missing from the folder: "
                        f"{_names(missing)} (an incomplete copy?)", base if base is not None else sums)
    unlisted = sorted(read - set(expected))
    said = [f"{len(read) - len(unlisted)} of {len(read)} recordings verified against {sums}"]
    if unlisted:
        said.append(f"{len(unlisted)} read but not listed, so not checked: {_names(unlisted)}")
        log.warning("%s: %d recording(s) not listed in %s read unchecked: %s", sums.parent, len(unlisted),
                    sums.name, _names(unlisted))
    if problem:
        said.append(problem)
        log.warning("%s: %s", sums.parent, problem)
    return {"checksums": "; ".join(said)}
