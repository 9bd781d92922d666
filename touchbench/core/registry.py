"""One registry pattern for everything registered: datasets, scenes, feature
sets, classifiers and splitters.

A registry is a closed set of names. Entries are added by a decorator at
import time; YAML and the command line can only name what is registered,
never import an arbitrary Python path. Looking up an unknown name raises
:class:`touchbench.core.errors.UnknownNameError` with the nearest names.

A registry that takes plugins (:mod:`touchbench.core.plugins`) also holds
the entries of installed plugins: on first use it imports its own package's
modules, then every plugin's module. An entry a plugin adds carries the
plugin (a :class:`touchbench.core.plugins.PluginInfo`) in its ``plugin``
tag; :attr:`Entry.plugin` reads it.

A name that was renamed stays known as a former name (:data:`RENAMED`): looking
it up is refused with the name it became, never silently mapped (a protocol
that names it should be updated, its results identity follows the names).
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass, field
from functools import partial
from typing import Any, Callable, Generic, Iterator, TypeVar

from .errors import RegistrationError, UnknownNameError
from .paramdoc import Param, document
from .plugins import PluginInfo, current_plugin, importing, load_plugins, on_left_out
from .suggest import did_you_mean

T = TypeVar("T")

#: Former names of registered components, per registry kind: former name -> current name.
#: Every lookup of an unknown name reads it (:meth:`Registry.entry`, ``suggest``).
RENAMED: dict[str, dict[str, str]] = {
    "classifier": {
        "sota-et": "touch-extra-trees",
        "sota-et-fast": "touch-extra-trees-fast",
        "sota-et-tuned": "touch-extra-trees-tuned",
    },
    "file format": {"long": "table"},
}


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

    @property
    def plugin(self) -> PluginInfo | None:
        """The plugin that registered this entry; None for touchbench's own."""
        return self.tags.get("plugin")

    @property
    def origin(self) -> str:
        """Where the entry comes from, for messages: the plugin, or the module that registered it."""
        if self.plugin is not None:
            return self.plugin.where
        return f"module {getattr(self.obj, '__module__', None) or '?'}"


class Registry(Generic[T]):
    """A named, closed set of factories (classes or functions).

    >>> CLASSES = Registry("colour")
    >>> @CLASSES.register("red", description="the colour red")
    ... def red(): return "#f00"
    >>> CLASSES.create("red")
    '#f00'
    """

    def __init__(self, kind: str, loader: Callable[[], Any] | None = None, *, package: str | None = None,
                 tags_of: Callable[[Any], dict[str, Any]] | None = None, plugins: bool | None = None,
                 params_of: Callable[[Any, dict[str, Any]], list[Param] | None] | None = None):
        """``tags_of(obj)`` gives the tags an entry declares on the object itself
        (class attributes, say), so that they are written once, not twice.
        ``params_of(obj, tags)`` reads the parameters an entry declares (:mod:`touchbench.core.paramdoc`):
        each entry registered gets their "Parameters" section in its docstring, generated, in place
        of a hand-written one.
        ``plugins``: whether installed plugins fill this registry too; by
        default the registries that find their modules by ``package`` do."""
        self.kind = kind
        self._tags_of = tags_of
        self._params_of = params_of
        self._entries: dict[str, Entry[T]] = {}
        if package is not None:
            loader = partial(import_submodules, package)
        self._loader = loader
        self._loaded = loader is None
        self._load_error: BaseException | None = None
        self.plugins = package is not None if plugins is None else plugins

    def _ensure_loaded(self) -> None:
        # Modules that register entries are imported lazily, on first use,
        # so that `import touchbench` stays cheap and optional extras
        # (torch, aeon) are only imported when their entry is used. Then
        # the plugins (once per process, for every registry that takes them).
        self._load_own()
        if self.plugins:
            load_plugins()

    def _load_own(self) -> None:
        if self._load_error is not None:  # a module that failed stays failed: no half-filled registry
            raise self._load_error
        if not self._loaded:
            self._loaded = True
            assert self._loader is not None
            try:
                with importing(None):  # a plugin's import may be what started this: these entries are not its
                    self._loader()
            except Exception as e:
                self._load_error = e
                raise

    def register(self, name: str, *, description: str, **tags: Any) -> Callable[[T], T]:
        def deco(obj: T) -> T:
            plugin = current_plugin()
            if plugin is not None:
                if not self.plugins:
                    raise RegistrationError(f"{self.kind} {name!r}: the {self.kind} registry does not take plugins")
                self._load_own()  # touchbench's own entries first, whichever registry loaded the plugin
            declared = self._tags_of(obj) if self._tags_of is not None else {}
            if name in self._entries:
                new = Entry(name, obj, description, {"plugin": plugin} if plugin else {})
                kept = (" (kept)", f" (left out, with everything {plugin.label} registers)") if plugin else ("", "")
                raise RegistrationError(f"{self.kind} {name!r} is registered twice: by {self._entries[name].origin}"
                                        f"{kept[0]} and by {new.origin}{kept[1]}")
            clash = sorted(set(declared) & set(tags))
            if clash:
                raise RegistrationError(f"{self.kind} {name!r}: {', '.join(clash)} declared twice "
                                        "(on the object and as tags)")
            if "plugin" in declared or "plugin" in tags:
                raise RegistrationError(f"{self.kind} {name!r}: the tag 'plugin' is touchbench's (it names the plugin)")
            extra = {"plugin": plugin} if plugin is not None else {}
            self._entries[name] = Entry(name, obj, description, {**declared, **tags, **extra})
            if self._params_of is not None:
                document(obj, self._params_of(obj, {**declared, **tags}))
            if plugin is not None:
                on_left_out(plugin, partial(self._entries.pop, name, None))
            return obj

        return deco

    def entry(self, name: str) -> Entry[T]:
        self._ensure_loaded()
        try:
            return self._entries[name]
        except KeyError:
            raise UnknownNameError(self._unknown_message(name)) from None

    def _unknown_message(self, name: str) -> str:
        current = RENAMED.get(self.kind, {}).get(str(name))
        if current is not None and current in self._entries:
            return f"{self.kind} {name!r} was renamed {current!r}: use {current!r} instead"
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

    def registered(self) -> list[Entry[T]]:
        """The entries registered so far, by name, without loading anything (and so never failing)."""
        return [self._entries[n] for n in sorted(self._entries)]

    def suggest(self, name: str) -> str:
        """The message an unknown ``name`` gets (for schema validators)."""
        self._ensure_loaded()
        return self._unknown_message(name)
