"""``touchbench protocols``: validate a protocol file, list the shipped protocols."""

from __future__ import annotations

from pathlib import Path

import click

from ..core.yamlsafe import load_bounded
from ..protocols.library import find_protocol, listed_protocols, protocol_dirs
from ..protocols.schema import load_protocol


def _description(path: Path) -> str:
    try:
        data, _ = load_bounded(path.read_text(encoding="utf-8"))
    except Exception:
        return "(not valid YAML)"
    if not isinstance(data, dict):
        return "(not a protocol)"
    text = str(data.get("description") or "").strip()
    return text.splitlines()[0] if text else ""


@click.group()
def protocols() -> None:
    """Protocol files: validate them, list the shipped ones."""


@protocols.command("validate")
@click.argument("file")
@click.option("--schema-only", is_flag=True, help="Check the file alone; do not load the dataset or build the folds.")
def validate(file: str, schema_only: bool) -> None:
    """Validate FILE: schema, names, parameters, and (unless --schema-only)
    the dataset filters and the folds of the scheme. Nothing is computed."""
    path = find_protocol(file)
    proto = load_protocol(path)
    combos = proto.combinations()
    clfs = proto.classifier_entries()
    n_methods = len(proto.entries())
    shape = f"{len(combos)} feature combination(s) x {len(clfs)} classifier(s)" if combos else ""
    extra = f"{len(proto.method_entries())} method(s)" if proto.methods else ""
    click.echo(f"{path}: valid protocol {proto.name!r}: scheme {proto.scheme.name}, "
               + " + ".join(x for x in (shape, extra) if x))
    if schema_only:
        return
    from ..engine.runner import plan_run

    plan = plan_run(proto)
    ds = plan.dataset
    click.echo(f"dataset {proto.dataset.name}: {len(ds)} captures after filters, "
               f"{ds.meta['subject'].nunique()} subjects, {ds.meta[proto.target].nunique()} {proto.target} classes")
    shape = f"{len(combos)} x {len(clfs)}" if not proto.methods else f"{n_methods} method(s)"
    click.echo(f"{plan.n_folds} fold(s) x {shape} = {len(plan.tasks)} task(s)")
    for n in plan.notes:
        click.echo(f"note: {n}")


@protocols.command("list")
def list_() -> None:
    """Protocols found by name: your folders (--protocols, $TOUCHBENCH_PROTOCOLS,
    ./protocols) and the shipped ones (papers included), with their descriptions."""
    files = listed_protocols()
    for f in files:
        try:
            rel = f.relative_to(Path.cwd())
        except ValueError:
            rel = f
        click.echo(f"{str(rel):48s} {_description(f)}")
    if not files:
        click.echo("no protocols found (looked in " + ", ".join(str(d) for d in protocol_dirs()) + ")")
