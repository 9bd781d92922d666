"""The names every registry holds, kept in ``registry-names.json`` beside this file.

The tests compare each registry with the snapshot, so adding, renaming or
removing an entry shows up as a reviewed change of that file. Regenerate it
after an intended change with ``make snapshots`` (which runs this file).
Only touchbench's own entries count: installed plugins (the test
environment has the example plugin) add theirs beside them.
"""

from __future__ import annotations

import json
from pathlib import Path

SNAPSHOT = Path(__file__).resolve().parent / "registry-names.json"


def registries() -> dict:
    from touchbench.classifiers import CLASSIFIERS
    from touchbench.datasets import DATASETS
    from touchbench.datasets.formats import FORMATS
    from touchbench.features import FEATURES
    from touchbench.methods import METHODS
    from touchbench.protocols.schemes import SPLITTERS
    from touchbench.reports.figures import FIGURES
    from touchbench.scenes import SCENES
    from touchbench.streams.rules import RULES

    return {"classifiers": CLASSIFIERS, "datasets": DATASETS, "evaluation schemes": SPLITTERS,
            "decision rules": RULES, "features": FEATURES, "figure kinds": FIGURES, "file formats": FORMATS, "methods": METHODS,
            "scenes": SCENES}


def builtin_names(reg) -> list[str]:
    """The names of touchbench's own entries (not a plugin's), sorted."""
    return [e.name for e in reg.entries() if e.plugin is None]


def current() -> dict[str, list[str]]:
    return {kind: builtin_names(reg) for kind, reg in registries().items()}


def snapshot() -> dict[str, list[str]]:
    return json.loads(SNAPSHOT.read_text(encoding="utf-8"))


if __name__ == "__main__":
    SNAPSHOT.write_text(json.dumps(current(), indent=2) + "\n", encoding="utf-8")
    print(f"wrote {SNAPSHOT}")
