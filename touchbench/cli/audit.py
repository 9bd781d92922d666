"""``touchbench audit``: how much each leaky evaluation inflates a protocol's methods."""

from __future__ import annotations

import math
from pathlib import Path

import click

from ..engine.backends import backend_for_run, backend_options
from ..protocols.library import find_protocol
from .common import echo_json, example, jobs_option, json_option, log


def _tune(values: tuple[str, ...], known: list[str]) -> dict[str, list]:
    """``--tune`` values as grids; a parameter that no entry of the protocol states is refused, naming those it does."""
    from ..core.yamlsafe import safe_load

    out = {}
    for v in values:
        name, sep, grid = v.partition("=")
        if not sep or not name or not grid:
            raise click.BadParameter(f"{v!r}: expected PARAM=V1,V2,... (e.g. L=10,20,30)", param_hint="--tune")
        if name not in known:
            valid = (f"the parameters it can tune: {', '.join(known)}" if known
                     else "its classifier and method entries state no parameter to tune")
            raise click.BadParameter(f"{name!r} is no parameter of the protocol's classifier or method entries "
                                     f"({valid})", param_hint="--tune")
        out[name] = [safe_load(x) for x in grid.split(",")]
    return out


def _window_seconds(ctx, param, value: float) -> float:
    if not math.isfinite(value) or value <= 0:
        raise click.BadParameter(f"{value!r}: a window length in seconds, a finite number above 0 (e.g. 2)")
    return value


@click.command("audit", epilog=example("touchbench audit cnn-table2-loso-haart --tune L=10,30,86 --jobs 2",
                                       "touchbench audit my-protocol.yaml --variant honest --variant capture-kfold"))
@click.argument("protocol")
@click.option("--evaluation", default=None, metavar="NAME", help="The evaluation to audit, of a protocol with several.")
@click.option("--variant", "variants", multiple=True,
              type=click.Choice(["honest", "capture-kfold", "window-kfold", "subject-id", "tuned-on-test",
                                 "stopped-on-test"]),
              help="Variants to run (repeatable) [default: every applicable one].")
@click.option("--k", default=10, show_default=True, type=click.IntRange(min=2), help="Folds of the k-fold variants.")
@click.option("--window-seconds", default=2.0, show_default=True, type=float, callback=_window_seconds,
              help="Window length of window-kfold for methods without sub-windows of their own.")
@click.option("--tune", multiple=True, metavar="PARAM=V1,V2,...",
              help="The grid tuned-on-test chooses from by test accuracy (e.g. L=10,20,30).")
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Results folder [default: results/audit/<protocol>].")
@jobs_option
@json_option
@backend_options
def audit(protocol: str, evaluation: str | None, variants: tuple[str, ...], k: int, window_seconds: float,
          tune: tuple[str, ...], out: str | None, jobs: int, as_json: bool, backend: str, scheduler: str | None,
          address: str | None) -> None:
    """Run PROTOCOL's methods under the honest scheme (subjects kept apart, nothing chosen on test data)
    and under each applicable leaky variant (k-fold over captures ignoring subjects, k-fold over windows
    cut from the captures, the subject's id as a feature, a parameter chosen by its test accuracy, a
    network's training epoch chosen by its test accuracy), and
    report the inflation of each: a table, audit.md, audit.html and a figure in the results folder. Every
    variant is a protocol of its own in its folder; finished tasks are reused.

    Cost: up to six runs of the protocol's methods, one per variant: honest (the protocol's own
    folds, or one per subject), capture-kfold, window-kfold and subject-id (--k folds each),
    tuned-on-test (the honest folds, once per --tune value) and stopped-on-test (the honest folds, the
    methods that train by epochs). The number of tasks of each variant is
    printed before any runs; the smallest real-data protocol (haart-loso-msd-rf, one method: 4
    variants x 10 folds = 40 tasks) took 11 minutes on two cores."""
    from ..engine.audit import VARIANTS, plan_audit, run_audit, tunable_params
    from ..engine.planning import default_cache_root
    from ..protocols.errors import UnknownEvaluation
    from ..protocols.loading import load_protocol
    from ..reports.audit import audit_rows, write_audit

    proto = load_protocol(find_protocol(protocol))
    try:
        sub = proto.evaluations_named([evaluation] if evaluation is not None else [])[0]
    except UnknownEvaluation as e:
        raise click.BadParameter(str(e), param_hint="--evaluation") from None
    grid = _tune(tune, tunable_params(sub))
    folder = Path(out) if out else Path("results") / "audit" / (proto.name + (f"-{sub.evaluation}" if sub.evaluation else ""))
    options = dict(k=k, window_seconds=window_seconds, tune=grid, variants=variants or VARIANTS)
    planned = plan_audit(sub, folder, **options)
    log.info(f"audit of {proto.name}: {planned.describe()} -> {folder}")
    with backend_for_run(backend, scheduler, address, default_cache_root(), jobs) as jobs:
        result = run_audit(sub, folder, jobs=jobs, planned=planned, **options)
    files = write_audit(result.table, folder, result.published, result.notes,
                        title=f"Leakage audit: {proto.name}" + (f" / {sub.evaluation}" if sub.evaluation else ""))
    if as_json:
        echo_json({"rows": result.table.to_dict(orient="records"), "published": result.published,
                   "notes": result.notes, "files": [str(f) for f in files]})
        return
    header, cells = audit_rows(result.table, result.published)
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=f"Leakage audit: {escape(proto.name)}")
    for h in header:
        t.add_column(escape(h))
    for row in cells:
        t.add_row(*(escape(x) for x in row))
    console = Console(width=200)
    console.print(t)
    for n in result.notes:
        log.info(f"note: {n}")
    log.info(f"audit: {', '.join(str(f) for f in files)}")
