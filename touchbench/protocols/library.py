"""Where protocols are found: the shipped ones, and a name given on the command line.

:func:`find_protocol` turns what a user typed (a file path, or the name of a
protocol) into a file; :func:`protocol_dirs` lists the folders searched.
"""

from __future__ import annotations

from pathlib import Path

from ..core.paths import REPO_ROOT
from .schema import ProtocolError

__all__ = ["find_protocol", "protocol_dirs"]


def protocol_dirs() -> list[Path]:
    """``protocols/`` of the current directory and of the checkout (deduplicated)."""
    out: list[Path] = []
    for base in (Path.cwd(), REPO_ROOT):
        d = (base / "protocols").resolve()
        if d.is_dir() and d not in out:
            out.append(d)
    return out


def find_protocol(ref: str) -> Path:
    """A protocol file path, or a name looked up in protocols/ and protocols/papers/."""
    p = Path(ref)
    if p.is_file():
        return p
    for d in protocol_dirs():
        for sub in (d, d / "papers"):
            for cand in (sub / ref, sub / f"{ref}.yaml", sub / f"{ref}.yml"):
                if cand.is_file():
                    return cand
    raise ProtocolError(f"{ref}: no such protocol file (nor a protocol of that name in protocols/ or protocols/papers/)")
