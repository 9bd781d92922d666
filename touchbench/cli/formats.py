"""``--format`` choices and format options on the command line, from the file-format registry
(:mod:`touchbench.datasets.formats`); shared by ``data`` and ``predict`` / ``stream``."""

from __future__ import annotations

from typing import Any, Callable

import click

from ..datasets.formats import FORMATS, FileFormat, FormatOption


class FormatChoice(click.Choice):
    """The registered formats that ``keep`` accepts, after the words ``extra``.

    A registered format the command cannot use is refused saying so; an
    unknown one gets the registry's "did you mean".
    """

    def __init__(self, verb: str, keep: Callable[[FileFormat], bool] = lambda f: True, extra: tuple[str, ...] = ()):
        super().__init__([*extra, *(e.name for e in FORMATS.entries() if keep(e.obj))])
        self.verb = verb

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if value in self.choices:
            return value
        if value in FORMATS:
            self.fail(f"touchbench cannot {self.verb} the {value} format (it can: {', '.join(self.choices)})", param, ctx)
        self.fail(FORMATS.suggest(value), param, ctx)


class _OptionValue(click.ParamType):
    """The text of a format option, parsed by the option's own ``parse``."""

    def __init__(self, option: FormatOption):
        self.option = option
        self.name = option.metavar or "value"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if not isinstance(value, str):
            return value
        try:
            return self.option.parse(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)


def format_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """Add a ``--NAME`` option (default None) for every option a registered format takes."""
    takers: dict[str, tuple[FormatOption, dict[str, list[str]]]] = {}
    for e in FORMATS.entries():
        for o in e.obj.options:
            takers.setdefault(o.name, (o, {}))[1].setdefault(o.help, []).append(e.name)
    for o, helps in reversed(list(takers.values())):
        f = click.option(o.flag, o.name, type=_OptionValue(o), default=None, metavar=o.metavar,
                         help=_option_help(helps))(f)
    return f


def _option_help(helps: dict[str, list[str]]) -> str:
    """One option's help over the formats that take it: each format's own words (its default is its own)."""
    if len(helps) == 1:
        (text, names), = helps.items()
        return f"{text} (format {', '.join(names)})."
    return "; ".join(f"format {', '.join(names)}: {text}" for text, names in helps.items()) + "."


FORMATS_HELP = "`touchbench data formats` describes them"
