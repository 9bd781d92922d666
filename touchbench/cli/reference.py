"""``touchbench reference``: save a finished run as reference results, list the saved ones.

``touchbench leaderboard RESULTS --reference NAME`` places a reference's
methods beside a run's when their test sets have the same content
(:mod:`touchbench.reports.reference`).
"""

from __future__ import annotations

import click

from .common import echo_json, example, json_option


@click.group("reference", epilog=example("touchbench reference list",
                                            "touchbench leaderboard results/mine --reference haart-loso-msd-rf"))
def reference() -> None:
    """Reference results: the shipped protocols' per-fold results, to compare a new method
    against without rerunning the shipped ones (`leaderboard --reference NAME`)."""


@reference.command("list", epilog=example("touchbench reference list --json"))
@json_option
def list_references(as_json: bool) -> None:
    """The saved references: name, protocol, the touchbench version and machine that made them."""
    from ..reports.reference import find_reference, reference_names

    refs = [find_reference(n) for n in reference_names()]
    if as_json:
        echo_json([{"name": r.name, "path": str(r.path), **r.index} for r in refs])
        return
    if not refs:
        click.echo("no reference results saved (`touchbench reference save RESULTS --name NAME`)")
    for r in refs:
        click.echo(f"{r.name:24s} {r.describe().split(': ', 1)[1]}; {len(r.evaluations())} evaluation(s)")


@reference.command("save", epilog=example("touchbench reference save results/demo-haart --name demo-haart"))
@click.argument("results", type=click.Path(exists=True, file_okay=False))
@click.option("--name", required=True, help="The reference's name (as `leaderboard --reference` takes it).")
@click.option("--to", "dest", type=click.Path(file_okay=False), default=None,
              help="Folder of references [default: the package's own, the shipped references].")
def save(results: str, name: str, dest: str | None) -> None:
    """Save the finished run in RESULTS as the reference NAME: its scores, predictions and
    manifest per evaluation, with the version and machine that made them."""
    from ..reports.reference import find_reference, save_reference

    out = save_reference(results, name, dest)
    click.echo(f"saved {find_reference(name).describe() if dest is None else name} in {out}")
