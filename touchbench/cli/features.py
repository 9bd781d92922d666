"""``touchbench features``: the registered feature sets.

``list`` without a sensor reads the registry index (:mod:`touchbench.core.listing`); the feature
sets' modules are imported by the commands that need them (sizes for a sensor, ``show``)."""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING

import click

from ..core.listing import cached_rows
from .common import echo_json, example, json_option, log
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


@click.group(epilog=example("touchbench features list --grid 8x8 --frame-rate 54 --value-range 0..1023", "touchbench features show msd"))
def features() -> None:
    """Feature sets: scikit-learn transformers over captures."""


def _value_range(text: str | None, old: tuple[float, float] | None) -> tuple[float, float] | None:
    """The sensor's value range from ``--value-range LO..HI`` (the spelling of every reader's option),
    or from the former ``--range LO HI``, still read for one release with a warning."""
    if old is not None:
        if text is not None:
            raise click.UsageError("give the value range once: --value-range LO..HI (--range LO HI is its former spelling)")
        log.warning(f"--range LO HI is deprecated and goes in the next release: write --value-range {old[0]:g}..{old[1]:g}")
        text = f"{old[0]!r}..{old[1]!r}"
    if text is None:
        return None
    from ..datasets.formats import parse_value_range

    try:
        return parse_value_range(text)
    except ValueError as e:
        raise click.BadParameter(str(e), param_hint="--value-range") from None


def _frame_rate(rate: float | None, old: float | None) -> float | None:
    """The sensor's frame rate from ``--frame-rate`` (every reader's spelling), or from ``--rate``, its
    former spelling, with a warning."""
    if old is None:
        return rate
    if rate is not None:
        raise click.UsageError("give the frame rate once: --frame-rate HZ (--rate is its former spelling)")
    log.warning(f"--rate is deprecated and goes in the next release: write --frame-rate {old:g}")
    return old


@features.command("list", epilog=example("touchbench features list --grid 19x24 --frame-rate 12 --value-range 0..255 --json"))
@json_option
@click.option("--grid", "grid", default=None, help="sensor grid (HxW) to compute the output sizes for")
@click.option("--frame-rate", "rate", type=float, default=None, metavar="HZ",
              help="sensor frame rate (Hz), with --grid (as the readers' --frame-rate)")
@click.option("--rate", "old_rate", type=float, default=None, hidden=True,
              help="former spelling of --frame-rate")
@click.option("--value-range", "value_range", default=None, metavar="LO..HI",
              help="sensor value range, e.g. 0..1023 (as data convert's --value-range), with --grid")
@click.option("--range", "old_range", type=(float, float), default=None, hidden=True,
              help="deprecated spelling of --value-range: LO HI")
def list_(as_json: bool, grid: str | None, rate: float | None, old_rate: float | None, value_range: str | None,
          old_range: tuple[float, float] | None) -> None:
    """Every feature set with its paper, output size and cost tag (sizes for the sensor
    given by --grid, --frame-rate and --value-range; '-' where a set needs parameters stated or
    refuses that sensor)."""
    from rich.console import Console
    from rich.table import Table

    value_range = _value_range(value_range, old_range)
    rate = _frame_rate(rate, old_rate)
    sensor = None
    if grid is not None or rate is not None or value_range is not None:
        if grid is None or rate is None or value_range is None:
            raise click.UsageError("give --grid, --frame-rate and --value-range together (the sensor the sizes are computed for)")
        from ..datasets.model import SensorSpec

        try:
            sensor = SensorSpec("--grid", _grid(grid), rate, value_range)
        except ValueError as e:
            raise click.BadParameter(str(e)) from None
    title = ("feature sets (output size for " + sensor.describe().replace("'--grid' ", "") + ", default parameters)"
             if sensor is not None else "feature sets (output sizes: give --grid, --frame-rate and --value-range)")
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


@features.command("condition", epilog=example(
    "touchbench features condition zhou-table6-descriptors-tpm",
    "touchbench features condition gaus-table5-haart --fold f0 --json"))
@click.argument("protocol")
@click.option("--evaluation", default=None, help="The evaluation to measure, for a protocol with several.")
@click.option("--fold", default=None, help="The training part of this fold of the protocol's scheme only.")
@json_option
def condition(protocol: str, evaluation: str | None, fold: str | None, as_json: bool) -> None:
    """The condition number of the pooled within-class covariance (the matrix LDA inverts) of each
    feature combination of PROTOCOL, on the captures `touchbench train` fits on (float64; inf when
    singular)."""
    from ..deploy.conditioning import within_class_conditioning

    rows = within_class_conditioning(protocol, evaluation=evaluation, fold=fold)
    for r in rows:
        r["singular"] = r["condition"] == float("inf")
    if as_json:
        echo_json(rows)
        return
    click.echo(f"{rows[0]['selection']}: {rows[0]['captures']} captures, {rows[0]['classes']} classes")
    for r in rows:
        cond = "inf (singular)" if r["singular"] else f"{r['condition']:.4g}"
        click.echo(f"{r['features']}: {r['columns']} columns, rank {r['rank']}, condition number {cond}")
