"""``REPORT.md`` of the paper reproduction: for every table and figure of the
four papers, the paper's number, ours, within tolerance or not, and the cause
of every difference with its kind (measured, ruled out or unexplained:
:mod:`.causes`); the counts lead, apart for the tables a scene value was
calibrated on, and the kinds of the causes of the numbers outside tolerance."""

from __future__ import annotations

import json
import math
import os
import platform
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..catalog import parse_dataset_ref
from ..core.errors import TouchbenchError
from ..core.paths import REPO_ROOT
from ..core.version import __version__
from ..protocols.expected import ExpectedBest, ExpectedConfusion, ExpectedDeviation
from ..protocols.loading import load_protocol
from ..reports.audit import audit_markdown
from ..reports.rendering import write_text
from ..reports.stats import NO_VARIANCE, ZERO_DIFFERENCE, corrected_resampled_t, holm
from ..results.manifest import git_revision
from ..results.store import PREDICTED, TRUE, read_results_table
from ..results.summary import check_expected
from ..scenes import load_scene
from .causes import KIND_SHORT, cause_cell, kind_counts
from .profiles import Profile, apply_profile

__all__ = ["PAPERS", "ProtocolRun", "audit_dir", "write_report"]

# The papers, in report order: (short name, citation, protocol name prefix).
PAPERS = [
    ("Gaus et al. 2015", "Gaus et al. 2015, Social touch gesture recognition using Random Forest and Boosting on "
                         "distinct feature sets (ICMI)", "gaus-"),
    ("Al-mashhadani et al. 2021", "Al-mashhadani et al. 2021, Human-animal affective robot touch classification "
                                  "using deep neural network", "cnn-"),
    ("Flagg 2012", "Flagg 2012, Sensing and recognizing affective touch in a furry zoomorphic object (MSc thesis, "
                   "UBC)", "flagg-"),
    ("Zhou et al. 2017", "Zhou et al. 2017, Textile pressure mapping sensor for emotional touch detection in HRI "
                         "(Sensors)", "zhou-"),
]


@dataclass
class ProtocolRun:
    path: Path
    name: str
    out: Path
    changes: list[str]
    seconds: float = 0.0
    error: str | None = None
    n_ran: int = 0


def _is_real(ref: str) -> bool:
    """A registered dataset (recorded data), not a synthetic scene or a file."""
    return parse_dataset_ref(ref).kind == "registered"


def _data_kind(ref: str) -> str:
    parsed = parse_dataset_ref(ref)
    if parsed.kind == "scene":
        return f"synthetic scene `{ref}`"
    if parsed.kind == "registered" and parsed.value.startswith("haart"):
        return f"real HAART (`{ref}`)"
    return f"`{ref}`"


def _fmt(v: float | None, d: int = 1) -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.{d}f}"


def _rel(p: Path) -> str:
    try:
        return str(Path(p).resolve().relative_to(REPO_ROOT))
    except ValueError:
        return str(p)


def _read(out: Path) -> tuple[pd.DataFrame | None, pd.DataFrame | None, dict[str, Any]]:
    if not (out / "scores.parquet").is_file():
        return None, None, {}
    scores = read_results_table(out / "scores.parquet")
    preds = read_results_table(out / "predictions.parquet") if (out / "predictions.parquet").is_file() else None
    man = json.loads((out / "manifest.json").read_text()) if (out / "manifest.json").is_file() else {}
    return scores, preds, man


def _ok_tasks(scores: pd.DataFrame, classifier: str | None = None) -> pd.DataFrame:
    ok = scores[scores["status"] == "ok"]
    return ok if classifier is None else ok[ok["classifier"] == classifier]


def _deviation_section(check: ExpectedDeviation, scores: pd.DataFrame, flags: list[str], name: str) -> list[str]:
    """A paper's standard deviation over the folds against ours (sample sd of our folds' accuracy)."""
    sel = _ok_tasks(scores, check.classifier)
    sd = 100 * float(np.std(sel["accuracy"], ddof=1)) if len(sel) > 1 else math.nan
    d = sd - check.value
    within = math.isfinite(sd) and abs(d) <= check.tolerance
    if not within:
        flags.append(f"{check.source} (`{name}`): ours {_fmt(sd)} points, paper {check.value:g} "
                     f"(tolerance {check.tolerance:g})")
    return [f"**{check.source}:** paper {check.value:g} points, ours {_fmt(sd)} points "
            f"(sample sd over {len(sel)} folds), difference {d:+.1f}, tolerance {check.tolerance:g}: "
            f"{'within' if within else '**outside**'}."]


def _confusion_matrices(check: ExpectedConfusion, scores: pd.DataFrame,
                        preds: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The paper's matrix and ours (pooled over the folds of ``check.classifier``'s tasks, or of the
    configuration of it with the best mean accuracy where a grid named several), rows the true class."""
    paper = np.asarray(check.matrix, dtype=float)
    if check.rows == "predicted":
        paper = paper.T  # rows = true class, as ours
    ok = _ok_tasks(scores)
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
        lines.append(f"| {c} | {cells} | {_fmt(r_paper[i])} | {_fmt(r_ours[i])} | {d:+.1f}{mark} |")
    acc_p = 100 * np.trace(paper) / paper.sum()
    acc_o = 100 * np.trace(ours) / ours.sum() if ours.sum() else math.nan
    lines += ["", f"Cells are paper / ours. Accuracy of the matrix: paper {acc_p:.2f} % ({int(paper.sum())} captures), "
                  f"ours {_fmt(acc_o, 2)} % ({int(ours.sum())} captures)."]
    if outside:
        flags.append(f"{check.source} (`{name}`): per-class recall differs by more than {check.tolerance:g} "
                     f"points for {', '.join(outside)}")
        lines += ["", f"**Outside tolerance:** {', '.join(outside)}."]
    return lines


def _best_section(check: ExpectedBest, paper_best: str, scores: pd.DataFrame, flags: list[str],
                  name: str) -> list[str]:
    """The best configuration of a sweep (``paper_best``: its entry's label) against ours (best mean accuracy)."""
    ok = _ok_tasks(scores)
    if ok.empty:
        return [f"**{check.source}:** no results."]
    m = ok.groupby("classifier")["accuracy"].agg(["mean", "std", "count"])
    order = sorted(m.index, key=lambda s: float(s.split("=")[-1].rstrip(")")) if "=" in s else s)
    best = m["mean"].idxmax()
    lines = [f"**{check.source}.** Ours, mean accuracy over the held-out subjects (%):", "",
             "| configuration | mean | sd | folds |", "|---|---|---|---|"]
    for k in order:
        star = " (best)" if k == best else ""
        lines.append(f"| {k}{star} | {100 * m.loc[k, 'mean']:.1f} | {_fmt(100 * m.loc[k, 'std'])} | {int(m.loc[k, 'count'])} |")
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


def _other_sections(proto, scores: pd.DataFrame, preds: pd.DataFrame | None, flags: list[str]) -> list[list[str]]:
    """The sections of the expected numbers that are not one accuracy, in the order
    standard deviations, confusions, best parameter values."""
    if proto.expected is None:
        return []
    e, name = proto.expected, proto.name
    return ([_deviation_section(c, scores, flags, name) for c in e.standard_deviations]
            + [_confusion_section(c, scores, preds, flags, name) for c in e.confusions]
            + [_best_section(c, proto.best_label(c), scores, flags, name) for c in e.best_parameters])


def _expected_rows(proto, scores: pd.DataFrame, preds: pd.DataFrame | None) -> list[dict[str, Any]]:
    if proto.expected is None:
        return []
    rows = check_expected(proto.expected, scores, preds, proto.features_label_of)
    parsed = parse_dataset_ref(proto.dataset.name)
    scene = parsed.value if parsed.kind == "scene" else None
    for r, e in zip(rows, proto.expected.results):
        r["cell"] = e.source or ""
        r["kind"], r["cause"] = cause_cell(r["within"], e.cause, scene)
    return rows


def _calibrated_on(ref: str, name: str) -> list[str]:
    """The scene values (``"scene-name `population.repetition`"``) calibrated on the table of the paper
    protocol ``name`` whose data is ``ref``, from that scene's ``calibrated:`` block; [] for real data."""
    parsed = parse_dataset_ref(ref)
    if parsed.kind != "scene":
        return []
    return [f"{parsed.value} `{prop}`" for prop, cal in load_scene(parsed.value).calibrated.items()
            if name in cal.protocols]


@dataclass
class _Section:
    lines: list[str]
    flags: list[str]  # numbers beyond tolerance
    problems: list[str] = field(default_factory=list)  # protocols or tasks that did not run
    real: bool = False
    data: str = "?"  # the overview's data column
    compared: int = 0
    within: int = 0
    seconds: float = 0.0
    status: str = "ran"
    calibrated: list[str] = field(default_factory=list)  # the scene values calibrated on this table
    kinds: list[str] = field(default_factory=list)  # the kind of cause of each number outside tolerance


def audit_dir(out: Path) -> Path:
    """Where ``papers reproduce --audit`` audits the protocol whose results are in ``out``."""
    return out.parent / f"{out.name}-audit"


def _audit_section(proto, out: Path) -> list[str]:
    """The leakage audit of a protocol, as measured (its ``audit.json``), with the variants that
    come within the paper's tolerance; or how to run it."""
    if proto.audit is None:
        return []
    path = audit_dir(out) / "audit.json"
    if not path.is_file():
        return ["", f"_Leakage audit not run: `touchbench papers reproduce --audit` (or `touchbench audit "
                    f"{proto.name} --out {_rel(audit_dir(out))}`)._", ""]
    doc = json.loads(path.read_text())
    table = pd.DataFrame(doc["rows"])
    lines = ["", f"Leakage audit (`{_rel(audit_dir(out))}`): the same method under the honest scheme and each "
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
    for check in (proto.expected.confusions if proto.expected is not None else []):
        lines += ["", *_audit_confusion(check, audit_dir(out), list(dict.fromkeys(table["variant"])))]
    return lines + [""]


def _audit_folds(folder: Path, variants: list[str]) -> str:
    """How many folds each audit variant ran (its ``scores.parquet`` in ``folder/<variant>/``)."""
    parts = []
    for v in variants:
        scores = _read(folder / v)[0]
        parts.append(f"{v} {'not run' if scores is None else int(scores['fold'].nunique())}")
    return "Folds run: " + ", ".join(parts) + "."


def _audit_confusion(check: ExpectedConfusion, folder: Path, variants: list[str]) -> list[str]:
    """Each audit variant's confusion (its pooled predictions, ``folder/<variant>/``) against a paper's
    matrix by per-class recall, and the variants whose every class comes within the tolerance."""
    lines = [f"{check.source}, per-class recall within {check.tolerance:g} points, by variant:", ""]
    matched = []
    for v in variants:
        scores, preds, _ = _read(folder / v)
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


def _protocol_section(r: ProtocolRun, profile: Profile) -> _Section:
    """The report section of one protocol: the comparison with the paper."""
    sec = _Section([], [])
    try:
        proto, _ = apply_profile(load_protocol(r.path), profile)
    except TouchbenchError as e:
        sec.status = "invalid"
        sec.lines = [f"### {r.name}", "", f"**Invalid protocol:** {e}", ""]
        sec.problems.append(f"{r.name}: invalid protocol")
        return sec
    ref = proto.dataset.name
    sec.real = _is_real(ref)
    sec.calibrated = _calibrated_on(ref, r.name)
    sec.data = "real HAART" if sec.real else ref
    body, flags = sec.lines, sec.flags
    body += [f"### {proto.description or proto.name}", ""]
    body.append(f"Protocol: `{_rel(r.path)}`. Data: {_data_kind(ref)}"
                + (f", options {proto.dataset.options}" if proto.dataset.options else "")
                + f". Scheme: {proto.scheme.name} {proto.scheme.params or ''}. Results: `{_rel(r.out)}`.")
    if r.changes:
        body.append(f"Profile '{profile.name}' changed: " + "; ".join(r.changes) + ".")
    if r.error:
        body += ["", f"**Did not run:** {r.error}", ""]
        sec.problems.append(f"{r.name}: did not run ({r.error.splitlines()[0]})")
        sec.status = "did not run"
        return sec
    scores, preds, man = _read(r.out)
    if scores is None:
        body += ["", "**No results.**", ""]
        sec.problems.append(f"{r.name}: no results")
        sec.status = "no results"
        return sec
    sec.seconds = sum(float(x.get("seconds") or 0) for x in man.get("sessions", []))
    n_fail = int((scores["status"] != "ok").sum())
    n_folds = int(scores["fold"].nunique())
    body.append(f"Run: {len(scores)} tasks over {n_folds} fold{'' if n_folds == 1 else 's'} ({n_fail} failed), "
                f"{sec.seconds / 60:.1f} min of run time on "
                f"{(man.get('platform') or {}).get('cpu_count', '?')} CPUs.")
    if n_fail:
        err = str(scores[scores["status"] != "ok"]["error"].iloc[0]).splitlines()[0]
        sec.problems.append(f"{r.name}: {n_fail} of {len(scores)} tasks failed ({err})")
    body.append("")
    rows = _expected_rows(proto, scores, preds)
    if rows:
        agg = proto.expected.aggregate
        body += [f"Accuracy in % ({'mean over folds' if agg == 'mean' else 'pooled over the folds'}):", "",
                 "| table cell | features | classifier | paper | ours | difference | tolerance | within | cause |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for e in rows:
            within = {True: "yes", False: "**NO**", None: "not run"}[e["within"]]
            diff = "—" if e["difference"] is None else f"{e['difference']:+.2f}"
            body.append(f"| {e['cell']} | {e['features']} | {e['classifier']} | {e['expected']:.2f} | "
                        f"{_fmt(e['observed'], 2)} | {diff} | {e['tolerance']:g} | {within} | {e['cause']} |")
            if e["within"] is not None:
                sec.compared += 1
                sec.within += bool(e["within"])
            if e["within"] is False:
                sec.kinds.append(e["kind"])
                flags.append(f"{e['cell']} (`{r.name}`): ours {e['observed']:.2f} %, paper "
                             f"{e['expected']:.2f} %, {e['difference']:+.2f} points (tolerance {e['tolerance']:g}); "
                             f"{KIND_SHORT[e['kind']]}")
        body.append("")
    body += _audit_section(proto, r.out)
    others = _other_sections(proto, scores, preds, flags)
    for lines in others:
        body += lines + [""]
    if not rows and not others:
        body += ["_No paper numbers to compare._", ""]
    return sec


@dataclass
class _Tally:
    """What the report's head says: the counts and the overview, the flags, the problems."""

    body: list[str] = field(default_factory=list)
    overview: list[str] = field(default_factory=lambda: [
        "| paper | table / figure | data | accuracies within tolerance | other differences | scene values "
        "calibrated on it | run time min | protocol |", "|---|---|---|---|---|---|---|---|"])
    flags_real: list[str] = field(default_factory=list)
    flags_synth: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    counts: dict[str, list[int]] = field(default_factory=dict)  # all, real, free, each paper: [within, compared]
    kinds: list[str] = field(default_factory=list)  # the kind of cause of each accuracy outside tolerance
    compute: float = 0.0

    def count(self, key: str, sec: _Section) -> None:
        c = self.counts.setdefault(key, [0, 0])
        c[0] += sec.within
        c[1] += sec.compared

    def add(self, short: str, r: ProtocolRun, sec: _Section) -> None:
        self.body += sec.lines
        (self.flags_real if sec.real else self.flags_synth).extend(sec.flags)
        self.problems += sec.problems
        self.kinds += sec.kinds
        self.compute += sec.seconds
        for key, counted in (("all", True), ("real", sec.real), ("free", not sec.calibrated),
                             (short, True)):
            if counted:
                self.count(key, sec)
        desc = sec.lines[0][4:] if sec.lines and sec.lines[0].startswith("### ") else r.name
        what = desc.split(":")[0].split("(")[0].strip()
        others = len(sec.flags) - (sec.compared - sec.within) + len(sec.problems)
        self.overview.append(
            f"| {short} | {what} | {sec.data} | "
            + (f"{sec.within} / {sec.compared}" if sec.compared else "—") + " | "
            + (sec.status if sec.status != "ran" else (str(others) if others else "—")) + " | "
            + (", ".join(sec.calibrated) or "—") + " | "
            + f"{sec.seconds / 60:.1f} | `{_rel(r.path)}` |")

    def of(self, key: str) -> str:
        w, c = self.counts.get(key, [0, 0])
        return f"{w} of {c}"


def _tally(runs: list[ProtocolRun], profile: Profile) -> _Tally:
    t = _Tally()
    for short, citation, prefix in PAPERS:
        mine = sorted((r for r in runs if r.name.startswith(prefix)), key=lambda r: r.name)
        if mine:
            t.body += [f"## {citation}", ""]
        for r in mine:
            t.add(short, r, _protocol_section(r, profile))
    return t


def write_report(runs: list[ProtocolRun], profile: Profile, path: Path, *, timing: dict[str, Any] | None = None) -> Path:
    """``REPORT.md``: for every table and figure, the paper's number, ours, the difference.

    ``timing``: wall and CPU seconds, load averages, jobs of the invocation
    that computed the results (see :func:`reproduce`).
    """
    now = datetime.now(timezone.utc).isoformat(timespec="seconds")
    git = git_revision()
    t = _tally(runs, profile)
    head = [
        "# Reproducing the four papers",
        "",
        f"Generated {now} by `touchbench papers reproduce --profile {profile.name}` (touchbench {__version__}, "
        f"git {str(git.get('revision') or '?')[:12]}{' with uncommitted changes' if git.get('dirty') else ''}) on "
        f"{platform.platform()}, {os.cpu_count()} CPUs"
        + (f", {timing['jobs']} parallel jobs" if timing and timing.get("jobs") else "") + ".",
        "",
        *_summary(t),
        f"**Profile `{profile.name}`:** {profile.description}.",
    ]
    if profile.classifier_caps or profile.scheme_caps or profile.dataset_options:
        head.append("Overrides (a cap replaces the protocol's value, or the classifier's default, by at most the "
                    "cap): " + "; ".join(_caps(profile)) + ". Each protocol below lists what changed.")
    head += [
        "",
        f"**Time:** {t.compute / 60:.1f} min of run time summed over the protocols' results (every session that "
        f"computed them)." + (" " + _timing_text(timing) if timing else ""),
        "",
        "Every number is computed by the protocol named in its section, from the method's parameters as the "
        "protocol file gives them (with the profile's caps); no method is tuned to a paper's number.",
        "",
    ] + t.overview + [""] + _differences(t)
    return write_text(Path(path), "\n".join(head + t.body) + "\n")


def _summary(t: _Tally) -> list[str]:
    per_paper = "; ".join(f"{short} {t.of(short)}" for short, _, _ in PAPERS if short in t.counts)
    return [
        f"**Summary:** {t.of('all')} paper numbers reproduced within tolerance ({per_paper}). On real HAART "
        f"data {t.of('real')}. On the tables no scene value was calibrated on, {t.of('free')}: a value a paper "
        "leaves unstated (how distinct two people are, how much one person's captures vary) is chosen on one "
        "named table and must then hold on the others (`docs/scenes.md` gives every scene property and where "
        "its value comes from; `docs/research/scene-calibration.md` the candidates measured).",
        "",
        _kinds_line(t.kinds),
        "",
    ]


def _kinds_line(kinds: list[str]) -> str:
    """The summary of the causes of the accuracies outside tolerance, counted by kind."""
    c = kind_counts(kinds)
    return (f"**Causes of the {len(kinds)} accuracies outside tolerance:** {c['measured']} measured (the "
            f"command that isolates the cause, and what it gave), {c['ruled_out']} ruled out (the cause is open; "
            f"what was excluded, each with its command or source), {c['unexplained']} unexplained (no cause "
            "known; on a synthetic scene, the scene's data). Each number's cause is in its table's cause column.")


def _caps(profile: Profile) -> list[str]:
    caps = [f"{c}: " + ", ".join(f"{p} ≤ {v:g}" for p, v in d.items()) for c, d in profile.classifier_caps.items()]
    caps += [f"scheme {s}: " + ", ".join(f"{p} ≤ {v}" for p, v in d.items()) for s, d in profile.scheme_caps.items()]
    return caps + [f"{ds}: " + ", ".join(f"{k} = {v}" for k, v in o.items()) for ds, o in profile.dataset_options.items()]


def _differences(t: _Tally) -> list[str]:
    head: list[str] = []
    if t.flags_real or t.flags_synth or t.problems:
        head += ["## Where we differ from the papers (beyond tolerance)", ""]
    if t.flags_real:
        head += ["On real HAART data:", ""] + [f"- {f}" for f in t.flags_real] + [""]
    if t.flags_synth:
        head += ["On synthetic scenes (each number's cause is in its table):", ""]
        head += [f"- {f}" for f in t.flags_synth] + [""]
    if t.problems:
        head += ["Not run or failed:", ""] + [f"- {f}" for f in t.problems] + [""]
    return head


def _timing_text(t: dict[str, Any]) -> str:
    who = (f"The invocation that computed them (finished {t.get('finished_at')}, {t.get('tasks_ran')} tasks)"
           if t.get("reused") else "This invocation")
    text = f"{who} took {t['wall_seconds'] / 60:.1f} min of wall time, dataset loading and scene generation included"
    cpus = t.get("cpus") or 1
    if t.get("cpu_seconds") is not None:
        text += (f", and {t['cpu_seconds'] / 60:.1f} min of CPU time (user + system, worker processes included): "
                 f"{t['cpu_seconds'] / 60 / cpus:.1f} min per CPU, the wall time to expect on an otherwise idle "
                 f"{cpus}-CPU machine")
    return text + "." + _conditions_text(t, cpus)


def _conditions_text(t: dict[str, Any], cpus: int) -> str:
    """The run's conditions: the load average sampled during the run (else at its ends), peak memory,
    the machine."""
    out = ""
    sampled, load = t.get("load_sampled"), t.get("load") or []
    if sampled:
        out += (f" The machine's 1-minute load average, sampled every {sampled['interval_s']:g} s during the run "
                f"({sampled['n']} samples), was {sampled['min']:.1f} to {sampled['max']:.1f} (median "
                f"{sampled['median']:.1f})" + (f": above {cpus}, other jobs shared the CPUs." if sampled["max"] > cpus
                                               else "."))
    elif len(load) == 2 and None not in load:
        out += (f" The machine's 1-minute load average was {load[0]:.1f} at the start and {load[1]:.1f} at the end"
                + (f" (above {cpus}: other jobs shared the CPUs)." if max(load) > cpus else "."))
    if t.get("peak_rss_mb") is not None:
        out += f" Peak memory (resident, the largest process): {t['peak_rss_mb']:.0f} MiB."
    m = t.get("machine") or {}
    if m:
        out += (f" Machine: {m.get('cpu_model') or m.get('processor') or m.get('machine')}, {m.get('cpu_count')} CPUs "
                f"({m.get('usable_cpus')} usable), {m.get('platform')}, Python {m.get('python')}.")
    return out
