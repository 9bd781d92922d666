"""``touchbench run PROTOCOL``: evaluate every feature combination x classifier of a protocol."""

from __future__ import annotations

import math
import sys

import click

from ..engine.backends import backend_for_run, backend_options
from ..protocols.library import find_protocol
from ..streams.replay import LiveSpec
from . import exitcodes
from .common import echo_json, example, jobs_option, jobs_value, json_option, log

__all__ = ["format_summary", "jobs_value", "run", "run_summary"]


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


def _stream_tables(res) -> list[str]:
    """A stream evaluation's summary: per method and rule, frame accuracy beside the idle-only baseline,
    accuracy 1 s after onset and false activations per idle minute (the leaderboard has the rest)."""
    from ..reports.leaderboard import leaderboard
    from ..reports.stream_table import live_sources

    lines = []
    for lb in leaderboard(res.out):
        if lb.live is None:
            continue
        lines.append(f"{live_sources(lb.live)}, {int(lb.live['streams'].iloc[0])} test streams:")
        lines.append(f"{'method':24s} {'rule':30s} {'frame%':>6s} {'idle-only%':>10s} {'@1s%':>5s} {'FA/min':>6s}")
        for _, r in lb.live.iterrows():
            rule = str(r["rule"])[:20] + " (default)" if bool(r.get("default", False)) else str(r["rule"])[:30]
            lines.append(f"{str(r['method'])[:24]:24s} {rule:30s} {_pct(r['frame_accuracy']):>6s} "
                         f"{_pct(r['idle_baseline']):>10s} {_pct(r['accuracy_at_1s']):>5s} "
                         f"{r['false_activations_per_idle_minute']:6.1f}")
    return lines


def run_summary(res, plan) -> dict:
    """What ``run --json`` prints: the run, its task counts and each method's scores."""
    cols = [c for c in dict.fromkeys(("features", "classifier", "early_frames", "n_folds", "n_failed", "accuracy_mean",
                                      "accuracy_std", "balanced_accuracy_mean", "macro_f1_mean", "latency_ms_median",
                                      *(f"{m}_mean" for m in plan.protocol.metrics)))
            if c in res.summary]
    failed = res.scores[res.scores["status"] == "failed"] if len(res.scores) else res.scores
    return {
        "protocol": plan.protocol.name, "dataset": plan.protocol.dataset.name, "captures": len(plan.dataset),
        "scheme": plan.protocol.scheme.name, "out": str(res.out), "run_id": res.run_id,
        "tasks": {"total": res.n_tasks, "ran": res.n_ran, "skipped": res.n_skipped, "failed": res.n_failed},
        "stopped_early": bool(getattr(res, "stopped_early", False)), "seconds": res.seconds, "notes": res.notes,
        "methods": res.summary[cols].to_dict(orient="records"),
        "failures": [{"task_id": r["task_id"], "fold": r["fold"], "features": r["features"],
                      "classifier": r["classifier"], "error": str(r["error"]).strip().splitlines()[0]
                      if str(r["error"]).strip() else ""} for _, r in failed.iterrows()],
        "expected": res.expected,
    }


@click.command("run", epilog=example("touchbench run demo-haart --jobs 2",
                                     "touchbench run my-protocol.yaml --out results/mine --fail-fast --json"))
@click.argument("protocol")
@jobs_option
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Results directory [default: results/<protocol name>/].")
@click.option("--force", is_flag=True, help="Recompute every task, even finished ones.")
@click.option("--retry-failed", is_flag=True, help="Run the tasks that failed last time again.")
@click.option("--fail-fast", is_flag=True, help="Stop at the first task that fails (finished tasks are kept).")
@click.option("--progress/--no-progress", default=None, help="Progress bar [default: on a terminal only].")
@click.option("--wait", type=click.FloatRange(min=0), default=0, show_default=True, metavar="SECONDS",
              help="When another run holds the results directory, wait this long for it before giving up.")
@click.option("--evaluation", "evaluations", multiple=True, metavar="NAME",
              help="Run only this evaluation of a protocol with several (repeatable) [default: all].")
@click.option("--method", "methods", multiple=True, metavar="METHOD",
              help="Run only this method's tasks: FEATURES/METHOD as the results name it, e.g. msd+sd/gaus-rf, or "
                   "a method's label alone (every method with that label; repeatable) [default: all]; "
                   "the tables hold every finished task of the protocol.")
@click.option("--final", is_flag=True,
              help="The run you report: refused when this test set already had a final run with other methods.")
@click.option("--force-final", is_flag=True, help="With --final: run even so (recorded in the ledger).")
@click.option("--summary/--no-summary", default=True, hidden=True,
              help="Print each evaluation's summary of accuracies (`touchbench demo` prints the leaderboard instead).")
@json_option
@backend_options
def run(protocol: str, jobs: int, out: str | None, force: bool, retry_failed: bool, fail_fast: bool,
        progress: bool | None, wait: float, evaluations: tuple[str, ...], methods: tuple[str, ...], final: bool,
        force_final: bool, summary: bool, as_json: bool, backend: str, scheduler: str | None,
        address: str | None) -> None:
    """Evaluate PROTOCOL (a file, or the name of a shipped protocol or of one in your folders): every feature
    combination x classifier under its scheme (under each of its evaluations, each into its own
    folder). Finished tasks are skipped, so an interrupted run resumes where it stopped. Every run
    that scores a test set is recorded in the ledger of the results root (ledger.jsonl), which the
    leaderboard reads. Exits with status 1 when a task failed."""
    from ..core.suggest import did_you_mean
    from ..engine.planning import names_a_method, plan_method_list
    from ..methods import method_name
    from ..engine.runner import plan_protocol
    from ..protocols.errors import UnknownEvaluation
    from ..protocols.loading import load_protocol

    if force_final and not final:
        raise click.UsageError("--force-final goes with --final")
    if final and methods:
        raise click.UsageError("--final reports every method of the protocol: run it without --method")
    proto = load_protocol(find_protocol(protocol))
    try:
        proto.evaluations_named(evaluations)
    except UnknownEvaluation as e:
        raise click.BadParameter(str(e), param_hint="--evaluation") from None
    plans = plan_protocol(proto, out, evaluations=evaluations, methods=methods)  # all checked before any runs
    unknown = [m for m in methods if not any(names_a_method(plan, m) for plan, _ in plans)]
    if unknown:
        known = sorted({method_name(m) for plan, _ in plans for m in plan_method_list(plan)})
        raise click.BadParameter(f"{unknown[0]!r} is not a method of {proto.name}"
                                 f"{did_you_mean(unknown[0], known, cutoff=0.4)} (FEATURES/LABEL or a label alone: "
                                 f"{', '.join(known)})", param_hint="--method")
    failed = 0
    summaries = []
    for plan, out_dir in plans:
        present = [m for m in methods if names_a_method(plan, m)]
        if methods and not present:  # left out of this evaluation (its sensor refused them)
            continue
        res = _run_one(plan, out_dir, jobs, force, retry_failed, fail_fast, progress, wait, final, force_final,
                       as_json or not summary, backend, scheduler, address, present)
        summaries.append(run_summary(res, plan))
        failed += res.n_failed
        if res.stopped_early:
            break
    if as_json:
        echo_json(summaries[0] if not proto.evaluations else {"evaluations": summaries})
    if failed:
        sys.exit(exitcodes.TASKS_FAILED)


def _run_one(plan, out_dir, jobs, force, retry_failed, fail_fast, progress, wait, final, force_final, quiet,
             backend, scheduler, address, methods=()):
    """Run one evaluation's plan and report it (messages on stderr, the summary on stdout unless
    ``quiet``: --json, or --no-summary)."""
    from ..engine.runner import run_plan

    proto = plan.protocol
    what = f"{proto.name}" + (f" / {proto.evaluation}" if proto.evaluation else "")
    log.info(f"{what}: {proto.dataset.name} ({len(plan.dataset)} captures), "
             f"scheme {proto.scheme.name}: {len(plan.tasks)} tasks -> {out_dir}")
    for n in plan.notes:
        log.info(f"note: {n}")
    for reason in plan.leakages:
        log.warning(f"LEAKY evaluation ({reason}): its accuracy overstates accuracy on new people")
    adapted = list(dict.fromkeys(t.method.label for t in plan.tasks if t.method.adaptation))
    if adapted:
        who = f"method {adapted[0]} adapts" if len(adapted) == 1 else f"methods {', '.join(adapted)} adapt"
        log.info(f"note: {who} to each test subject's unlabelled captures: a figure of another kind, which "
                 "the leaderboard tables apart from the plain methods")
    try:
        with backend_for_run(backend, scheduler, address, plan.cache_root, jobs) as jobs:
            res = run_plan(plan, out_dir, jobs=jobs, force=force, retry_failed=retry_failed, progress=progress,
                           wait=wait, fail_fast=fail_fast, final=final, force_final=force_final,
                           methods=list(methods) or None)
    except KeyboardInterrupt:
        click.echo("\ninterrupted: finished tasks are saved; run the same command again to resume", err=True)
        sys.exit(exitcodes.INTERRUPTED)
    for n in res.notes:
        if n not in plan.notes:
            log.info(f"note: {n}")
    if res.noop:
        log.info(f"nothing to do: all {res.n_tasks} tasks finished (use --force to recompute)")
    else:
        log.info(f"ran {res.n_ran} task(s), skipped {res.n_skipped} finished, {res.n_failed} failed, "
                 f"in {res.seconds:.1f} s")
    live = _stream_tables(res) if any(t.fold.extra(LiveSpec) is not None for t in plan.tasks) else []
    if not quiet:
        click.echo("\n".join(live) if live else format_summary(res.summary, res.expected))
    if res.stopped_early:
        log.warning("stopped at the first failed task (--fail-fast); run again without it to finish the others")
    if res.n_failed:
        failed = res.scores[res.scores["status"] == "failed"]
        first = str(failed.iloc[0]["error"]).splitlines()[0]
        log.warning(f"{res.n_failed} task(s) failed, e.g. {failed.iloc[0]['fold']} / {failed.iloc[0]['classifier']}: "
                    f"{first}")
    log.info(f"reports: {res.out}/scores.parquet, predictions.parquet, confusion.parquet, manifest.json")
    return res
