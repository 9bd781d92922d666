"""Dataset references: the one parser of what a protocol, ``data info``,
``predict`` or ``scenes fidelity`` names as a dataset.

A reference is one of

- ``scene:NAME`` (or ``scene:path/to/scene.yaml``): a synthetic scene,
  generated (and cached) by :mod:`touchbench.scenes`;
- a file path (ends in ``.parquet``, contains a path separator, or names an
  existing file): a dataset Parquet file written by touchbench;
- anything else: the name of a registered dataset (``haart``, ...).

With a ``format`` (a registered file format: ``haart-raw``, ``table``...),
the reference is a file or folder read by that format's reader with the
given options (a protocol's ``dataset: {name: study/, format: haart-raw}``).

This module sits above both the real-data readers and the scenes, so that
neither has to know about the other.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from .datasets.formats import FORMATS
from .datasets.model import TouchDataset
from .datasets.registry import DATASETS
from .scenes import SCENES, generate_scene

__all__ = ["DatasetRef", "dataset_ref_problem", "format_ref_problem", "load_dataset", "parse_dataset_ref"]

SCENE_PREFIX = "scene:"


@dataclass(frozen=True)
class DatasetRef:
    """A parsed dataset reference: ``kind`` and the ``value`` it names."""

    kind: Literal["scene", "file", "registered"]
    value: str

    def __str__(self) -> str:
        return SCENE_PREFIX + self.value if self.kind == "scene" else self.value


def parse_dataset_ref(ref: str | Path, base: Path | None = None) -> DatasetRef:
    """Parse ``ref``; a relative file path that does not exist as given is
    looked up in ``base`` (the folder of the protocol that names it)."""
    text = str(ref)
    if text.startswith(SCENE_PREFIX):
        return DatasetRef("scene", text[len(SCENE_PREFIX):])
    if text.endswith(".parquet") or "/" in text or "\\" in text or Path(text).is_file():
        p = Path(text)
        if base is not None and not p.is_absolute() and not p.exists() and (base / p).exists():
            p = base / p
        return DatasetRef("file", str(p))
    return DatasetRef("registered", text)


def dataset_ref_problem(ref: DatasetRef) -> str | None:
    """Why ``ref`` cannot name a dataset (unknown name, missing file), or None."""
    if ref.kind == "scene":
        name = ref.value
        if name and not name.endswith((".yaml", ".yml")) and name not in SCENES:
            return SCENES.suggest(name)
        return None
    if ref.kind == "file":
        return None if Path(ref.value).is_file() else f"no dataset file {ref.value!r}"
    if ref.value not in DATASETS:
        return DATASETS.suggest(ref.value) + "; or write scene:NAME or a .parquet path"
    return None


def format_ref_problem(path: str | Path, fmt: str) -> str | None:
    """Why ``path`` cannot be read in the file format ``fmt`` (unknown format, missing path), or None."""
    if fmt not in FORMATS:
        return FORMATS.suggest(fmt)
    return None if Path(path).exists() else f"no file or folder {str(path)!r}"


def load_dataset(ref: str | Path | DatasetRef, format: str | None = None, **kwargs: Any) -> TouchDataset:
    """Load a registered dataset, a ``scene:NAME`` or a dataset Parquet file; with ``format``, a
    file or folder read by that registered format's reader.

    ``kwargs`` go to the registered loader (``cache_dir``, ``data_dir``,
    ``refresh``), the scene generator (``seed``, overrides) or the format's
    reader (its options); a Parquet file takes none.
    """
    if format is not None:
        path = ref.value if isinstance(ref, DatasetRef) else str(ref)
        return FORMATS.get(format).read(path, **kwargs)
    parsed = ref if isinstance(ref, DatasetRef) else parse_dataset_ref(ref)
    if parsed.kind == "scene":
        return generate_scene(parsed.value, **kwargs)
    if parsed.kind == "file":
        return TouchDataset.from_parquet(parsed.value)
    return DATASETS.create(parsed.value, **kwargs)
