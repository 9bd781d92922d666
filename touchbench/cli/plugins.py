"""``touchbench plugins``: the installed plugins, their versions and what they registered."""

from __future__ import annotations

import click

from ..classifiers import CLASSIFIERS
from ..core.plugins import GROUP, PluginError, plugin_status
from ..core.registry import Entry, Registry
from ..datasets import DATASETS
from ..datasets.formats import FORMATS
from ..features import FEATURES
from ..protocols.schemes import SPLITTERS
from ..reports.figures import FIGURES
from .common import echo_json, example, json_option

# Every registry a plugin may fill, as the listings name them.
PLUGIN_REGISTRIES: tuple[Registry, ...] = (FEATURES, CLASSIFIERS, DATASETS, FORMATS, SPLITTERS, FIGURES)


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
    return [(reg.kind, e) for reg in PLUGIN_REGISTRIES for e in reg.entries() if e.plugin is not None]


@click.group("plugins", epilog=example("touchbench plugins list"))
def plugins() -> None:
    """Installed plugins: packages that add feature sets, classifiers, datasets, file formats, schemes or
    figure kinds."""


@plugins.command("list", epilog=example("touchbench plugins list --json"))
@json_option
def list_(as_json: bool) -> None:
    """Every installed plugin with its version, its entry point and what it registered."""
    status = plugin_status()
    if as_json:
        added = plugin_entries()
        echo_json([{"package": info.package, "version": info.version, "entry_point": info.entry_point,
                    "module": info.module, "error": None if error is None else str(error),
                    "registered": [{"registry": kind, "name": e.name, "description": e.description}
                                   for kind, e in added if e.plugin == info]} for info, error in status])
        if any(error is not None for _, error in status):
            raise PluginError("a plugin failed to load (see \"error\" in the output)")
        return
    if not status:
        click.echo(f"no plugins installed (a plugin declares an entry point in the group {GROUP!r}; "
                   "see the README, section Plugins)")
        return
    added = plugin_entries()
    for info, error in status:
        click.echo(f"{info.package} {info.version}  (entry point {info.entry_point} = {info.module})")
        if error is not None:
            click.echo(f"    failed to load: {error}")
        mine = [(kind, e) for kind, e in added if e.plugin == info]
        for kind, e in mine:
            click.echo(f"    {kind:19s} {e.name:26s} {e.description}")
        if error is None and not mine:
            click.echo("    (registered nothing)")
    failed = [info for info, error in status if error is not None]
    if failed:
        raise PluginError(f"{len(failed)} plugin(s) failed to load: " + ", ".join(i.where for i in failed))
