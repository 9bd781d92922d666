"""Report commands: ``leaderboard``, ``compare``, ``plot``, ``report`` and ``papers reproduce``.

RESULTS arguments are results directories written by ``touchbench run``, or
folders holding several (searched recursively). Results of several runs and
machines combine: a method is its parameters' hash (the ``method`` column),
so the same method run twice is one row.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click

from ..core.errors import TouchbenchError
from . import exitcodes
from .common import LazyChoice, echo_json, example, jobs_option, json_option, log

_FORMATS = ("terminal", "md", "csv", "json")


def _load(results: tuple[str, ...], predictions: bool = True):
    from ..reports.results import load_results

    return load_results(results, predictions=predictions)


def _filter(lbs, dataset: str | None, scheme: str | None):

    out = [lb for lb in lbs if (dataset is None or dataset in (lb.dataset, lb.dataset_hash[: len(dataset)]))
           and (scheme is None or lb.scheme == scheme or lb.scheme.split("(")[0] == scheme)]
    if not out:
        avail = "; ".join(f"{lb.dataset} / {lb.scheme}" for lb in lbs)
        raise TouchbenchError(f"no table for dataset={dataset!r} scheme={scheme!r} (tables: {avail})")
    return out


_table_options = [
    click.option("--dataset", default=None, help="Only tables of this dataset (name or hash prefix)."),
    click.option("--scheme", default=None, help="Only tables of this scheme (name, or name(params) as shown)."),
    click.option("--alpha", default=0.05, show_default=True, help="Significance level after Holm's correction."),
    click.option("--pool-machines", is_flag=True,
                 help="Pool timings of different machines into one ranking and Pareto front."),
    click.option("--machine", default=None, help="Reference machine id for timings (default: the one that ran most methods)."),
]


def _with_table_options(f):
    for opt in reversed(_table_options):
        f = opt(f)
    return f


_fraction_option = click.option(
    "--fraction", default=0.95, show_default=True, type=click.FloatRange(0, 1, min_open=True),
    help="On a data curve (learning or calibration curve): the share of its full accuracy a method is asked to "
         "reach; the tables show the smallest size that reaches it.")


def _boards(results, dataset, scheme, alpha, pool_machines, machine, predictions=True, reference=None, fraction=0.95):
    from ..reports.leaderboard import build_leaderboards

    rs = _load(results, predictions=predictions)
    if reference:
        from ..reports.reference import add_reference

        rs, lines = add_reference(rs, reference)
        for line in lines:
            click.echo(line, err=True)
    lbs = build_leaderboards(rs, alpha=alpha, pool_machines=pool_machines, machine=machine, fraction=fraction)
    return rs, _filter(lbs, dataset, scheme)


@click.command("leaderboard", epilog=example("touchbench leaderboard results/demo-haart",
                                             "touchbench leaderboard results/a results/b --json"))
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=True))
@json_option
@click.option("--format", "-f", "formats", multiple=True, type=click.Choice(_FORMATS), default=("terminal",),
              show_default=True, help="Output format (repeatable). md/csv/json go to stdout, or to files with --out.")
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Write leaderboard.md/.csv/.json into this folder (the --format choices, all three by default).")
@click.option("--reference", default=None, metavar="NAME",
              help="Place the reference results NAME beside these (`touchbench reference list`); refused unless "
                   "a test set has the same content.")
@_fraction_option
@_with_table_options
def leaderboard(results, as_json, formats, out, reference, fraction, dataset, scheme, alpha, pool_machines,
                machine) -> None:
    """One table per dataset and scheme: rank, features, classifier, accuracy
    (mean over folds, sd, 95 % interval), macro F1, latency per capture, fit
    time, feature time, the paired test against the best method (exact
    permutation or Wilcoxon, Holm-corrected) and the accuracy/latency Pareto
    front (★)."""
    from ..reports.rendering import print_terminal, to_csv, to_json, to_markdown, write_outputs

    _, lbs = _boards(results, dataset, scheme, alpha, pool_machines, machine, reference=reference, fraction=fraction)
    if as_json:  # the same document as --format json, alone on stdout
        formats = tuple(f for f in formats if f != "terminal") or ("json",)
        if set(formats) != {"json"}:
            raise click.UsageError("--json prints JSON alone: leave out the other --format values")
    if out:
        fmts = [f for f in formats if f != "terminal"] or ["md", "csv", "json"]
        for p in write_outputs(lbs, Path(out), fmts):
            click.echo(f"wrote {p}", err=True)
        if "terminal" not in formats:
            return
    for f in formats:
        if f == "terminal":
            print_terminal(lbs)
        else:
            click.echo({"md": to_markdown, "csv": to_csv, "json": to_json}[f](lbs))


@click.command("compare", epilog=example("touchbench compare results/demo-haart --a msd/gaus-rf --b sd/gaus-rf"))
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--a", "a", required=True, help="Method A: its id (or a prefix), or features/classifier if unambiguous.")
@click.option("--b", "b", required=True, help="Method B, as --a.")
@json_option
@_with_table_options
def compare(results, a, b, as_json, dataset, scheme, alpha, pool_machines, machine) -> None:
    """The paired test of method A against B (the corrected resampled t-test
    over folds, McNemar's exact test on the test captures when they share
    one fold) with the interval that inverts it, the per-fold differences and
    the per-class recall and F1 differences, in every table holding both
    methods; across several such tables, a meta-analysis (effect size per
    table, Stouffer's combined p). Its p-values are this comparison's alone;
    the leaderboard's are Holm-adjusted over each table's comparisons with
    its best, and the output says which is which."""
    from ..reports.compare import compare_methods

    rs, lbs = _boards(results, dataset, scheme, alpha, pool_machines, machine)
    done, errors = [], []
    for lb in lbs:
        try:
            done.append(compare_methods(rs, lb, a, b))
        except TouchbenchError as e:
            errors.append(f"{lb.title}: {e}")
    if not done:
        raise TouchbenchError("no table holds both methods:\n" + "\n".join(errors))
    meta = _meta(done)
    if as_json:
        _compare_json(done, meta)
        return
    for c in done:
        _echo_comparison(c)
    if meta is not None:
        _echo_meta(done, meta)


def _meta(done):
    """The meta-analysis of the comparison across the tables holding both methods (None: fewer than two tested)."""
    from ..reports.stats import meta_analysis

    tested = [c.test for c in done if c.test.test != "none"]
    return meta_analysis(tested) if len(tested) >= 2 else None


def _compare_json(done, meta) -> None:
    """``compare --json``: each table's comparison (its p uncorrected: ``p_correction``; the
    leaderboard's p of the pair and its correction: ``leaderboard``), and the meta-analysis across
    them (null for one; NaN and infinity as null)."""
    from ..reports.compare import leaderboard_p

    payload = [{
        "table": {"dataset": c.leaderboard.dataset, "scheme": c.leaderboard.scheme},
        "a": {k: c.a[k] for k in ("method_id", "features", "classifier", "accuracy", "macro_f1")},
        "b": {k: c.b[k] for k in ("method_id", "features", "classifier", "accuracy", "macro_f1")},
        "test": c.test.as_dict(),
        "p_correction": "none",
        "leaderboard": leaderboard_p(c),
        "pairs": c.pairs.to_dict(orient="records"),
        "per_class": c.per_class.to_dict(orient="records"),
    } for c in done]
    echo_json({"comparisons": payload, "meta_analysis": None if meta is None else meta.as_dict()})


def _echo_comparison(c) -> None:
    """One table's comparison: the methods, the test, the paired units (or McNemar's counts) and the classes."""
    from ..reports.compare import leaderboard_p, test_lines
    from ..reports.labels import method_label

    t = c.test
    click.echo(f"== {c.leaderboard.title}")
    click.echo(f"A = {c.a['method_id']}  {method_label(c.a)}: accuracy {100 * c.a['accuracy']:.2f} %")
    click.echo(f"B = {c.b['method_id']}  {method_label(c.b)}: accuracy {100 * c.b['accuracy']:.2f} %")
    for line in test_lines(t) + ([leaderboard_p(c)["text"]] if t.test != "none" else []):
        click.echo(line)
    click.echo("")
    if t.paired_by == "capture":
        a, b = c.pairs["a"] >= 0.5, c.pairs["b"] >= 0.5
        click.echo(f"test captures: {int((a & b).sum())} both right, {int((a & ~b).sum())} only A, "
                   f"{int((~a & b).sum())} only B, {int((~a & ~b).sum())} both wrong")
    else:
        click.echo(f"{t.paired_by or 'unit':28s} {'A %':>7s} {'B %':>7s} {'A-B':>7s}")
        for r in c.pairs.itertuples():
            click.echo(f"{str(r.unit)[:28]:28s} {100 * r.a:7.1f} {100 * r.b:7.1f} {100 * r.diff:+7.1f}")
    if len(c.per_class):
        click.echo("")
        click.echo(f"{'class':16s} {'n':>5s} {'recall A':>9s} {'recall B':>9s} {'A-B':>7s} {'F1 A':>6s} {'F1 B':>6s} {'A-B':>7s}")
        for r in c.per_class.itertuples():
            click.echo(f"{str(r._1)[:16]:16s} {r.support:5d} {100 * r.recall_a:9.1f} {100 * r.recall_b:9.1f} "
                       f"{100 * r.recall_diff:+7.1f} {100 * r.f1_a:6.1f} {100 * r.f1_b:6.1f} {100 * r.f1_diff:+7.1f}")
    click.echo("")


def _echo_meta(done, meta) -> None:
    """The meta-analysis across the tables: effect size per table, Stouffer's combined z and p; a
    table without a p-value named as left out, with the direction of its differences."""
    click.echo(f"== across {len(meta.n)} evaluations (meta-analysis: Stouffer's method, weights sqrt(n))")
    tested = [c for c in done if c.test.test != "none"]
    for c, es, n, p, used in zip(tested, meta.effect_sizes, meta.n, meta.p_greater, meta.combined):
        if used:
            dz = f"{es:+6.2f}" if math.isfinite(es) else "     —"  # no d_z without spread
            click.echo(f"{c.leaderboard.title[:48]:48s} d_z {dz}  n={n:<4d} one-sided p (A better) {p:.4g}")
            continue
        d = c.test.mean_difference
        click.echo(f"{c.leaderboard.title[:48]:48s} left out ({c.test.note}: A-B {100 * d:+.2f} points in every fold, "
                   f"{'A' if d > 0 else 'B'} better; no p-value to combine)")
    if not any(meta.combined):
        click.echo("combined: nothing to combine (no table has a p-value)")
    else:
        click.echo(f"combined: z = {meta.z:+.2f} (positive: A better), two-sided p = {meta.pvalue:.4g} "
                   f"(Stouffer over {sum(meta.combined)} table(s); no multiple-comparison correction)")
    click.echo("")


def figure_kinds() -> list[str]:
    """The registered figure kinds in the order their figures come: ``plot --kind``'s choices."""
    from ..reports.figures.base import kinds_in_order

    return [e.name for e in kinds_in_order()]


def parse_reference(text: str) -> tuple[str, float]:
    """``"LABEL=PERCENT"`` -> (label, percent); a bad value is a ``click.BadParameter`` naming it."""
    label, sep, value = str(text).rpartition("=")
    try:
        pct = float(value)
    except ValueError:
        pct = float("nan")
    if not sep or not label.strip() or not (0.0 <= pct <= 100.0):
        raise click.BadParameter(f"{text!r}: expected LABEL=PERCENT with a percentage from 0 to 100, e.g. 'Gaus 2015=66.5'",
                                 param_hint="'--reference'")
    return label.strip(), pct


@click.command("plot", epilog=example("touchbench plot results/demo-haart --out figures --kind pareto --size column"))
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False), help="Folder for the figure files.")
@click.option("--kind", "kinds", multiple=True, type=LazyChoice(figure_kinds),
              help="Plots to draw (repeatable) [default: all that apply]. cd: critical difference diagram across the "
                   "tables (each table one data set; drawn when they are enough to separate methods at --alpha; "
                   "needs aeon: touchbench[peers]).")
@click.option("--size", type=click.Choice(["text", "column"]), default="text", show_default=True,
              help="Print width: text (7 in) or column (3.5 in); fonts are at least 7 pt at that size.")
@click.option("--format", "formats", multiple=True, type=click.Choice(["pdf", "svg", "png"]),
              help="File formats (repeatable) [default: pdf, svg and png at 300 dpi].")
@click.option("--method", "methods", multiple=True,
              help="Method(s) for confusion matrices (id or unambiguous label) [default: each table's best].")
@click.option("--reference", "references", multiple=True, callback=lambda ctx, param, v: [parse_reference(r) for r in v],
              metavar="LABEL=PERCENT",
              help="A reference accuracy drawn as a dashed line on the Pareto plots, e.g. 'Gaus 2015=66.5' (repeatable).")
@click.option("--name", default=None, metavar="STEM",
              help="File names STEM-<kind>.<format> instead of <results folder>-<kind> (one table only, and "
                   "STEM-adapted-<kind> for its methods adapted to each test session).")
@_fraction_option
@_with_table_options
def plot(results, out, kinds, size, formats, methods, references, name, fraction, dataset, scheme, alpha,
         pool_machines, machine) -> None:
    """Plot accuracy against latency / fit time / feature time (Pareto front),
    accuracy against frames and seconds seen (early scheme), confusion
    matrices (counts and row-normalised) and per-subject accuracy."""
    from ..reports.compare import resolve_method
    from ..reports.figures import FORMATS, plot_table
    from ..reports.figures.cd import plot_cd_across

    rs, lbs = _boards(results, dataset, scheme, alpha, pool_machines, machine, fraction=fraction)
    n_adapted = sum(1 for lb in lbs if lb.adaptation)
    if name is not None and max(len(lbs) - n_adapted, n_adapted) > 1:  # one table, and its adapted methods' one
        raise TouchbenchError(f"--name {name}: the results hold {len(lbs)} tables; choose one with --dataset/--scheme")
    taken: set[str] = set()
    formats = tuple(formats) or FORMATS
    for lb in lbs:
        ids = [resolve_method(lb.rows, m) for m in methods] if methods else None
        stem = None if name is None else f"{name}-adapted" if lb.adaptation else name  # its adapted table beside it
        made = plot_table(rs, lb, Path(out), tuple(kinds) or None, ids, references, name=stem, size=size,
                          formats=formats, taken=taken)
        for kind, paths in made.items():
            click.echo(f"{lb.title}: {kind}: " + ", ".join(str(p) for p in paths))
    if (not kinds or "cd" in kinds) and len(lbs) > 1:
        try:
            paths = plot_cd_across(lbs, Path(out) / "across-tables-cd", size, formats)
            click.echo("across tables: cd: " + ", ".join(str(p) for p in paths))
        except ValueError as e:
            click.echo(f"across tables: no critical difference diagram: {e}", err=True)


@click.command("report", epilog=example("touchbench report results/demo-haart --out report"))
@click.argument("results", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False), help="Folder for report.html and its files.")
@click.option("--title", default="touchbench report", show_default=True)
@_fraction_option
@_with_table_options
def report(results, out, title, fraction, dataset, scheme, alpha, pool_machines, machine) -> None:
    """Write one self-contained HTML page (images embedded) with every
    leaderboard and plot, plus the plots as PNG/SVG and the leaderboard as
    Markdown, CSV and JSON beside it."""
    from ..reports.html import write_report

    rs, lbs = _boards(results, dataset, scheme, alpha, pool_machines, machine, fraction=fraction)
    page = write_report(rs, lbs, Path(out), title=title)
    click.echo(f"wrote {page}")


@click.group("papers", epilog=example("touchbench papers list", "touchbench papers reproduce --only gaus"))
def papers() -> None:
    """Reproduce the four papers (the shipped papers/ protocols)."""


@papers.command("list", epilog=example("touchbench papers list --profile full --json"))
@click.option("--profile", default="quick", show_default=True, help="Show what this profile changes.")
@json_option
def papers_list(profile: str, as_json: bool) -> None:
    """The paper protocols, what the profile changes in each, and the optional extras each needs
    (those not installed here marked so: only the protocols run need theirs)."""
    from ..papers.profiles import PROFILES, apply_profile, paper_protocols
    from ..protocols.checks import needed_extras
    from ..protocols.loading import load_protocol

    if profile not in PROFILES:
        raise TouchbenchError(f"unknown profile {profile!r} (known: {', '.join(PROFILES)})")
    rows = []
    for f in paper_protocols():
        proto, changes = apply_profile(load_protocol(f), PROFILES[profile])
        rows.append({"name": f.stem, "description": proto.description, "changes": changes,
                     "extras": needed_extras(proto)})
    if as_json:
        echo_json({"profile": profile, "description": PROFILES[profile].description, "protocols": rows})
        return
    click.echo(f"profile {profile}: {PROFILES[profile].description}")
    for row in rows:
        click.echo(f"{row['name']:38s} {row['description']}")
        for c in row["changes"]:
            click.echo(f"{'':40s}{c}")
        for extra, missing in row["extras"].items():
            click.echo(f"{'':40s}needs the optional {extra!r} extra"
                       + (f" (not installed here: {', '.join(missing)}; pip install 'touchbench[{extra}]')"
                          if missing else ""))


@papers.command("reproduce", epilog=example("touchbench papers reproduce --profile quick --jobs 2"))
@click.option("--profile", default="quick", show_default=True, type=click.Choice(["quick", "full"]),
              help="quick: fewer trees, epochs and folds (stated in the report; the data and scenes whole); full: the papers' settings.")
@click.option("--out", "-o", default="results/papers", show_default=True, type=click.Path(file_okay=False),
              help="Results go to OUT/<profile>/<protocol>/; the report to OUT/REPORT.md.")
@click.option("--only", multiple=True, help="Only protocols whose name contains this (repeatable); REPORT.md keeps the other protocols "
                   "whose results an earlier run left in OUT.")
@jobs_option
@click.option("--report", "report_path", default=None, type=click.Path(dir_okay=False),
              help="Where to write the report [default: OUT/REPORT.md]; docs/papers-report.md is the committed report "
                   "of the last full quick-profile run (with its date, commit and load).")
@click.option("--progress/--no-progress", default=None, help="Progress bars [default: on a terminal only].")
@click.option("--audit", is_flag=True, help="Also run the leakage audit of the protocols that declare one "
                                           "(OUT/<profile>/<protocol>-audit/); the report shows it.")
def papers_reproduce(profile, out, only, jobs, report_path, progress, audit) -> None:
    """Run every shipped paper protocol (touchbench/protocols/papers/) under PROFILE (resuming
    finished tasks) and write REPORT.md: for each table and figure, the
    paper's number, ours, the difference, real or synthetic data, and the
    protocol file."""
    from ..papers.profiles import paper_protocols
    from ..papers.reproduce import chosen_files, reproduce

    if only:
        try:
            chosen_files(paper_protocols(), list(only))
        except TouchbenchError as e:
            raise click.BadParameter(str(e).removeprefix("--only: "), param_hint="--only") from None
    failed: list[str] = []
    p = reproduce(profile, out, only=list(only) or None, jobs=jobs, progress=progress, report=report_path,
                  echo=log.info, failed=failed, audit=audit)
    click.echo(f"wrote {p}")
    if failed:
        log.warning(f"{len(failed)} protocol(s) with failed tasks: {', '.join(failed)}")
        sys.exit(exitcodes.TASKS_FAILED)
