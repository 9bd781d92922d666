"""``touchbench run PROTOCOL``: evaluate every feature combination x classifier of a protocol."""

from __future__ import annotations

import math
import sys

import click

from ..engine.backends import backend_for_run, backend_options
from ..protocols.library import find_protocol


def jobs_value(ctx: click.Context, param: click.Parameter, value: int) -> int:
    """``--jobs``: a positive number of parallel tasks, or -1 (one per CPU); anything else is a usage error."""
    if value == 0 or value < -1:
        raise click.BadParameter(f"{value} is not a number of parallel tasks: give 1 or more, or -1 for one per CPU "
                                 "(more than the CPUs available runs as many as there are)")
    return value


def _pct(x: float) -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:5.1f}"


def format_summary(summary, expected) -> str:
    lines = []
    if len(summary):
        has_early = "early_frames" in summary and summary["early_frames"].notna().any()
        head = f"{'features':32s} {'classifier':28s}" + (f" {'first':>6s}" if has_early else "")
        head += f" {'folds':>5s} {'acc%':>6s} {'sd':>5s} {'bal%':>6s} {'F1%':>6s} {'lat ms':>7s}"
        lines.append(head)
        for _, r in summary.iterrows():
            line = f"{str(r['features'])[:32]:32s} {str(r['classifier'])[:28]:28s}"
            if has_early:
                line += f" {'' if math.isnan(r['early_frames']) else int(r['early_frames']):>6}"
            fails = f"+{r['n_failed']}!" if r["n_failed"] else ""
            line += (f" {str(r['n_folds']) + fails:>5s} {_pct(r['accuracy_mean']):>6s} {_pct(r['accuracy_std']):>5s}"
                     f" {_pct(r['balanced_accuracy_mean']):>6s} {_pct(r['macro_f1_mean']):>6s}"
                     f" {r['latency_ms_median']:7.2f}")
            lines.append(line)
    if expected:
        lines.append("")
        lines.append("expected (paper)            observed  expected  diff   tol  ok")
        for e in expected:
            obs = "-" if e["observed"] is None else f"{e['observed']:.1f}"
            diff = "-" if e["difference"] is None else f"{e['difference']:+.1f}"
            ok = {True: "yes", False: "NO", None: "n/a"}[e["within"]]
            lines.append(f"{e['features'][:16]:16s} {e['classifier'][:10]:10s} {obs:>8s} {e['expected']:9.2f} "
                         f"{diff:>5s} {e['tolerance']:5.1f}  {ok}")
    return "\n".join(lines)


@click.command("run")
@click.argument("protocol")
@click.option("--jobs", "-j", default=1, show_default=True, callback=jobs_value,
              help="Tasks run in parallel (-1: one per CPU; at most the CPUs available, and the tasks).")
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Results directory [default: results/<protocol name>/].")
@click.option("--force", is_flag=True, help="Recompute every task, even finished ones.")
@click.option("--retry-failed", is_flag=True, help="Run the tasks that failed last time again.")
@click.option("--progress/--no-progress", default=None, help="Progress bar [default: on a terminal only].")
@click.option("--wait", type=click.FloatRange(min=0), default=0, show_default=True, metavar="SECONDS",
              help="When another run holds the results directory, wait this long for it before giving up.")
@backend_options
def run(protocol: str, jobs: int, out: str | None, force: bool, retry_failed: bool, progress: bool | None,
        wait: float, backend: str, scheduler: str | None, address: str | None) -> None:
    """Evaluate PROTOCOL (a file, or the name of a shipped protocol or of one in your folders): every feature
    combination x classifier under its scheme. Finished tasks are skipped, so
    an interrupted run resumes where it stopped."""
    from ..engine.runner import default_results_dir, plan_run, run_plan
    from ..protocols.schema import load_protocol

    proto = load_protocol(find_protocol(protocol))
    plan = plan_run(proto)
    out_dir = out or default_results_dir(proto)
    click.echo(f"{proto.name}: {proto.dataset.name} ({len(plan.dataset)} captures, {plan.dataset.content_hash[:12]}), "
               f"scheme {proto.scheme.name}: {len(plan.tasks)} tasks -> {out_dir}", err=True)
    for n in plan.notes:
        click.echo(f"note: {n}", err=True)
    try:
        with backend_for_run(backend, scheduler, address, plan.cache_root, jobs) as jobs:
            res = run_plan(plan, out_dir, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                           wait=wait)
    except KeyboardInterrupt:
        click.echo("\ninterrupted: finished tasks are saved; run the same command again to resume", err=True)
        sys.exit(130)
    for n in res.notes:
        if n not in plan.notes:
            click.echo(f"note: {n}", err=True)
    if res.noop:
        click.echo(f"nothing to do: all {res.n_tasks} tasks finished (use --force to recompute)", err=True)
    else:
        click.echo(f"ran {res.n_ran} task(s), skipped {res.n_skipped} finished, {res.n_failed} failed, "
                   f"in {res.seconds:.1f} s", err=True)
    click.echo(format_summary(res.summary, res.expected))
    if res.n_failed:
        failed = res.scores[res.scores["status"] == "failed"]
        first = str(failed.iloc[0]["error"]).splitlines()[0]
        click.echo(f"{res.n_failed} task(s) failed, e.g. {failed.iloc[0]['fold']} / {failed.iloc[0]['classifier']}: {first}",
                   err=True)
    click.echo(f"reports: {res.out}/scores.parquet, predictions.parquet, confusion.parquet, manifest.json", err=True)
