"""One registry pattern for everything registered: datasets, scenes, feature
sets, classifiers and splitters.

A registry is a closed set of names. Entries are added by a decorator at
import time; YAML and the command line can only name what is registered,
never import an arbitrary Python path. Looking up an unknown name raises
:class:`~touchbench.core.errors.UnknownNameError` with the nearest names.
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Callable, Generic, Iterator, TypeVar

from .errors import UnknownNameError
from .suggest import did_you_mean

T = TypeVar("T")


def import_submodules(package: str) -> list[str]:
    """Import every module of ``package`` whose name does not start with ``_``; their names."""
    pkg = importlib.import_module(package)
    names = sorted(f"{package}.{m.name}" for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))
    for name in names:
        importlib.import_module(name)
    return names


@dataclass(frozen=True)
class Entry(Generic[T]):
    """A registered object with its one-line description and free-form tags."""

    name: str
    obj: T
    description: str
    tags: dict[str, Any] = field(default_factory=dict)


class Registry(Generic[T]):
    """A named, closed set of factories (classes or functions).

    >>> CLASSES = Registry("colour")
    >>> @CLASSES.register("red", description="the colour red")
    ... def red(): return "#f00"
    >>> CLASSES.create("red")
    '#f00'
    """

    def __init__(self, kind: str, loader: Callable[[], Any] | None = None, *, package: str | None = None,
                 tags_of: Callable[[Any], dict[str, Any]] | None = None):
        """``tags_of(obj)`` gives the tags an entry declares on the object itself
        (class attributes, say), so that they are written once, not twice."""
        self.kind = kind
        self._tags_of = tags_of
        self._entries: dict[str, Entry[T]] = {}
        if package is not None:
            loader = partial(import_submodules, package)
        self._loader = loader
        self._loaded = loader is None

    def _ensure_loaded(self) -> None:
        # Modules that register entries are imported lazily, on first use,
        # so that `import touchbench` stays cheap and optional extras
        # (torch, aeon) are only imported when their entry is used.
        if not self._loaded:
            self._loaded = True
            assert self._loader is not None
            self._loader()

    def register(self, name: str, *, description: str, **tags: Any) -> Callable[[T], T]:
        def deco(obj: T) -> T:
            if name in self._entries:
                raise ValueError(f"{self.kind} {name!r} is registered twice")
            declared = self._tags_of(obj) if self._tags_of is not None else {}
            clash = sorted(set(declared) & set(tags))
            if clash:
                raise ValueError(f"{self.kind} {name!r}: {', '.join(clash)} declared twice (on the object and as tags)")
            self._entries[name] = Entry(name, obj, description, {**declared, **tags})
            return obj

        return deco

    def entry(self, name: str) -> Entry[T]:
        self._ensure_loaded()
        try:
            return self._entries[name]
        except KeyError:
            raise UnknownNameError(self._unknown_message(name)) from None

    def _unknown_message(self, name: str) -> str:
        hint = did_you_mean(name, self._entries)
        known = ", ".join(sorted(self._entries))
        return f"unknown {self.kind} {name!r}{hint} (known: {known})"

    def get(self, name: str) -> T:
        return self.entry(name).obj

    def create(self, name: str, /, **params: Any) -> Any:
        """Call the registered factory with ``params``."""
        return self.get(name)(**params)

    def __contains__(self, name: object) -> bool:
        self._ensure_loaded()
        return name in self._entries

    def names(self) -> list[str]:
        self._ensure_loaded()
        return sorted(self._entries)

    def entries(self) -> Iterator[Entry[T]]:
        self._ensure_loaded()
        for name in sorted(self._entries):
            yield self._entries[name]

    def suggest(self, name: str) -> str:
        """The message an unknown ``name`` gets (for schema validators)."""
        self._ensure_loaded()
        return self._unknown_message(name)
