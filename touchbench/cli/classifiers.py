"""``touchbench classifiers``: the classifier registry on the command line; ``list`` reads the
registry index (:mod:`touchbench.core.listing`)."""

from __future__ import annotations

import click

from ..core.listing import cached_rows
from .common import echo_json, example, json_option
from .plugins import plugin_note


def _fmt(v) -> str:
    return repr(v) if isinstance(v, str) else str(v)


@click.group("classifiers", epilog=example("touchbench classifiers list"))
def classifiers() -> None:
    """Registered classifiers (defaults are the papers' settings)."""


def classifier_table() -> list[dict]:
    """One row per registered classifier: name, description, source, defaults (and as the line listing
    writes them), the extra it needs, whether that is installed and how to install it, the plugin that
    added it, and the note a line listing ends with."""
    from ..classifiers import CLASSIFIERS, cnn, peers, xgb
    from ..classifiers._util import torch_available

    extras_ok = {"deep": torch_available(), "peers": peers.aeon_available(), "xgboost": xgb.xgboost_available()}
    hints = {"deep": cnn.INSTALL_HINT, "peers": peers.INSTALL_HINT, "xgboost": xgb.INSTALL_HINT}
    rows = []
    for e in CLASSIFIERS.entries():
        extra = e.tags.get("extra")
        needs = extra.split(",") if extra else []  # e.g. "peers,deep": every one of them
        available = all(extras_ok.get(x, False) for x in needs)
        defaults = e.tags.get("defaults", {})
        rows.append({
            "name": e.name,
            "description": e.description,
            "source": e.tags.get("source", ""),
            "defaults": defaults,
            "extra": extra,
            "available": available,
            "install": None if available else hints.get(extra, f"pip install 'touchbench[{extra}]'"),
            "plugin": None if e.plugin is None else {"package": e.plugin.package, "version": e.plugin.version,
                                                     "entry_point": e.plugin.entry_point},
            "note": plugin_note(e),
            "defaults_text": ", ".join(f"{k}={_fmt(v)}" for k, v in defaults.items()),
        })
    return rows


@classifiers.command("list", epilog=example("touchbench classifiers list --json"))
@json_option
def list_classifiers(as_json: bool) -> None:
    """List every classifier with its source and defaults."""
    rows = cached_rows("classifiers", classifier_table, ("touchbench.classifiers",))
    if as_json:
        echo_json([{k: v for k, v in r.items() if k not in ("note", "defaults_text")} for r in rows])
        return
    for r in rows:
        status = ""
        if r["extra"]:
            status = f"  [extra '{r['extra']}'" + ("]" if r["available"] else f": not installed; {r['install']}]")
        click.echo(f"{r['name']}  {r['description']}{status}{r['note']}")
        click.echo(f"    source:   {r['source']}")
        click.echo(f"    defaults: {r['defaults_text']}")
