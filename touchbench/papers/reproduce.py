"""``touchbench papers reproduce``: run the shipped paper protocols (``touchbench/protocols/papers/``) and write ``REPORT.md``.

Every one of them reproduces one table or figure of one of four papers
(Gaus et al. 2015, Al-mashhadani et al. 2021, Flagg 2012, Zhou et al. 2017)
and carries the paper's numbers in its ``expected:`` block: accuracies,
standard deviations, confusion matrices, the best value of a sweep
(:class:`touchbench.protocols.schema.Expected`).
:func:`reproduce` runs them all through the run engine
(:func:`touchbench.engine.runner.run_protocol`) under a *profile*, then
:func:`write_report` compares each expected number with ours.

Profiles (:data:`PROFILES`) trade fidelity for time, and say so in the
report. A profile changes three things, nothing else:

- ``classifier_caps``: ``{classifier name: {parameter: maximum}}``. The
  value a protocol gives (or, when it gives none, the classifier's
  registered default) is replaced by ``min(value, maximum)``; in a grid each
  value is capped and repeats are dropped. E.g. ``gaus-rf`` at most 100
  trees instead of the paper's 1000.
- ``scheme_caps``: ``{scheme name: {parameter: maximum}}``, the same for the
  scheme's parameters (Flagg's 100-fold cross-validation becomes 10-fold).
- ``dataset_options``: ``{dataset reference: {option: value}}`` merged into
  the protocol's ``dataset.options``: smaller synthetic scenes (fewer
  repetitions per person and gesture). Real data is never reduced.

and, for ``--audit``, ``audit_options``: keyword arguments of
:func:`touchbench.engine.audit.run_audit` (the quick profile's
``window_folds``: the window variant runs 2 of its 10 folds; the audit's
variants also get the classifier caps, being made from the profiled protocol).

A profile never changes features, feature parameters, classifiers'
other parameters, filters or seeds, and never touches the expected numbers:
a method is never adjusted to a number. The quick and full profiles write
to different results directories and their methods have different
parameter hashes, so they are never combined.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pandas as pd
from joblib.externals.loky import get_reusable_executor

from ..core.version import __version__
from ..catalog import load_dataset, parse_dataset_ref
from ..classifiers import CLASSIFIERS
from ..core.errors import TouchbenchError
from ..core.paths import REPO_ROOT
from ..engine.audit import run_audit
from ..engine.runner import run_protocol
from ..protocols.derive import derive, protocol_data
from ..protocols.library import PAPERS_DIR
from ..protocols.schema import (
    ExpectedBest,
    ExpectedConfusion,
    ExpectedDeviation,
    Protocol,
    load_protocol,
    resolve_dataset_ref,
)
from ..reports.audit import audit_markdown, write_audit
from ..reports.leaderboard import write_text
from ..reports.stats import corrected_resampled_t, holm
from ..results.manifest import git_revision, load_average
from ..results.store import PREDICTED, TRUE, read_results_table
from ..results.summary import check_expected

__all__ = ["PAPERS", "PROFILES", "Profile", "apply_profile", "paper_protocols", "reproduce", "write_report"]


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    classifier_caps: dict[str, dict[str, float]] = field(default_factory=dict)
    scheme_caps: dict[str, dict[str, int]] = field(default_factory=dict)
    dataset_options: dict[str, dict[str, Any]] = field(default_factory=dict)
    audit_options: dict[str, Any] = field(default_factory=dict)


PROFILES: dict[str, Profile] = {
    "full": Profile(
        "full",
        "the papers' settings: every classifier, scheme and dataset as the protocol files give them "
        "(1000-tree forests, 500 boosting iterations, 100-fold CV, full-size scenes, up to 100 CNN epochs)",
    ),
    "quick": Profile(
        "quick",
        "fewer trees and epochs and smaller synthetic scenes, so that every protocol runs on two cores in "
        "under 20 minutes; real HAART data is used whole; with --audit, the CNN's window variant (24,900 "
        "windows) runs the first 2 of its 10 folds",
        classifier_caps={
            "gaus-rf": {"n_estimators": 100},
            "gaus-boost": {"n_trees": 100, "n_estimators": 10},
            "cnn": {"max_epochs": 15, "patience": 4},
            "flagg-mlp": {"max_epochs": 100},
            "flagg-rf": {"n_estimators": 10},
            "zhou-bagged-trees": {"n_estimators": 30},
            "xgboost": {"n_estimators": 100},
        },
        scheme_caps={"kfold": {"k": 10}, "within-subject": {"k": 10}},
        dataset_options={
            "scene:cost-like": {"repetitions": 1},
            "scene:tpm-like": {"repetitions": 4},
            "scene:fur-like": {"repetitions": 10},
        },
        audit_options={"window_folds": 2},
    ),
}

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


# ----------------------------------------------------------------- profiles
def paper_protocols(directory: Path | None = None) -> list[Path]:
    d = Path(directory) if directory is not None else PAPERS_DIR
    files = sorted(d.glob("*.yaml"))
    if not files:
        raise TouchbenchError(f"no protocols in {d}")
    return files


def _cap(value: Any, cap: float) -> Any:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return value
    out = min(value, cap)
    return int(out) if isinstance(value, int) and float(out).is_integer() else out


def _cap_param(value: Any, cap: float) -> Any:
    if isinstance(value, dict) and set(value) == {"grid"}:
        vals = []
        for v in value["grid"]:
            c = _cap(v, cap)
            if c not in vals:
                vals.append(c)
        return {"grid": vals}
    return _cap(value, cap)


def apply_profile(original: Protocol, profile: Profile) -> tuple[Protocol, list[str]]:
    """``original`` under ``profile``'s overrides (a protocol made from the protocol,
    :func:`touchbench.protocols.derive.derive`), and the list of changes."""
    data = protocol_data(original)
    changes = (_cap_classifiers(data, profile) + _cap_scheme(data, profile) + _dataset_overrides(data, profile))
    if not changes:
        return original, []
    name = original.path.name if original.path is not None else original.name
    head = (f"# {name} under the '{profile.name}' profile of touchbench papers reproduce:\n"
            + "".join(f"#   {c}\n" for c in changes))
    return derive(original, data, head), changes


def _cap_classifiers(data: dict[str, Any], profile: Profile) -> list[str]:
    """Each classifier's parameters capped as the profile says (in ``data``); the changes."""
    changes = []
    for spec in data.get("classifiers") or []:
        caps = profile.classifier_caps.get(spec["name"], {})
        params = dict(spec.get("params") or {})
        defaults = CLASSIFIERS.entry(spec["name"]).tags.get("defaults") or {}
        for p, cap in caps.items():
            current = params.get(p, defaults.get(p))
            new = None if current is None else _cap_param(current, cap)
            if new is not None and new != current:
                params[p] = new
                changes.append(f"{spec.get('label') or spec['name']}: {p} {_show(current)} -> {_show(new)}")
        if params:
            spec["params"] = params
    return changes


def _cap_scheme(data: dict[str, Any], profile: Profile) -> list[str]:
    """The scheme's parameters capped as the profile says (in ``data``); the changes."""
    sch, changes = data["scheme"], []
    for p, cap in profile.scheme_caps.get(sch["name"], {}).items():
        if p in sch:
            new = _cap(sch[p], cap)
            if new != sch[p]:
                changes.append(f"scheme {sch['name']}: {p} {sch[p]} -> {new}")
                sch[p] = new
    return changes


def _dataset_overrides(data: dict[str, Any], profile: Profile) -> list[str]:
    """The dataset options the profile sets (in ``data``); the changes."""
    dspec = data["dataset"]
    opts = profile.dataset_options.get(dspec["name"])
    if not opts:
        return []
    dspec["options"] = {**(dspec.get("options") or {}), **opts}
    return [f"dataset {dspec['name']}: " + ", ".join(f"{k}={v}" for k, v in opts.items())]


def _show(v: Any) -> str:
    if isinstance(v, dict) and set(v) == {"grid"}:
        return "[" + ", ".join(map(str, v["grid"])) + "]"
    return str(v)


# ----------------------------------------------------------------- running
@dataclass
class ProtocolRun:
    path: Path
    name: str
    out: Path
    changes: list[str]
    seconds: float = 0.0
    error: str | None = None
    n_ran: int = 0


def _dataset_key(protocol) -> str:
    return json.dumps([resolve_dataset_ref(protocol), protocol.dataset.options], sort_keys=True, default=str)


def reproduce(profile: str = "quick", out: str | Path = "results/papers", *, only: list[str] | None = None,
              jobs: int = 1, progress: bool | None = None, report: str | Path | None = None,
              echo: Callable[[str], None] = print, protocols_dir: Path | None = None,
              failed: list[str] | None = None, audit: bool = False) -> Path:
    """Run every paper protocol under ``profile`` and write the report; returns its path.

    Results go to ``out/<profile>/<protocol name>/`` (resumable: a rerun
    skips finished tasks). Each dataset is loaded once for the protocols that
    share it. A protocol that fails to run is reported, and the others go on;
    ``failed`` (when given) receives the name of each protocol that failed or
    had a failed task. ``audit``: a protocol with an ``audit:`` block is also
    audited (:func:`touchbench.engine.audit.run_audit`) into
    ``out/<profile>/<protocol name>-audit/``; REPORT.md shows every audit found there.
    """
    if profile not in PROFILES:
        raise TouchbenchError(f"unknown profile {profile!r} (known: {', '.join(PROFILES)})")
    prof = PROFILES[profile]
    out = Path(out)
    if jobs in (-1, 0):
        jobs = os.cpu_count() or 1
    cpu0 = _cpu_seconds()
    load0 = _load()
    planned = _planned_protocols(protocols_dir, only, prof)
    runs: list[ProtocolRun] = []
    t_all = time.perf_counter()
    loaded = _LoadedDataset()
    audit_options = dict(prof.audit_options) if audit else None
    for proto, changes, f in planned:
        r = ProtocolRun(path=f, name=proto.name, out=out / profile / proto.name, changes=changes)
        _run_guarded(proto, r, loaded, echo=echo, jobs=jobs, progress=progress, failed=failed, audit=audit_options)
        runs.append(r)
    wall = time.perf_counter() - t_all
    _stop_workers()
    timing = {"wall_seconds": wall, "cpu_seconds": _cpu_seconds() - cpu0, "load": [load0, _load()], "jobs": jobs,
              "cpus": os.cpu_count(), "tasks_ran": sum(r.n_ran for r in runs),
              "protocols": len(runs), "finished_at": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    timing = _kept_timing(timing, out / profile / "invocation.json", subset=bool(only))
    report_path = Path(report) if report is not None else out / "REPORT.md"
    write_report(runs, prof, report_path, timing=timing)
    return report_path


def _planned_protocols(protocols_dir: Path | None, only: list[str] | None, prof) -> list[tuple]:
    """The paper protocols chosen by ``only``, under the profile, each with its changes and file,
    ordered so that the protocols of one dataset run together."""
    files = paper_protocols(protocols_dir)
    if only:
        files = [f for f in files if any(o == f.stem or o in f.stem for o in only)]
        if not files:
            raise TouchbenchError(f"no paper protocol matches {only}")
    planned = []
    for f in files:
        proto, changes = apply_profile(load_protocol(f), prof)
        planned.append((proto, changes, f))
    planned.sort(key=lambda t: (_dataset_key(t[0]), t[2].name))  # one dataset in memory at a time
    return planned


class _LoadedDataset:
    """The dataset last loaded, kept for the protocols after it that read the same one."""

    def __init__(self) -> None:
        self.key: str | None = None
        self.dataset = None

    def get(self, proto, echo: Callable[[str], None]):
        """The dataset of ``proto``: the one kept, or loaded now (and kept in its place)."""
        key = _dataset_key(proto)
        if key != self.key:
            self.key, self.dataset = None, None
            echo(f"loading {proto.dataset.name} {proto.dataset.options or ''}")
            self.dataset = load_dataset(resolve_dataset_ref(proto), **proto.dataset.options)
            self.key = key
        return self.dataset


def _run_guarded(proto, r: ProtocolRun, loaded: _LoadedDataset, *, echo: Callable[[str], None], jobs: int,
                 progress: bool | None, failed: list[str] | None, audit: dict[str, Any] | None) -> None:
    """Run one protocol into ``r``: any error is recorded in ``r.error`` (and the protocol's name in
    ``failed``) instead of raised, so that the other reproductions go on."""
    t0 = time.perf_counter()
    try:
        dataset = loaded.get(proto, echo)
        _run_one(proto, r, dataset, echo=echo, jobs=jobs, progress=progress, failed=failed, audit=audit)
    except TouchbenchError as e:
        r.error = str(e)
        echo(f"{proto.name}: FAILED: {e}")
    except Exception as e:  # a broken component must not stop the other reproductions
        r.error = f"{type(e).__name__}: {e}"
        echo(f"{proto.name}: FAILED: {r.error}")
    r.seconds = time.perf_counter() - t0
    if r.error and failed is not None:
        failed.append(proto.name)


def _run_one(proto, r: ProtocolRun, dataset, *, echo: Callable[[str], None], jobs: int, progress: bool | None,
             failed: list[str] | None, audit: dict[str, Any] | None) -> None:
    """Run one protocol on ``dataset`` into ``r.out``, and its leakage audit when asked (``audit``: the
    profile's options of :func:`touchbench.engine.audit.run_audit`, None: no audit)."""
    echo(f"{proto.name}: running -> {r.out}")
    res = run_protocol(proto, r.out, jobs=jobs, progress=progress, dataset=dataset)
    r.n_ran = res.n_ran
    echo(f"{proto.name}: {res.n_ran} ran, {res.n_skipped} finished before, {res.n_failed} failed, "
         f"{res.seconds:.0f} s")
    if res.n_failed and failed is not None:
        failed.append(proto.name)
    if audit is not None and proto.audit is not None:
        echo(f"{proto.name}: leakage audit -> {audit_dir(r.out)}")
        a = run_audit(proto, audit_dir(r.out), jobs=jobs, k=proto.audit.k,
                      window_seconds=proto.audit.window_seconds, tune=proto.audit.tune,
                      variants=tuple(proto.audit.variants), progress=progress, **audit)
        write_audit(a.table, audit_dir(r.out), a.published, a.notes, title=f"Leakage audit: {proto.name}")


def _kept_timing(timing: dict, timing_path: Path, *, subset: bool) -> dict:
    """The timing the report shows: this invocation's, written to ``timing_path``, when it ran tasks of
    every protocol; else the one recorded there by the run that computed them (if any)."""
    if timing["tasks_ran"] and not subset:
        write_text(timing_path, json.dumps(timing, indent=2) + "\n")
    elif timing_path.is_file():  # nothing (or only a subset) computed now: report the run that computed them
        try:
            timing = {**json.loads(timing_path.read_text()), "reused": True}
        except (OSError, ValueError):
            pass
    return timing


def _cpu_seconds() -> float:
    """User + system CPU seconds of this process and its finished child processes."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _load() -> float | None:
    """The load average for the timing record (JSON: None where the system keeps none)."""
    value = load_average()
    return None if math.isnan(value) else value


def _stop_workers() -> None:
    """Shut joblib's worker processes down, so their CPU time is counted."""
    try:
        get_reusable_executor().shutdown(wait=True)
    except Exception:  # no executor was started, or another backend
        pass


# ----------------------------------------------------------------- the report
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
    differences (Nadeau & Bengio), Holm-adjusted over the comparisons with the best."""
    acc = ok.pivot_table(index="fold", columns="classifier", values="accuracy", aggfunc="mean")
    ratio = ok.assign(r=ok["n_test"] / ok["n_train"]).groupby("fold")["r"].mean()
    others = [k for k in order if k != best]
    tests = []
    for k in others:
        both = acc[[best, k]].dropna()
        tests.append(corrected_resampled_t(both[best] - both[k], float(ratio.loc[both.index].mean())))
    if not tests:
        return []
    adjusted = holm([t.pvalue for t in tests])
    apart = [k for k, p in zip(others, adjusted) if p < alpha]
    lines = [f"Is the best distinguishable (corrected resampled t-test over the folds, Holm-adjusted over the "
             f"{len(others)} comparisons with the best, alpha {alpha:g})? Distinguishable from "
             + (", ".join(apart) if apart else "none of the others") + "."]
    if paper_best in others:
        i = others.index(paper_best)
        verdict = "distinguishable" if adjusted[i] < alpha else "not distinguishable"
        lines += ["", f"**Best {best} (ours) vs the paper's {paper_best}: {verdict} on {tests[i].n} folds "
                     f"(p = {tests[i].pvalue:.3f}, Holm-adjusted {adjusted[i]:.3f}; difference "
                     f"{100 * tests[i].mean_difference:+.1f} points).**"]
    return lines


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
    for r, e in zip(rows, proto.expected.results):
        r["cell"] = e.source or ""
        r["cause"] = _cause(r, e, proto.dataset.name)
    return rows


def _cause(row: dict[str, Any], result, ref: str) -> str:
    """The report's cause of one paper number: reproduced, synthetic data, or the measured cause
    the protocol gives (with the command that measured it)."""
    parsed = parse_dataset_ref(ref)
    if parsed.kind == "scene":
        return f"synthetic data (scene {parsed.value})"
    if row["within"] is None:
        return "not run"
    if row["within"]:
        return "reproduced"
    if result.cause is None:
        return "not explained"
    return f"{result.cause} (measured by `{result.measured_by}`)".replace("|", "\\|")


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
    body.append(f"Run: {len(scores)} tasks ({n_fail} failed), {sec.seconds / 60:.1f} min of run time on "
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
                flags.append(f"{e['cell']} (`{r.name}`): ours {e['observed']:.2f} %, paper "
                             f"{e['expected']:.2f} %, {e['difference']:+.2f} points (tolerance {e['tolerance']:g})")
        body.append("")
    body += _audit_section(proto, r.out)
    others = _other_sections(proto, scores, preds, flags)
    for lines in others:
        body += lines + [""]
    if not rows and not others:
        body += ["_No paper numbers to compare._", ""]
    return sec


def write_report(runs: list[ProtocolRun], profile: Profile, path: Path, *, timing: dict[str, Any] | None = None) -> Path:
    """``REPORT.md``: for every table and figure, the paper's number, ours, the difference.

    ``timing``: wall and CPU seconds, load averages, jobs of the invocation
    that computed the results (see :func:`reproduce`).
    """
    now = datetime.now(timezone.utc).isoformat(timespec="seconds")
    git = git_revision()
    flags_real: list[str] = []
    flags_synth: list[str] = []
    problems: list[str] = []
    body: list[str] = []
    overview = ["| paper | table / figure | data | accuracies within tolerance | other differences | run time min | protocol |",
                "|---|---|---|---|---|---|---|"]
    n_compared = n_within = real_compared = real_within = 0
    compute = 0.0
    for short, citation, prefix in PAPERS:
        mine = sorted((r for r in runs if r.name.startswith(prefix)), key=lambda r: r.name)
        if not mine:
            continue
        body += [f"## {citation}", ""]
        for r in mine:
            sec = _protocol_section(r, profile)
            body += sec.lines
            (flags_real if sec.real else flags_synth).extend(sec.flags)
            problems += sec.problems
            compute += sec.seconds
            n_compared += sec.compared
            n_within += sec.within
            if sec.real:
                real_compared += sec.compared
                real_within += sec.within
            desc = sec.lines[0][4:] if sec.lines and sec.lines[0].startswith("### ") else r.name
            what = desc.split(":")[0].split("(")[0].strip()
            others = len(sec.flags) - (sec.compared - sec.within) + len(sec.problems)
            overview.append(
                f"| {short} | {what} | {sec.data} | "
                + (f"{sec.within} / {sec.compared}" if sec.compared else "—") + " | "
                + (sec.status if sec.status != "ran" else (str(others) if others else "—")) + " | "
                + f"{sec.seconds / 60:.1f} | `{_rel(r.path)}` |")
    head = [
        "# Reproducing the four papers",
        "",
        f"Generated {now} by `touchbench papers reproduce --profile {profile.name}` (touchbench {__version__}, "
        f"git {str(git.get('revision') or '?')[:12]}{' with uncommitted changes' if git.get('dirty') else ''}) on "
        f"{platform.platform()}, {os.cpu_count()} CPUs"
        + (f", {timing['jobs']} parallel jobs" if timing and timing.get("jobs") else "") + ".",
        "",
        f"**Profile `{profile.name}`:** {profile.description}.",
    ]
    if profile.classifier_caps or profile.scheme_caps or profile.dataset_options:
        caps = [f"{c}: " + ", ".join(f"{p} ≤ {v:g}" for p, v in d.items()) for c, d in profile.classifier_caps.items()]
        caps += [f"scheme {s}: " + ", ".join(f"{p} ≤ {v}" for p, v in d.items()) for s, d in profile.scheme_caps.items()]
        caps += [f"{ds}: " + ", ".join(f"{k} = {v}" for k, v in o.items()) for ds, o in profile.dataset_options.items()]
        head.append("Overrides (a cap replaces the protocol's value, or the classifier's default, by at most the "
                    "cap): " + "; ".join(caps) + ". Each protocol below lists what changed.")
    head += [
        "",
        f"**Time:** {compute / 60:.1f} min of run time summed over the protocols' results (every session that "
        f"computed them)." + (" " + _timing_text(timing) if timing else ""),
        "",
        f"**Summary:** {n_within} of {n_compared} paper numbers reproduced within tolerance; on real HAART data "
        f"{real_within} of {real_compared}. Synthetic scenes (CoST, fur sensor, textile sensor) only imitate "
        f"the papers' data: their numbers check that each protocol runs, not the paper's result.",
        "",
        "Every number is computed by the protocol named in its section, from the method's parameters as the "
        "protocol file gives them (with the profile's caps); no method is tuned to a paper's number.",
        "",
    ] + overview + [""]
    if flags_real or flags_synth or problems:
        head += ["## Where we differ from the papers (beyond tolerance)", ""]
    if flags_real:
        head += ["On real HAART data:", ""] + [f"- {f}" for f in flags_real] + [""]
    if flags_synth:
        head += ["On synthetic scenes (not the papers' data; agreement is not expected):", ""]
        head += [f"- {f}" for f in flags_synth] + [""]
    if problems:
        head += ["Not run or failed:", ""] + [f"- {f}" for f in problems] + [""]
    text = "\n".join(head + body) + "\n"
    return write_text(Path(path), text)


def _timing_text(t: dict[str, Any]) -> str:
    who = (f"The invocation that computed them (finished {t.get('finished_at')}, {t.get('tasks_ran')} tasks)"
           if t.get("reused") else "This invocation")
    text = f"{who} took {t['wall_seconds'] / 60:.1f} min of wall time, dataset loading and scene generation included"
    cpus = t.get("cpus") or 1
    if t.get("cpu_seconds") is not None:
        text += (f", and {t['cpu_seconds'] / 60:.1f} min of CPU time (user + system, worker processes included): "
                 f"{t['cpu_seconds'] / 60 / cpus:.1f} min per CPU, the wall time to expect on an otherwise idle "
                 f"{cpus}-CPU machine")
    load = t.get("load") or []
    if len(load) == 2 and None not in load:
        text += (f". The machine's 1-minute load average was {load[0]:.1f} at the start and {load[1]:.1f} at the "
                 f"end (above {cpus}: other jobs shared the CPUs)" if max(load) > cpus else
                 f". The machine's 1-minute load average was {load[0]:.1f} at the start and {load[1]:.1f} at the end")
    return text + "."
