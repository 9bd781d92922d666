"""``touchbench data export`` and ``data convert``: datasets written to and read from files, in the
formats of the file-format registry (:mod:`touchbench.datasets.formats`), which gives their
``--format`` choices and options."""

from __future__ import annotations

from pathlib import Path

import click

from ..datasets.formats import FORMATS
from .common import example
from .data import _load
from .formats import FORMATS_HELP, FormatChoice, format_options


@click.command(epilog=example("touchbench data export haart-challenge out/challenge --format challenge-csv"))
@click.argument("name")
@click.argument("out_dir", type=click.Path(file_okay=False))
@click.option("--format", "fmt", type=FormatChoice("write", lambda f: f.writer is not None), default="challenge-csv",
              show_default=True, help=f"Format to write ({FORMATS_HELP}).")
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None)
@click.option("--data-dir", type=click.Path(file_okay=False), default=None)
def export(name: str, out_dir: str, fmt: str, cache_dir, data_dir) -> None:
    """Write dataset NAME to OUT_DIR (the challenge's training.csv and testWITHLABELS.csv, or Parquet)."""
    ds = _load(name, cache_dir, data_dir)
    for p in FORMATS.get(fmt).write(ds, out_dir):
        click.echo(str(p))


@click.command(epilog=example("touchbench data convert frames.csv mine.parquet --format table --grid 6x6 --frame-rate 50"))
@click.argument("source", type=click.Path(exists=True))
@click.argument("out", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", type=FormatChoice("read"), required=True,
              help=f"Format of SOURCE ({FORMATS_HELP}).")
@format_options
@click.option("--name", default=None, help="Dataset name (default: OUT's file name without .parquet).")
def convert(source: str, out: str, fmt: str, name, **options) -> None:
    """Read SOURCE in a supported format and save it as a touchbench Parquet dataset OUT."""
    form = FORMATS.get(fmt)
    missing = form.missing(options)
    if missing:
        raise click.UsageError(f"--format {fmt} needs {' and '.join(o.usage for o in missing)}")
    ds = form.read(source, name=name or Path(out).name.removesuffix(".parquet"), **options)
    ds.to_parquet(out)
    click.echo(f"{out}: {len(ds)} captures, hash {ds.content_hash}")
