"""The comparisons of REPORT.md other than the accuracy table: a paper's standard deviation, its
confusion matrix (per-class recall) and the best value of a sweep against ours, and the leakage
audit of a protocol with the variants that reach the paper."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core.paths import REPO_ROOT
from ..protocols.expected import ExpectedBest, ExpectedConfusion, ExpectedDeviation
from ..reports.audit import audit_markdown
from ..reports.stats import NO_VARIANCE, ZERO_DIFFERENCE, corrected_resampled_t, holm
from ..results.store import PREDICTED, TRUE, read_results_table

__all__ = ["audit_dir", "audit_figures", "audit_section", "fmt", "ok_tasks", "other_sections", "read_run", "rel", "seed_spread"]


def fmt(v: float | None, d: int = 1) -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.{d}f}"


def seed_spread(seeds: list[float]) -> str:
    """A row's seeds after its number: `` (5 seeds: 61.2 to 65.6, range 4.4)``; ``""`` for one seed."""
    if len(seeds) < 2:
        return ""
    lo, hi = min(seeds), max(seeds)
    return f" ({len(seeds)} seeds: {lo:.2f} to {hi:.2f}, range {hi - lo:.2f})"


def rel(p: Path) -> str:
    try:
        return str(Path(p).resolve().relative_to(REPO_ROOT))
    except ValueError:
        return str(p)


def read_run(out: Path) -> tuple[pd.DataFrame | None, pd.DataFrame | None, dict[str, Any]]:
    if not (out / "scores.parquet").is_file():
        return None, None, {}
    scores = read_results_table(out / "scores.parquet")
    preds = read_results_table(out / "predictions.parquet") if (out / "predictions.parquet").is_file() else None
    man = json.loads((out / "manifest.json").read_text()) if (out / "manifest.json").is_file() else {}
    return scores, preds, man


def ok_tasks(scores: pd.DataFrame, classifier: str | None = None) -> pd.DataFrame:
    ok = scores[scores["status"] == "ok"]
    return ok if classifier is None else ok[ok["classifier"] == classifier]


def _deviation_section(check: ExpectedDeviation, scores: pd.DataFrame, flags: list[str], name: str) -> list[str]:
    """A paper's standard deviation over the folds against ours (sample sd of our folds' accuracy)."""
    sel = ok_tasks(scores, check.classifier)
    sd = 100 * float(np.std(sel["accuracy"], ddof=1)) if len(sel) > 1 else math.nan
    d = sd - check.value
    within = math.isfinite(sd) and abs(d) <= check.tolerance
    if not within:
        flags.append(f"{check.source} (`{name}`): ours {fmt(sd)} points, paper {check.value:g} "
                     f"(tolerance {check.tolerance:g})")
    return [f"**{check.source}:** paper {check.value:g} points, ours {fmt(sd)} points "
            f"(sample sd over {len(sel)} folds), difference {d:+.1f}, tolerance {check.tolerance:g}: "
            f"{'within' if within else '**outside**'}."]


def _confusion_matrices(check: ExpectedConfusion, scores: pd.DataFrame,
                        preds: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The paper's matrix and ours (pooled over the folds of ``check.classifier``'s tasks, or of the
    configuration of it with the best mean accuracy where a grid named several), rows the true class."""
    paper = np.asarray(check.matrix, dtype=float)
    if check.rows == "predicted":
        paper = paper.T  # rows = true class, as ours
    ok = ok_tasks(scores)
    mine = ok[ok["classifier"] == check.classifier]
    if mine.empty:
        named = ok[ok["classifier"].astype(str).str.startswith(check.classifier)]
        if len(named):
            best = named.groupby("classifier")["accuracy"].mean().idxmax()
            mine = named[named["classifier"] == best]
    p = preds[preds["task_id"].isin(mine["task_id"])]
    ours = pd.crosstab(p[TRUE].astype(str), p[PREDICTED].astype(str)).reindex(
        index=check.classes, columns=check.classes, fill_value=0).to_numpy(dtype=float)
    return paper, ours


def _recalls(paper: np.ndarray, ours: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-class recall (%) of the paper's matrix and ours (rows the true class)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return 100 * np.diag(paper) / paper.sum(axis=1), 100 * np.diag(ours) / ours.sum(axis=1)


def _confusion_outside(check: ExpectedConfusion, scores: pd.DataFrame, preds: pd.DataFrame) -> list[str]:
    """The classes whose recall differs from the paper's by more than the tolerance, as ``class (+d)``."""
    r_paper, r_ours = _recalls(*_confusion_matrices(check, scores, preds))
    return [f"{c} ({d:+.1f})" for c, d in zip(check.classes, r_ours - r_paper) if not abs(d) <= check.tolerance]


def _confusion_section(check: ExpectedConfusion, scores: pd.DataFrame, preds: pd.DataFrame | None,
                       flags: list[str], name: str) -> list[str]:
    """A paper's confusion matrix against ours (pooled over the folds), compared by per-class recall."""
    classes = check.classes
    printed = "rows: true class, columns: predicted"
    if check.rows == "predicted":
        printed += " (the paper prints the transpose)"
    lines = [f"**{check.source}** vs ours ({check.classifier}), pooled over the folds; {printed}. Per-class recall "
             f"tolerance {check.tolerance:g} points."]
    if preds is None or preds.empty:
        return lines + ["", "_no predictions: not compared_"]
    paper, ours = _confusion_matrices(check, scores, preds)
    r_paper, r_ours = _recalls(paper, ours)
    lines += ["", "| true \\ predicted | " + " | ".join(classes) + " | recall paper % | recall ours % | difference |",
              "|---|" + "---|" * (len(classes) + 3)]
    outside = _confusion_outside(check, scores, preds)
    for i, c in enumerate(classes):
        cells = " | ".join(f"{int(paper[i, j])} / {int(ours[i, j])}" for j in range(len(classes)))
        d = r_ours[i] - r_paper[i]
        mark = "" if abs(d) <= check.tolerance else " **outside**"
        lines.append(f"| {c} | {cells} | {fmt(r_paper[i])} | {fmt(r_ours[i])} | {d:+.1f}{mark} |")
    acc_p = 100 * np.trace(paper) / paper.sum()
    acc_o = 100 * np.trace(ours) / ours.sum() if ours.sum() else math.nan
    lines += ["", f"Cells are paper / ours. Accuracy of the matrix: paper {acc_p:.2f} % ({int(paper.sum())} captures), "
                  f"ours {fmt(acc_o, 2)} % ({int(ours.sum())} captures)."]
    if outside:
        flags.append(f"{check.source} (`{name}`): per-class recall differs by more than {check.tolerance:g} "
                     f"points for {', '.join(outside)}")
        lines += ["", f"**Outside tolerance:** {', '.join(outside)}."]
    return lines


def _best_section(check: ExpectedBest, paper_best: str, scores: pd.DataFrame, flags: list[str],
                  name: str) -> list[str]:
    """The best configuration of a sweep (``paper_best``: its entry's label) against ours (best mean accuracy)."""
    ok = ok_tasks(scores)
    if ok.empty:
        return [f"**{check.source}:** no results."]
    m = ok.groupby("classifier")["accuracy"].agg(["mean", "std", "count"])
    order = sorted(m.index, key=lambda s: float(s.split("=")[-1].rstrip(")")) if "=" in s else s)
    best = m["mean"].idxmax()
    lines = [f"**{check.source}.** Ours, mean accuracy over the held-out subjects (%):", "",
             "| configuration | mean | sd | folds |", "|---|---|---|---|"]
    for k in order:
        star = " (best)" if k == best else ""
        lines.append(f"| {k}{star} | {100 * m.loc[k, 'mean']:.1f} | {fmt(100 * m.loc[k, 'std'])} | {int(m.loc[k, 'count'])} |")
    same = best == paper_best
    ours = f"Paper: best {paper_best}; ours: best {best} ({100 * m.loc[best, 'mean']:.1f} %)"
    if paper_best in m.index and not same:
        ours += f", {paper_best} {100 * m.loc[paper_best, 'mean']:.1f} %"
    lines += ["", ours + ("." if same else ": **differs**."), "", *_best_distinguishable(ok, best, paper_best, order)]
    if not same:
        flags.append(f"{check.source} (`{name}`): our best configuration is {best}, not {paper_best}")
    return lines


def _best_distinguishable(ok: pd.DataFrame, best: str, paper_best: str, order: list[str],
                          alpha: float = 0.05) -> list[str]:
    """Whether the best configuration is distinguishable from each other one on the folds they share,
    as the leaderboard tests fold-paired results: the corrected resampled t-test of the fold
    differences (Nadeau & Bengio), Holm-adjusted over the comparisons with the best. Where the test
    is undefined the line says why: identical scores on every fold (indistinguishable), the same
    difference on every fold (no variance), fewer than two shared folds."""
    acc = ok.pivot_table(index="fold", columns="classifier", values="accuracy", aggfunc="mean")
    ratio = ok.assign(r=ok["n_test"] / ok["n_train"]).groupby("fold")["r"].mean()
    others = [k for k in order if k != best]
    tests, identical = [], []
    for k in others:
        both = acc[[best, k]].dropna()
        d = both[best] - both[k]
        identical.append(len(d) > 0 and bool((d.abs() <= ZERO_DIFFERENCE).all()))
        tests.append(corrected_resampled_t(d, float(ratio.loc[both.index].mean())))
    if not tests:
        return []
    adjusted = holm([t.pvalue for t in tests])
    apart = [k for k, p in zip(others, adjusted) if p < alpha]
    lines = [f"Is the best distinguishable (corrected resampled t-test over the folds, Holm-adjusted over the "
             f"{len(others)} comparisons with the best, alpha {alpha:g})? Distinguishable from "
             + (", ".join(apart) if apart else "none of the others") + "."]
    same = [k for k, i in zip(others, identical) if i]
    if same:
        lines[0] += " Indistinguishable, identical scores on every fold: " + ", ".join(same) + "."
    if paper_best in others:
        i = others.index(paper_best)
        lines += ["", f"**Best {best} (ours) vs the paper's {paper_best}: "
                      f"{_verdict(tests[i], adjusted[i], identical[i], alpha)}.**"]
    return lines


def _verdict(test, adjusted: float, identical: bool, alpha: float) -> str:
    """One comparison of two configurations over their shared folds, in words, defined for every input."""
    diff = f"difference {100 * test.mean_difference:+.1f} points"
    if identical:
        return f"indistinguishable: identical scores on {test.n} folds"
    if test.note == NO_VARIANCE:
        return f"no variance: every one of the {test.n} folds differs by the same amount ({diff}); the t-test is undefined"
    if not math.isfinite(test.pvalue):
        return f"not tested: {test.n} shared fold{'' if test.n == 1 else 's'}, the t-test needs two"
    verdict = "distinguishable" if adjusted < alpha else "not distinguishable"
    return f"{verdict} on {test.n} folds (p = {test.pvalue:.3f}, Holm-adjusted {adjusted:.3f}; {diff})"


def other_sections(proto, scores: pd.DataFrame, preds: pd.DataFrame | None, flags: list[str]) -> list[list[str]]:
    """The sections of the expected numbers that are not one accuracy, in the order
    standard deviations, confusions, best parameter values."""
    if proto.expected is None:
        return []
    e, name = proto.expected, proto.name
    return ([_deviation_section(c, scores, flags, name) for c in e.standard_deviations]
            + [_confusion_section(c, scores, preds, flags, name) for c in e.confusions]
            + [_best_section(c, proto.best_label(c), scores, flags, name) for c in e.best_parameters])

def audit_dir(out: Path) -> Path:
    """Where ``papers reproduce --audit`` audits the protocol whose results are in ``out``."""
    return out.parent / f"{out.name}-audit"


def audit_figures(proto, out: Path) -> dict[str, dict[str, float]]:
    """This report's leakage audit of ``proto`` (its ``audit.json`` beside ``out``), method -> variant ->
    accuracy %; {} when it did not run."""
    path = audit_dir(out) / "audit.json"
    if proto.audit is None or not path.is_file():
        return {}
    figures: dict[str, dict[str, float]] = {}
    for row in json.loads(path.read_text())["rows"]:
        if row.get("accuracy") is not None and math.isfinite(row["accuracy"]):
            figures.setdefault(row["method"], {})[row["variant"]] = 100.0 * float(row["accuracy"])
    return figures


def _cited_audit(proto, out: Path) -> list[str]:
    """The figures the protocol's causes cite from its audit (a candidate's ``row`` and ``variant``)
    that this report's audit rounds otherwise, one line each; [] when all agree."""
    figures, lines = audit_figures(proto, out), []
    for e in (proto.expected.results if proto.expected is not None and figures else []):
        method = proto.method_name_of(e)
        for r in (e.cause.ruled_out if e.cause is not None else []):
            fresh = r.this_run(figures.get(method, {}))
            if fresh is not None:
                lines.append(f"- {method}, {r.variant}: the protocol cites {r.row:g} %, this audit gave {fresh:.1f} %")
    if not lines:
        return []
    return ["", "**The protocol cites figures of this audit that this run did not give** (the same code, data and "
                "seed can train a network to other weights on another machine; the causes' kinds follow the "
                "cited figures):", "", *lines]


def audit_section(proto, out: Path) -> list[str]:
    """The leakage audit of a protocol, as measured (its ``audit.json``), with the variants that
    come within the paper's tolerance; or how to run it."""
    if proto.audit is None:
        return []
    path = audit_dir(out) / "audit.json"
    if not path.is_file():
        return ["", f"_Leakage audit not run: `touchbench papers reproduce --audit` (or `touchbench audit "
                    f"{proto.name} --out {rel(audit_dir(out))}`)._", ""]
    doc = json.loads(path.read_text())
    table = pd.DataFrame(doc["rows"])
    lines = ["", f"Leakage audit (`{rel(audit_dir(out))}`): the same method under the honest scheme and each "
                 "leaky variant, measured:", ""]
    lines += audit_markdown(table, doc.get("published"), title="", notes=doc.get("notes")).splitlines()[2:]
    lines += [_audit_folds(audit_dir(out), list(dict.fromkeys(table["variant"]))), ""]
    for method, pub in (doc.get("published") or {}).items():
        g = table[table["method"] == method]
        hits = [v for v, a in zip(g["variant"], g["accuracy"]) if abs(100 * a - pub["value"]) <= pub["tolerance"]]
        honest = g.loc[g["variant"] == "honest", "accuracy"]
        lines.append(f"**{method}: the paper's {pub['value']:g} % (tolerance {pub['tolerance']:g}) is reproduced by "
                     + (", ".join(f"`{v}`" for v in hits) if hits else "no variant")
                     + (f"; the honest figure is {100 * float(honest.iloc[0]):.1f} %." if len(honest) else ".") + "**")
    lines += _cited_audit(proto, out)
    for check in (proto.expected.confusions if proto.expected is not None else []):
        lines += ["", *_audit_confusion(check, audit_dir(out), list(dict.fromkeys(table["variant"])))]
    return lines + [""]


def _audit_folds(folder: Path, variants: list[str]) -> str:
    """How many folds each audit variant ran (its ``scores.parquet`` in ``folder/<variant>/``)."""
    parts = []
    for v in variants:
        scores = read_run(folder / v)[0]
        parts.append(f"{v} {'not run' if scores is None else int(scores['fold'].nunique())}")
    return "Folds run: " + ", ".join(parts) + "."


def _audit_confusion(check: ExpectedConfusion, folder: Path, variants: list[str]) -> list[str]:
    """Each audit variant's confusion (its pooled predictions, ``folder/<variant>/``) against a paper's
    matrix by per-class recall, and the variants whose every class comes within the tolerance."""
    lines = [f"{check.source}, per-class recall within {check.tolerance:g} points, by variant:", ""]
    matched = []
    for v in variants:
        scores, preds, _ = read_run(folder / v)
        if scores is None or preds is None or preds.empty:
            lines.append(f"- `{v}`: no predictions")
            continue
        outside = _confusion_outside(check, scores, preds)
        if not outside:
            matched.append(v)
        lines.append(f"- `{v}`: " + (f"{len(outside)} of {len(check.classes)} classes outside: {', '.join(outside)}"
                                     if outside else f"all {len(check.classes)} classes within"))
    lines += ["", f"**{check.source} is matched by " + (", ".join(f"`{v}`" for v in matched) if matched
                                                         else "no variant") + ".**"]
    return lines


