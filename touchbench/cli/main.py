"""The ``touchbench`` command: a click group whose subcommands live in one
module per area (``cli/data.py``, ``cli/features.py``, ...)."""

from __future__ import annotations

import importlib
import sys

import click

from .. import __version__
from ..core.errors import TouchbenchError
from ..core.plugins import PluginError
from ..protocols.library import add_protocol_dir

# (module, attribute) of each subcommand; one line per area.
_COMMANDS: list[tuple[str, str]] = [
    ("touchbench.cli.data", "data"),
    ("touchbench.cli.classifiers", "classifiers"),
    ("touchbench.cli.features", "features"),
    ("touchbench.cli.demo", "demo"),
    ("touchbench.cli.deploy", "train"),
    ("touchbench.cli.deploy", "predict"),
    ("touchbench.cli.deploy", "stream"),
    ("touchbench.cli.protocols", "protocols"),
    ("touchbench.cli.run", "run"),
    ("touchbench.cli.reports", "leaderboard"),
    ("touchbench.cli.reports", "compare"),
    ("touchbench.cli.reports", "plot"),
    ("touchbench.cli.reports", "report"),
    ("touchbench.cli.reports", "papers"),
    ("touchbench.cli.scenes", "scenes"),
    ("touchbench.cli.plugins", "plugins"),
]


class _Group(click.Group):
    """Turns a TouchbenchError anywhere below into one clear line and exit 2."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except TouchbenchError as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(2)


@click.group(cls=_Group)
@click.version_option(__version__, prog_name="touchbench")
@click.option("--protocols", "protocol_folders", multiple=True, type=click.Path(file_okay=False, exists=True),
              help="A folder of your own protocols, searched by name before the shipped ones (repeatable; "
                   "also $TOUCHBENCH_PROTOCOLS).")
def cli(protocol_folders: tuple[str, ...]) -> None:
    """touchbench: benchmark social touch gesture recognition."""
    for folder in protocol_folders:
        add_protocol_dir(folder)


def _unavailable(name: str, error: PluginError) -> click.Command:
    """Stands in for a command whose options come from the registries (``--format``) when a plugin
    failed to load: ``--help`` and the other commands still work; this one reports the plugin."""

    @click.command(name, context_settings={"ignore_unknown_options": True, "allow_extra_args": True,
                                           "help_option_names": []},
                   help="Unavailable: a plugin failed to load (`touchbench plugins list`).")
    def command() -> None:
        raise PluginError(str(error))

    return command


for _mod, _attr in _COMMANDS:
    try:
        _command = getattr(importlib.import_module(_mod), _attr)
    except PluginError as _error:
        _command = _unavailable(_attr, _error)
    cli.add_command(_command)
