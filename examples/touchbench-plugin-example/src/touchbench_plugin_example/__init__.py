"""An example touchbench plugin: one feature set and one classifier.

touchbench imports this module through the entry point ``example`` of the
group ``touchbench.plugins`` (see ``pyproject.toml``). Importing the two
submodules registers their entries with touchbench's registries; the names
start with ``example-`` so that they cannot clash with touchbench's own.
"""

from . import classifiers, features

__all__ = ["classifiers", "features"]
