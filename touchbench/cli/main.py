"""The ``touchbench`` command: a click group whose subcommands live in one module per area
(``cli/data.py``, ``cli/features.py``, ...), imported only when a command runs, so that
``touchbench --help`` and ``--version`` start in a fraction of a second."""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading

import click

from ..core.version import __version__
from ..core.errors import TouchbenchError
from . import exitcodes
from .common import example, setup_logging

# name -> (module, attribute, one-line help shown by `touchbench --help` without importing the module)
_COMMANDS: dict[str, tuple[str, str, str]] = {
    "audit": ("touchbench.cli.audit", "audit", "A protocol's methods under the honest scheme and each leaky variant."),
    "classifiers": ("touchbench.cli.classifiers", "classifiers", "Registered classifiers (defaults are the papers' settings)."),
    "compare": ("touchbench.cli.reports", "compare", "The paired test of method A against B, per fold or subject."),
    "data": ("touchbench.cli.data", "data", "Datasets: real readers, the cache, exports."),
    "demo": ("touchbench.cli.demo", "demo", "Run the main job on the embedded default and show its leaderboard."),
    "export": ("touchbench.cli.export", "export", "Results in other tools' formats (tsml-eval results files)."),
    "features": ("touchbench.cli.features", "features", "Feature sets: scikit-learn transformers over captures."),
    "leaderboard": ("touchbench.cli.reports", "leaderboard", "One table per dataset and scheme: rank, accuracy, intervals, tests."),
    "papers": ("touchbench.cli.reports", "papers", "Reproduce the four papers (the shipped papers/ protocols)."),
    "plot": ("touchbench.cli.reports", "plot", "Paper-ready figures: Pareto front, confusion, subjects, critical difference."),
    "plugins": ("touchbench.cli.plugins", "plugins", "Installed plugins: packages that add components."),
    "predict": ("touchbench.cli.deploy", "predict", "Label the captures of DATA with MODEL."),
    "protocols": ("touchbench.cli.protocols", "protocols", "Protocol files: validate them, list the shipped ones."),
    "reference": ("touchbench.cli.reference", "reference", "Reference results: save a finished run, list the saved ones."),
    "report": ("touchbench.cli.reports", "report", "One self-contained HTML page with every leaderboard and plot."),
    "run": ("touchbench.cli.run", "run", "Evaluate a protocol: every method under its scheme, resumable."),
    "scenes": ("touchbench.cli.scenes", "scenes", "Synthetic scenes: sensors, gestures and people described in YAML."),
    "stream": ("touchbench.cli.deploy", "stream", "Label a stream of frames with MODEL, one decision per hop."),
    "train": ("touchbench.cli.deploy", "train", "Fit one method of a protocol on its data and save the model."),
}


# how long a SIGTERM that lands inside an import waits before it is delivered again
_IMPORT_RETRY_S = 0.05


# the modules of Python's import machinery (frozen, as Python runs them by default, or not)
_IMPORT_MACHINERY = {"_frozen_importlib", "_frozen_importlib_external", "importlib._bootstrap",
                     "importlib._bootstrap_external"}


def _importing(frame) -> bool:
    """Whether ``frame`` runs inside Python's import machinery (a module's body being executed)."""
    while frame is not None:
        if frame.f_globals.get("__name__") in _IMPORT_MACHINERY:
            return True
        frame = frame.f_back
    return False


def _terminate(signum, frame) -> None:
    """SIGTERM: the same path as Ctrl-C (finished work is kept). One that lands while a module is
    being imported is sent again a moment later instead: an exception raised inside the import of
    a compiled library (pyarrow, numpy) can leave it half made, and the command would then end
    with an unrelated error, or even run to the end, instead of stopping."""
    if _importing(frame):
        timer = threading.Timer(_IMPORT_RETRY_S, os.kill, (os.getpid(), signum))
        timer.daemon = True
        timer.start()
        return
    raise KeyboardInterrupt


class _Group(click.Group):
    """Subcommands imported on first use; a TouchbenchError anywhere below becomes one clear line and
    exit status 3, an interruption exit status 130."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(_COMMANDS)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in _COMMANDS:
            return None
        module, attr, _ = _COMMANDS[name]
        return getattr(importlib.import_module(module), attr)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, _COMMANDS[name][2]) for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except TouchbenchError as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(exitcodes.DATA)
        except KeyboardInterrupt:
            click.echo("\ninterrupted: finished work is kept; run the same command again to resume", err=True)
            sys.exit(exitcodes.INTERRUPTED)


@click.group(cls=_Group, epilog=exitcodes.HELP + "\n\n" + example("touchbench run demo-haart --jobs 2",
                                                                   "touchbench leaderboard results/demo-haart"))
@click.version_option(__version__, prog_name="touchbench")
@click.option("--protocols", "protocol_folders", multiple=True, type=click.Path(file_okay=False, exists=True),
              help="A folder of your own protocols, searched by name before the shipped ones (repeatable; "
                   "also $TOUCHBENCH_PROTOCOLS).")
@click.option("--verbose", "-v", count=True, help="More messages on stderr (repeatable).")
@click.option("--quiet", "-q", count=True, help="Fewer messages on stderr: warnings and errors only (-qq: errors).")
def cli(protocol_folders: tuple[str, ...], verbose: int, quiet: int) -> None:
    """touchbench: benchmark social touch gesture recognition."""
    setup_logging(verbose, quiet)
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminate)
    if protocol_folders:
        from ..protocols.library import add_protocol_dir

        for folder in protocol_folders:
            add_protocol_dir(folder)


def main() -> None:
    cli()


if __name__ == "__main__":
    main()
