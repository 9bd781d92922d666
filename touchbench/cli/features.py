"""``touchbench features``: the registered feature sets."""

from __future__ import annotations

import inspect

import click

from ..features import FEATURES
from .plugins import package_of


def _grid(value: str) -> tuple[int, int]:
    try:
        h, w = (int(v) for v in value.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"expected HxW such as 8x8, got {value!r}") from None
    if h < 1 or w < 1:
        raise click.BadParameter("grid sides must be at least 1")
    return h, w


def feature_table(grid: tuple[int, int] = (8, 8)) -> list[dict]:
    """One row per registered set: name, paper, output size for ``grid`` (default parameters), cost,
    description, package (touchbench or the plugin's distribution and version)."""
    rows = []
    for e in FEATURES.entries():
        cls = e.obj
        rows.append(
            {
                "name": e.name,
                "paper": cls.paper,
                "size": cls().n_features(grid),
                "cost": cls.cost,
                "fold_dependent": cls.fold_dependent,
                "description": e.description,
                "package": package_of(e),
            }
        )
    return rows


@click.group()
def features() -> None:
    """Feature sets: scikit-learn transformers over captures."""


@features.command("list")
@click.option("--grid", "grid", default="8x8", show_default=True, help="grid (HxW) the output sizes are computed for")
def list_(grid: str) -> None:
    """Every feature set with its paper, output size and cost tag."""
    from rich.console import Console
    from rich.table import Table

    g = _grid(grid)
    rows = feature_table(g)
    plugins = any(r["package"] != "touchbench" for r in rows)  # the package column only when a plugin added sets
    table = Table(title=f"feature sets (output size for a {g[0]} x {g[1]} grid, default parameters)")
    for col in ("name", "paper", "size", "cost", "fold-dependent", "description") + (("package",) if plugins else ()):
        table.add_column(col, justify="right" if col == "size" else "left", overflow="fold")
    for r in rows:
        table.add_row(r["name"], r["paper"], str(r["size"]), r["cost"], "yes" if r["fold_dependent"] else "no",
                      r["description"], *((r["package"],) if plugins else ()))
    Console(width=max(Console().width, 140)).print(table)


@features.command("show")
@click.argument("name")
def show(name: str) -> None:
    """A feature set's documentation: paper section, interpretations, parameters."""
    cls = FEATURES.get(name)  # an unknown name raises UnknownNameError (exit 2, nearest names)
    click.echo(f"{name}  ({cls.paper}; cost {cls.cost}; fold-dependent: {'yes' if cls.fold_dependent else 'no'})")
    click.echo(f"parameters: {inspect.signature(cls.__init__)}".replace("(self, ", "("))
    click.echo("")
    click.echo(inspect.getdoc(cls) or "")
