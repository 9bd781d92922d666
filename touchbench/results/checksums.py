"""The SHA-256 of the files a run wrote into its results folder, and which of them changed since.

A run records, in its manifest's ``tasks.merged_files``, the SHA-256 of each
merged file as the merge wrote it (``scores.parquet``, ``predictions.parquet``,
``confusion.parquet``, ``confusion_pooled.parquet``; a saved reference, of the
files it saved). :func:`changed_files` compares a folder's files with such a
record: the run merges again from its tasks' results when one differs
(:meth:`touchbench.results.store.ResultStore.merged_problems`), the reports
warn that what they show is not what the run wrote
(:func:`changed_since_run`). Only these files are hashed (a few megabytes at
most), never a dataset.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any, Iterable

__all__ = ["CHANGED", "changed_files", "changed_since_run", "file_checksums", "file_sha256", "mismatches",
           "recorded_checksums"]

#: how a file whose content is not the one recorded is described
CHANGED = "changed since the run wrote it"


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of the file ``path`` (hex), read in blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_checksums(folder: str | Path, names: Iterable[str]) -> dict[str, str]:
    """The SHA-256 of each file of ``folder`` named in ``names`` that exists."""
    folder = Path(folder)
    return {name: file_sha256(folder / name) for name in names if (folder / name).is_file()}


def mismatches(folder: str | Path, recorded: dict[str, str], names: Iterable[str] | None = None) -> dict[str, bool]:
    """The files ``names`` of ``folder`` (default: those ``recorded`` names) that do not match the
    SHA-256 ``recorded`` for each: name -> whether it exists (a name with no record does not match)."""
    folder = Path(folder)
    out = {}
    for name in (recorded if names is None else names):
        if not (folder / name).is_file():
            out[name] = False
        elif recorded.get(name) != file_sha256(folder / name):
            out[name] = True
    return out


def changed_files(folder: str | Path, recorded: dict[str, str], names: Iterable[str] | None = None) -> list[str]:
    """:func:`mismatches` in words: ``NAME is missing``, ``NAME changed since the run wrote it``."""
    return [f"{name} {CHANGED}" if exists else f"{name} is missing"
            for name, exists in mismatches(folder, recorded, names).items()]


def recorded_checksums(manifest: Any) -> dict[str, str]:
    """The SHA-256 of each file a run's manifest records (``tasks.merged_files``; empty: none)."""
    tasks = manifest.get("tasks") if isinstance(manifest, dict) else None
    recorded = tasks.get("merged_files") if isinstance(tasks, dict) else None
    return recorded if isinstance(recorded, dict) else {}


def changed_since_run(folder: str | Path, manifest: dict[str, Any]) -> list[str]:
    """The warnings of a results folder whose files are no longer those its run wrote (one per
    file, naming the folder and the file); none when they are, or when the manifest records no
    checksums (results of versions that did not record them)."""
    recorded = recorded_checksums(manifest)
    return [(f"{Path(folder)}: {name} {CHANGED} (its SHA-256 is not the one manifest.json records)" if exists else
             f"{Path(folder)}: {name}, which the run wrote, is missing")
            + ": the tables show these results as they are now, which may not be what the run measured"
            for name, exists in mismatches(folder, recorded).items()]
