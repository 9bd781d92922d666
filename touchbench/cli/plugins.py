"""``touchbench plugins``: the installed plugins, their versions and what they registered."""

from __future__ import annotations

import click

from ..core.listing import cached_rows
from ..core.plugins import GROUP, PluginError, PluginInfo, plugin_status
from ..core.registry import Entry, Registry
from .common import echo_json, example, json_option

#: The packages of the registries a plugin may fill: a listing read from the registry index
#: (:mod:`touchbench.core.listing`) imports none of them.
REGISTRY_PACKAGES = ("touchbench.features", "touchbench.classifiers", "touchbench.datasets",
                     "touchbench.protocols.schemes", "touchbench.reports.figures")


def plugin_registries() -> tuple[Registry, ...]:
    """Every registry a plugin may fill, as the listings name them (importing their packages)."""
    from ..classifiers import CLASSIFIERS
    from ..datasets import DATASETS
    from ..datasets.formats import FORMATS
    from ..features import FEATURES
    from ..protocols.schemes import SPLITTERS
    from ..reports.figures import FIGURES

    return FEATURES, CLASSIFIERS, DATASETS, FORMATS, SPLITTERS, FIGURES


def plugin_note(e: Entry) -> str:
    """``  [plugin PACKAGE VERSION]`` for a plugin's entry, else nothing (line listings end with it)."""
    return f"  [plugin {e.plugin.label}]" if e.plugin is not None else ""


def package_of(e: Entry) -> str:
    """The package an entry comes from: the plugin's distribution and version, or touchbench."""
    return e.plugin.label if e.plugin is not None else "touchbench"


def plugin_entries() -> list[tuple[str, Entry]]:
    """(registry kind, entry) for every entry a plugin added, over every registry that takes plugins.

    Loads the plugins (a plugin that failed to load is left out: it added nothing).
    """
    return [(reg.kind, e) for reg in plugin_registries() for e in reg.entries() if e.plugin is not None]


def plugin_table() -> list[dict]:
    """One row per plugin entry point: package, version, entry point, module, why it failed to load
    (None: loaded) and what it registered (registry, name, description)."""
    plugin_registries()  # imported before any plugin is: what their modules register is touchbench's
    status = plugin_status()
    added = plugin_entries() if status else []
    return [{"package": info.package, "version": info.version, "entry_point": info.entry_point,
             "module": info.module, "error": None if error is None else str(error),
             "registered": [{"registry": kind, "name": e.name, "description": e.description}
                            for kind, e in added if e.plugin == info]} for info, error in status]


@click.group("plugins", epilog=example("touchbench plugins list"))
def plugins() -> None:
    """Installed plugins: packages that add feature sets, classifiers, datasets, file formats, schemes or
    figure kinds."""


@plugins.command("list", epilog=example("touchbench plugins list --json"))
@json_option
def list_(as_json: bool) -> None:
    """Every installed plugin with its version, its entry point and what it registered."""
    rows = cached_rows("plugins", plugin_table, REGISTRY_PACKAGES)
    failed = [r for r in rows if r["error"] is not None]
    if as_json:
        echo_json(rows)
        if failed:
            raise PluginError("a plugin failed to load (see \"error\" in the output)")
        return
    if not rows:
        click.echo(f"no plugins installed (a plugin declares an entry point in the group {GROUP!r}; "
                   "see the README, section Plugins)")
        return
    for r in rows:
        click.echo(f"{r['package']} {r['version']}  (entry point {r['entry_point']} = {r['module']})")
        if r["error"] is not None:
            click.echo(f"    failed to load: {r['error']}")
        for e in r["registered"]:
            click.echo(f"    {e['registry']:19s} {e['name']:26s} {e['description']}")
        if r["error"] is None and not r["registered"]:
            click.echo("    (registered nothing)")
    if failed:
        raise PluginError(f"{len(failed)} plugin(s) failed to load: "
                          + ", ".join(_where(r) for r in failed))


def _where(row: dict) -> str:
    """A plugin row's distribution and entry point, as :attr:`PluginInfo.where` writes them."""
    return PluginInfo(row["package"], row["version"], row["entry_point"], row["module"]).where
