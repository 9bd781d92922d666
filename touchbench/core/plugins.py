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

A plugin that fails to import, or registers a name that exists already, is
never skipped: :func:`load_plugins` raises one :class:`PluginError` naming
the distribution and the entry point of every plugin that failed, and
raises it again on every later call, so each registry that takes plugins
refuses to answer until the plugin is fixed or uninstalled. A plugin is one
module that may fill any registry, so a plugin that failed halfway leaves
unknown which names it would have added or replaced: no registry can be
trusted to mean what it meant with the plugin working.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from importlib import metadata
from typing import Iterator

from .errors import TouchbenchError

__all__ = ["GROUP", "PluginError", "PluginInfo", "current_plugin", "importing", "installed_plugins", "load_plugins",
           "plugin_status"]

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


_state: dict = {"loaded": False, "loading": False, "status": [], "error": None}
_current: list[PluginInfo | None] = []


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
    return f"{type(exc).__name__}: {exc}"


def load_plugins() -> None:
    """Import every plugin's module (once per process); raise :class:`PluginError` if any failed.

    Re-entrant: a registry used while a plugin is being imported does not
    start a second round. After a failure, every call raises the same error.
    """
    if _state["loading"]:
        return
    if not _state["loaded"]:
        _state["loading"] = True
        try:
            status = []
            for info, ep in installed_plugins():
                try:
                    with importing(info):
                        ep.load()
                except Exception as e:  # any failure of the plugin's code: reported, never skipped
                    status.append((info, _describe(e)))
                else:
                    status.append((info, None))
            _state["status"] = status
            failed = [(i, why) for i, why in status if why is not None]
            if failed:
                lines = [f"{i.where} failed to load: {why}" for i, why in failed]
                names = " ".join(sorted({i.package for i, _ in failed}))
                _state["error"] = ("\n".join(lines) + f"\nFix the plugin or uninstall it (`pip uninstall {names}`); "
                                   "`touchbench plugins list` shows the installed plugins.")
        finally:
            _state["loading"] = False
            _state["loaded"] = True
    if _state["error"] is not None:
        raise PluginError(_state["error"])


def plugin_status() -> list[tuple[PluginInfo, str | None]]:
    """Each plugin entry point with why it failed to load (None: loaded). Loads them first; never raises."""
    with contextlib.suppress(PluginError):
        load_plugins()
    return list(_state["status"])
