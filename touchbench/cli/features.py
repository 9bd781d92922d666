"""``touchbench features``: the registered feature sets.

``list`` without a sensor reads the registry index (:mod:`touchbench.core.listing`); the feature
sets' modules are imported by the commands that need them (sizes for a sensor, ``show``)."""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING

import click

from ..core.listing import cached_rows
from .common import echo_json, example, json_option
from .plugins import package_of

if TYPE_CHECKING:
    from ..datasets.model import SensorSpec


def _grid(value: str) -> tuple[int, int]:
    from ..datasets.formats import parse_grid

    try:
        return parse_grid(value)
    except ValueError as e:
        raise click.BadParameter(str(e)) from None


def _size(name: str, sensor: SensorSpec | None) -> int | None:
    """Output size of ``name`` with default parameters on ``sensor``; None without a sensor, or when
    the set needs parameters stated (raw-window's frames) or refuses the sensor."""
    if sensor is None:
        return None
    from ..features.base import make_feature_set

    fs = make_feature_set(name, {}, sensor)
    if fs.check_sensor(sensor) is not None:
        return None
    return fs.n_features(sensor.grid)


def feature_table(sensor: SensorSpec | None = None) -> list[dict]:
    """One row per registered set: name, paper, output size on ``sensor`` (default parameters;
    None without a sensor or where the set cannot say), cost, description, package
    (touchbench or the plugin's distribution and version)."""
    from ..features import FEATURES

    rows = []
    for e in FEATURES.entries():
        cls = e.obj
        rows.append(
            {
                "name": e.name,
                "paper": cls.paper,
                "size": _size(e.name, sensor),
                "cost": cls.cost,
                "fold_dependent": cls.fold_dependent,
                "description": e.description,
                "package": package_of(e),
            }
        )
    return rows


@click.group(epilog=example("touchbench features list --grid 8x8 --rate 54 --range 0 1023", "touchbench features show msd"))
def features() -> None:
    """Feature sets: scikit-learn transformers over captures."""


@features.command("list", epilog=example("touchbench features list --grid 19x24 --rate 12 --range 0 255 --json"))
@json_option
@click.option("--grid", "grid", default=None, help="sensor grid (HxW) to compute the output sizes for")
@click.option("--rate", "rate", type=float, default=None, help="sensor frame rate (Hz), with --grid")
@click.option("--range", "value_range", type=(float, float), default=None, help="sensor value range LOW HIGH, with --grid")
def list_(as_json: bool, grid: str | None, rate: float | None, value_range: tuple[float, float] | None) -> None:
    """Every feature set with its paper, output size and cost tag (sizes for the sensor
    given by --grid, --rate and --range; '-' where a set needs parameters stated or
    refuses that sensor)."""
    from rich.console import Console
    from rich.table import Table

    sensor = None
    if grid is not None or rate is not None or value_range is not None:
        if grid is None or rate is None or value_range is None:
            raise click.UsageError("give --grid, --rate and --range together (the sensor the sizes are computed for)")
        from ..datasets.model import SensorSpec

        try:
            sensor = SensorSpec("--grid", _grid(grid), rate, value_range)
        except ValueError as e:
            raise click.BadParameter(str(e)) from None
    title = ("feature sets (output size for " + sensor.describe().replace("'--grid' ", "") + ", default parameters)"
             if sensor is not None else "feature sets (output sizes: give --grid, --rate and --range)")
    rows = feature_table(sensor) if sensor is not None else cached_rows("features", feature_table, ("touchbench.features",))
    if as_json:
        echo_json(rows)
        return
    plugins = any(r["package"] != "touchbench" for r in rows)  # the package column only when a plugin added sets
    table = Table(title=title)
    for col in ("name", "paper", "size", "cost", "fold-dependent", "description") + (("package",) if plugins else ()):
        table.add_column(col, justify="right" if col == "size" else "left", overflow="fold")
    for r in rows:
        size = "-" if r["size"] is None else str(r["size"])
        table.add_row(r["name"], r["paper"], size, r["cost"], "yes" if r["fold_dependent"] else "no", r["description"],
                      *((r["package"],) if plugins else ()))
    Console(width=max(Console().width, 140)).print(table)


@features.command("show", epilog=example("touchbench features show sd"))
@click.argument("name")
def show(name: str) -> None:
    """A feature set's documentation: paper section, interpretations, parameters."""
    from ..features import FEATURES

    cls = FEATURES.get(name)  # an unknown name raises UnknownNameError (exit 2, nearest names)
    click.echo(f"{name}  ({cls.paper}; cost {cls.cost}; fold-dependent: {'yes' if cls.fold_dependent else 'no'})")
    click.echo(f"parameters: {inspect.signature(cls.__init__)}".replace("(self, ", "("))
    click.echo("")
    click.echo(inspect.getdoc(cls) or "")
