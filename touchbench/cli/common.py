"""What every command shares: ``--json`` output, examples in ``--help``, the ``--jobs`` option,
choices read from a registry when first needed, and the ``touchbench`` loggers (``-v`` / ``-q``)."""

from __future__ import annotations

import importlib
import json
import logging
import math
from typing import Any, Callable, Iterable

import click

JOBS_DEFAULT = 1
log = logging.getLogger("touchbench")


def example(*lines: str) -> str:
    """A ``--help`` epilog showing ``lines`` as typed (click keeps a paragraph after ``\\b`` as is)."""
    return "\b\nExample:\n" + "\n".join(f"  {line}" for line in lines)


def json_option(f):
    """``--json``: the command's output as one JSON document on stdout, nothing else there."""
    return click.option("--json", "as_json", is_flag=True,
                        help="Print the output as JSON (machine-readable; messages stay on stderr).")(f)


class LazyChoice(click.Choice):
    """A choice whose values (a registry's names) are read when first needed -- parsing the
    option, showing the command's help -- not when the command is defined, so that importing
    the command imports none of the registry's modules."""

    def __init__(self, values: Callable[[], Iterable[str]]):
        self._values = values
        self._choices: tuple[str, ...] | None = None
        self.case_sensitive = True

    @property
    def choices(self) -> tuple[str, ...]:  # type: ignore[override]
        if self._choices is None:
            self._choices = tuple(self._values())
        return self._choices


class LazyGroup(click.Group):
    """A group whose subcommands named in ``lazy`` (name -> ``"module:attribute"``) are imported when
    first needed -- run, or listed by the group's help -- so that its other commands (a listing)
    import none of what they need."""

    def __init__(self, *args: Any, lazy: dict[str, str] | None = None, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self.lazy = dict(lazy or {})

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*super().list_commands(ctx), *self.lazy})

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in self.commands and name in self.lazy:
            module, attr = self.lazy[name].split(":")
            self.add_command(getattr(importlib.import_module(module), attr), name)
        return super().get_command(ctx, name)


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item") and callable(value.item):  # numpy scalars
        return _clean(value.item())
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set)):
        return [_clean(v) for v in value]
    return value


def echo_json(value: Any) -> None:
    """``value`` as JSON on stdout (NaN and infinity as null, numpy scalars as numbers)."""
    click.echo(json.dumps(_clean(value), indent=2, default=str))


def jobs_value(ctx: click.Context, param: click.Parameter, value: int) -> int:
    """``--jobs``: a positive number of parallel tasks, or -1 (one per CPU); anything else is a usage error."""
    if value == 0 or value < -1:
        raise click.BadParameter(f"{value} is not a number of parallel tasks: give 1 or more, or -1 for one per CPU "
                                 "(more than the CPUs available runs as many as there are)")
    return value


def jobs_option(f):
    """The one ``--jobs`` of every command that runs tasks; the default is one task at a time (as in
    scikit-learn: predictable memory on a shared machine; results do not depend on it)."""
    return click.option("--jobs", "-j", default=JOBS_DEFAULT, show_default=True, callback=jobs_value,
                        help="Tasks run in parallel (-1: one per CPU; at most the CPUs available, and the tasks).")(f)


class _Plain(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        text = record.getMessage()
        return f"{record.levelname.lower()}: {text}" if record.levelno >= logging.WARNING else text


def setup_logging(verbose: int, quiet: int) -> None:
    """Messages of the ``touchbench`` loggers on stderr: info by default, ``-v`` debug, ``-q``
    warnings and errors only, ``-qq`` errors only."""
    level = logging.INFO - 10 * verbose + 10 * quiet
    level = min(max(level, logging.DEBUG), logging.ERROR)
    handler = logging.StreamHandler()  # stderr, looked up when a record is written
    handler.setFormatter(_Plain())
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False
