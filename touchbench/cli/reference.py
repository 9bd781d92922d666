"""``touchbench reference``: save a finished run as reference results, list the saved ones.

``touchbench leaderboard RESULTS --reference NAME`` places a reference's
methods beside a run's when their test sets have the same content
(:mod:`touchbench.reports.reference`). ``save`` writes into the user's folder of
references; the shipped ones are read-only.
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
    """The saved references, the user's and the shipped ones: name, origin, protocol, the
    touchbench version and machine that made them."""
    from ..reports.reference import find_reference, reference_names, shipped_names

    refs = [find_reference(n) for n in reference_names()]
    shipped = set(shipped_names())
    hides = {r.name for r in refs if r.origin == "user" and r.name in shipped}
    if as_json:
        echo_json([{**r.index, "name": r.name, "path": str(r.path), "origin": r.origin,
                    "hides_shipped": r.name in hides} for r in refs])
        return
    if not refs:
        click.echo("no reference results saved (`touchbench reference save RESULTS --name NAME`)")
    for r in refs:
        hidden = " (hides the shipped one of this name)" if r.name in hides else ""
        click.echo(f"{r.name:24s} {r.origin:8s} {r.describe().split(': ', 1)[1]}; "
                   f"{len(r.evaluations())} evaluation(s){hidden}")


def _name(ctx: click.Context, param: click.Parameter, value: str) -> str:
    from ..reports.reference import ReferenceError, check_reference_name

    try:
        return check_reference_name(value)
    except ReferenceError as e:
        raise click.BadParameter(str(e)) from None


@reference.command("save", epilog=example("touchbench reference save results/mine --name my-method",
                                          "touchbench reference save results/mine --name my-method --force"))
@click.argument("results", type=click.Path(exists=True, file_okay=False))
@click.option("--name", required=True, callback=_name,
              help="The reference's name (as `leaderboard --reference` takes it): 1 to 64 ASCII letters, digits, "
                   "'-', '_' or '.', starting with a letter or a digit; not a shipped reference's name.")
@click.option("--to", "dest", type=click.Path(file_okay=False), default=None,
              help="Folder of references [default: the user's, $TOUCHBENCH_REFERENCE_DIR or reference/ in the "
                   "user's data directory]. `--to touchbench/data/reference` in a source checkout replaces the "
                   "shipped ones (`make reference-results`).")
@click.option("--force", is_flag=True, help="Replace a saved reference of this name (atomically).")
def save(results: str, name: str, dest: str | None, force: bool) -> None:
    """Save the finished run in RESULTS as the reference NAME: its scores, predictions and
    manifest per evaluation, with the version and machine that made them. A reference of that
    name is replaced only with --force; a shipped reference's name is refused (they are read-only)
    unless --to is the shipped folder itself."""
    from ..reports.reference import find_reference, save_reference

    out = save_reference(results, name, dest, force=force)
    click.echo(f"saved {find_reference(name).describe() if dest is None else name} in {out}")
