"""Where protocols are found: the shipped ones, a user's own folders, and a path.

Shipped protocols are package data (``touchbench/protocols/*.yaml`` and
``touchbench/protocols/papers/*.yaml``): they are found the same way from a
checkout and from an installed wheel. A user adds folders of their own with
``$TOUCHBENCH_PROTOCOLS`` (several joined by ``os.pathsep``) or the
command line's ``--protocols DIR``; a ``protocols/`` folder in the current
directory is searched too. Folders are searched in that order, the shipped
ones last, each with its ``papers/`` subfolder.

:func:`find_protocol` turns what a user typed (a file path, or the name of a
protocol) into a file; :func:`protocol_dirs` lists the folders searched.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["PAPERS_DIR", "SHIPPED_DIR", "add_protocol_dir", "find_protocol", "listed_protocols", "protocol_dirs",
           "shipped_protocols"]

SHIPPED_DIR = Path(__file__).resolve().parent
PAPERS_DIR = SHIPPED_DIR / "papers"

_EXTRA: list[Path] = []  # folders given on the command line (--protocols)


def add_protocol_dir(path: str | Path) -> None:
    """Search ``path`` (a user's folder of protocols) before the shipped ones."""
    p = Path(path).resolve()
    if not p.is_dir():
        from .errors import ProtocolError  # here: finding and listing protocols imports no schema

        raise ProtocolError(f"{path}: no such protocol folder")
    if p not in _EXTRA:
        _EXTRA.append(p)


def protocol_dirs() -> list[Path]:
    """Folders searched for protocols by name: ``--protocols``,
    ``$TOUCHBENCH_PROTOCOLS``, ``./protocols``, then the shipped folder."""
    out: list[Path] = []
    env = [Path(p) for p in os.environ.get("TOUCHBENCH_PROTOCOLS", "").split(os.pathsep) if p]
    for d in [*_EXTRA, *env, Path.cwd() / "protocols", SHIPPED_DIR]:
        d = d.resolve()
        if d.is_dir() and d not in out:
            out.append(d)
    return out


def _candidates(d: Path) -> list[Path]:
    return [d, d / "papers"] if (d / "papers").is_dir() else [d]


def find_protocol(ref: str) -> Path:
    """A protocol file path, or a name looked up in :func:`protocol_dirs` (and their ``papers/``)."""
    p = Path(ref)
    if p.is_file():
        return p
    for d in protocol_dirs():
        for sub in _candidates(d):
            for cand in (sub / ref, sub / f"{ref}.yaml", sub / f"{ref}.yml"):
                if cand.is_file():
                    return cand
    from .errors import ProtocolError

    searched = ", ".join(str(d) for d in protocol_dirs())
    raise ProtocolError(f"{ref}: no such protocol file (nor a protocol of that name in {searched})")


def listed_protocols() -> list[Path]:
    """Every protocol file of every searched folder (a name found twice: the first)."""
    seen: set[str] = set()
    out: list[Path] = []
    for d in protocol_dirs():
        for sub in _candidates(d):
            for f in sorted(sub.glob("*.yaml")) + sorted(sub.glob("*.yml")):
                if f.stem not in seen:
                    seen.add(f.stem)
                    out.append(f)
    return out


def shipped_protocols() -> list[Path]:
    """The protocol files shipped with touchbench (papers included)."""
    return sorted(SHIPPED_DIR.glob("*.yaml")) + sorted(PAPERS_DIR.glob("*.yaml"))
