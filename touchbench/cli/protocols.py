"""``touchbench protocols``: validate a protocol file, list the shipped protocols."""

from __future__ import annotations

from pathlib import Path

import click

from ..core.yamlsafe import load_bounded
from ..protocols.library import find_protocol, listed_protocols, protocol_dirs
from .common import echo_json, example, json_option


def _description(path: Path) -> str:
    try:
        data, _ = load_bounded(path.read_text(encoding="utf-8"))
    except Exception:
        return "(not valid YAML)"
    if not isinstance(data, dict):
        return "(not a protocol)"
    text = str(data.get("description") or "").strip()
    return text.splitlines()[0] if text else ""


@click.group(epilog=example("touchbench protocols list", "touchbench protocols validate my-protocol.yaml"))
def protocols() -> None:
    """Protocol files: validate them, list the shipped ones."""


@protocols.command("validate", epilog=example("touchbench protocols validate my-protocol.yaml --json"))
@click.argument("file")
@click.option("--schema-only", is_flag=True, help="Check the file alone; do not load the dataset or build the folds.")
@json_option
def validate(file: str, schema_only: bool, as_json: bool) -> None:
    """Validate FILE: schema, names, parameters, and (unless --schema-only)
    the dataset filters and the folds of the scheme. Nothing is computed."""
    from ..protocols.checks import require_extras
    from ..protocols.loading import load_protocol  # here: listing protocols reads no schema

    path = find_protocol(file)
    proto = load_protocol(path)
    require_extras(proto)  # every method must run here (`run --method` needs only the extras of those it runs)
    combos = proto.combinations()
    clfs = proto.classifier_entries()
    n_methods = len(proto.evaluated_methods())
    shape = f"{len(combos)} feature combination(s) x {len(clfs)} classifier(s)" if combos else ""
    extra = f"{n_methods - len(combos) * len(clfs)} method(s)" if proto.methods else ""
    out = {"file": str(path), "valid": True, "name": proto.name, "scheme": proto.scheme.name,
           "feature_combinations": len(combos), "classifiers": len(clfs), "methods": n_methods}
    if not as_json:
        click.echo(f"{path}: valid protocol {proto.name!r}: scheme {proto.scheme.name}, "
                   + " + ".join(x for x in (shape, extra) if x))
    if schema_only:
        if as_json:
            echo_json(out)
        return
    from ..engine.planning import plan_run

    evaluations = []
    for sub in proto.evaluation_protocols():
        plan = plan_run(sub)
        ds = plan.dataset
        evaluations.append({"evaluation": sub.evaluation, "dataset": sub.dataset.name, "scheme": sub.scheme.name,
                            "captures": len(ds), "subjects": int(ds.meta["subject"].nunique()),
                            "classes": int(ds.meta[sub.target].nunique()), "folds": plan.n_folds,
                            "tasks": len(plan.tasks), "notes": plan.notes,
                            "leakage": plan.leakages})
        if as_json:
            continue
        at = f"evaluation {sub.evaluation} ({sub.scheme.name}): " if sub.evaluation else ""
        click.echo(f"{at}dataset {sub.dataset.name}: {len(ds)} captures after filters, "
                   f"{ds.meta['subject'].nunique()} subjects, {ds.meta[sub.target].nunique()} {sub.target} classes")
        ran = plan.protocol  # without what this evaluation's sensor refused (one of several evaluations)
        shape = (f"{len(ran.combinations())} x {len(ran.classifier_entries())}" if not ran.methods
                 else f"{len(ran.evaluated_methods())} method(s)")
        click.echo(f"{plan.n_folds} fold(s) x {shape} = {len(plan.tasks)} task(s)")
        for reason in evaluations[-1]["leakage"]:
            click.echo(f"LEAKY: {reason}")
        for n in plan.notes:
            click.echo(f"note: {n}")
    if as_json:
        first = evaluations[0]
        echo_json({**out, **{k: v for k, v in first.items() if k not in ("evaluation", "dataset", "scheme")},
                   **({"evaluations": evaluations} if proto.evaluations else {})})


@protocols.command("list", epilog=example("touchbench protocols list --json"))
@json_option
def list_(as_json: bool) -> None:
    """Protocols found by name: your folders (--protocols, $TOUCHBENCH_PROTOCOLS,
    ./protocols) and the shipped ones (papers included), with their descriptions."""
    files = listed_protocols()
    if as_json:
        echo_json([{"name": f.stem, "path": str(f), "description": _description(f)} for f in files])
        return
    for f in files:
        try:
            rel = f.relative_to(Path.cwd())
        except ValueError:
            rel = f
        click.echo(f"{str(rel):48s} {_description(f)}")
    if not files:
        click.echo("no protocols found (looked in " + ", ".join(str(d) for d in protocol_dirs()) + ")")
