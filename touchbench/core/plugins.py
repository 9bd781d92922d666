"""Plugins: installed packages that add entries to touchbench's registries.

A plugin is a distribution that declares entry points in the group
``touchbench.plugins``; each entry point names a module (``name =
"package.module"``). Importing that module registers its entries with the
ordinary decorators (``@FEATURES.register(...)``, ``@CLASSIFIERS.register``,
``@DATASETS.register``, ``register_format``, ``@SPLITTERS.register``,
``@FIGURES.register``).

:func:`load_plugins` imports every plugin's module once per process. The
registries that take plugins call it on first use, after their own
package's modules, so every process (the command line, loky workers, Dask
and Ray workers) finds the plugins of its environment by itself. While a
plugin's module is imported, :func:`current_plugin` says which one: the
registry records it in the ``plugin`` tag of every entry the plugin adds.

A plugin that fails to import (any exception, ``SystemExit`` included; only
``KeyboardInterrupt`` goes through), or registers a name that exists
already, is left out: :func:`load_plugins` logs one warning naming the
distribution, the entry point and why, removes the entries it registered
before it failed, and the registries answer without it. A name registered
by two plugins is kept by the first (plugins load in the order of their
distribution names) and the message names both. ``touchbench plugins
list`` lists each failure (and exits with status 3).
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass
from importlib import metadata
from typing import Callable, Iterator

from .errors import TouchbenchError

__all__ = ["GROUP", "PluginError", "PluginInfo", "current_plugin", "importing", "installed_plugins", "load_plugins",
           "plugin_status", "on_left_out"]

GROUP = "touchbench.plugins"


class PluginError(TouchbenchError):
    """A plugin that could not be loaded: names its distribution and entry point."""


@dataclass(frozen=True)
class PluginInfo:
    """One entry point of the group: the distribution that declares it and the module it names."""

    package: str  # the distribution's name, as ``pip`` knows it
    version: str
    entry_point: str
    module: str  # the entry point's value

    @property
    def label(self) -> str:
        """``package version``: what listings show for the plugin's entries."""
        return f"{self.package} {self.version}"

    @property
    def where(self) -> str:
        """The distribution and entry point, for error messages."""
        return f"plugin {self.label} (entry point {self.entry_point!r} = {self.module!r} in group {GROUP!r})"


def installed_plugins() -> list[tuple[PluginInfo, metadata.EntryPoint]]:
    """Every entry point of the group in this environment, sorted by package and entry point name."""
    out = []
    seen = set()
    for ep in metadata.entry_points(group=GROUP):
        dist = ep.dist
        package = dist.metadata["Name"] if dist is not None else "(unknown package)"
        version = dist.version if dist is not None else "?"
        info = PluginInfo(package, version, ep.name, ep.value)
        if info not in seen:  # the same distribution found twice on sys.path counts once
            seen.add(info)
            out.append((info, ep))
    return sorted(out, key=lambda p: (p[0].package.lower(), p[0].entry_point))


_state: dict = {"loaded": False, "loading": False, "status": []}
_current: list[PluginInfo | None] = []
_undo: dict[PluginInfo, list[Callable[[], None]]] = {}  # what to remove if the plugin is left out
log = logging.getLogger("touchbench")


def on_left_out(info: PluginInfo, undo: Callable[[], None]) -> None:
    """Call ``undo`` (removing something the plugin ``info`` registered) if the plugin fails to load."""
    _undo.setdefault(info, []).append(undo)


def current_plugin() -> PluginInfo | None:
    """The plugin whose module is being imported now, else None."""
    return _current[-1] if _current else None


@contextlib.contextmanager
def importing(info: PluginInfo | None) -> Iterator[None]:
    """While inside, :func:`current_plugin` is ``info`` (None: touchbench's own modules are imported)."""
    _current.append(info)
    try:
        yield
    finally:
        _current.pop()


def _describe(exc: BaseException) -> str:
    if isinstance(exc, TouchbenchError):
        return str(exc)
    if isinstance(exc, SystemExit):
        return f"it called sys.exit({exc.code!r}) while being imported"
    return f"{type(exc).__name__}: {exc}"


def _load_one(info: PluginInfo, ep: metadata.EntryPoint) -> str | None:
    """Import one plugin's module; why it failed (its entries removed again), or None."""
    try:
        with importing(info):
            ep.load()
    except KeyboardInterrupt:
        raise
    except BaseException as e:  # any failure of the plugin's code, sys.exit included: reported, left out
        for undo in reversed(_undo.pop(info, [])):
            undo()
        why = _describe(e)
        log.warning(f"{info.where} failed to load and is left out: {why}")
        return why
    _undo.pop(info, None)
    return None


def load_plugins() -> None:
    """Import every plugin's module (once per process); a plugin that fails is left out with a warning
    (:func:`plugin_status` says which and why).

    Re-entrant: a registry used while a plugin is being imported does not
    start a second round.
    """
    if _state["loading"] or _state["loaded"]:
        return
    _state["loading"] = True
    try:
        _state["status"] = [(info, _load_one(info, ep)) for info, ep in installed_plugins()]
    finally:
        _state["loading"] = False
        _state["loaded"] = True


def plugin_status() -> list[tuple[PluginInfo, str | None]]:
    """Each plugin entry point with why it failed to load (None: loaded). Loads them first."""
    load_plugins()
    return list(_state["status"])
