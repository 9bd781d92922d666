"""``touchbench export``: results in other tools' formats (tsml-eval's results files)."""

from __future__ import annotations

from pathlib import Path

import click

from .common import echo_json, example, json_option, log
from .reports import _boards, _with_table_options


@click.command("export", epilog=example("touchbench export results/demo-haart --format tsml --out tsml-results"))
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--format", "fmt", type=click.Choice(["tsml"]), default="tsml", show_default=True,
              help="tsml: tsml-eval's classifier results files (OUT/<method>/Predictions/<dataset>/testResample<i>.csv), "
                   "read by tsml-eval's and aeon's evaluation tools; a resample is a fold of the scheme.")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False), help="Folder to write into.")
@json_option
@_with_table_options
def export(results, fmt, out, as_json, dataset, scheme, alpha, pool_machines, machine) -> None:
    """Write the test predictions of RESULTS (results folders) in another tool's format."""
    from ..reports.export import export_tsml

    rs, lbs = _boards(results, dataset, scheme, alpha, pool_machines, machine)
    paths = export_tsml(rs, lbs, Path(out))
    if as_json:
        echo_json({"format": fmt, "files": [str(p) for p in paths]})
    else:
        log.info(f"wrote {len(paths)} tsml results file(s) under {out}")
