"""``REPORT.md`` of the paper reproduction: for every table and figure of the
four papers, the paper's number, ours, within tolerance or not, and the cause
of every difference with its kind (measured, ruled out or unexplained:
:mod:`.causes`); the counts lead, apart for the tables a scene value was
calibrated on, and the kinds of the causes of the numbers outside tolerance."""

from __future__ import annotations

import os
import platform
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pandas as pd

from ..catalog import parse_dataset_ref
from ..core.errors import TouchbenchError
from ..core.version import __version__
from ..protocols.expected import KIND_RULE
from ..protocols.loading import load_protocol
from ..reports.rendering import write_text
from ..results.manifest import git_revision
from ..results.summary import check_expected
from ..scenes import load_scene
from .causes import KIND_SHORT, cause_cell, kind_counts
from .comparisons import audit_figures, audit_section, fmt, other_sections, read_run, rel, seed_spread
from .profiles import Profile, apply_profile
from .timing import timing_text

__all__ = ["PAPERS", "ProtocolRun", "write_report"]

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



def _expected_rows(proto, scores: pd.DataFrame, preds: pd.DataFrame | None, out: Path) -> list[dict[str, Any]]:
    if proto.expected is None:
        return []
    rows = check_expected(proto.expected, scores, preds, proto.features_label_of)
    parsed = parse_dataset_ref(proto.dataset.name)
    scene = parsed.value if parsed.kind == "scene" else None
    audit = audit_figures(proto, out)
    for r, e in zip(rows, proto.expected.results):
        r["cell"] = e.source or ""
        r["kind"], r["cause"] = cause_cell(r["within"], e.cause, scene, e.value, r["tolerance"],
                                           audit.get(proto.method_name_of(e)))
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
    body.append(f"Protocol: `{rel(r.path)}`. Data: {_data_kind(ref)}"
                + (f", options {proto.dataset.options}" if proto.dataset.options else "")
                + f". Scheme: {proto.scheme.name} {proto.scheme.params or ''}. Results: `{rel(r.out)}`.")
    if r.changes:
        body.append(f"Profile '{profile.name}' changed: " + "; ".join(r.changes) + ".")
    if r.error:
        body += ["", f"**Did not run:** {r.error}", ""]
        sec.problems.append(f"{r.name}: did not run ({r.error.splitlines()[0]})")
        sec.status = "did not run"
        return sec
    scores, preds, man = read_run(r.out)
    if scores is None:
        body += ["", "**No results.**", ""]
        sec.problems.append(f"{r.name}: no results")
        sec.status = "no results"
        return sec
    sec.seconds = sum(float(x.get("seconds") or 0) for x in man.get("sessions", []))
    n_fail = int((scores["status"] != "ok").sum())
    n_folds = int(scores["fold"].nunique())
    n_seeds = int(scores["repetition"].nunique()) if "repetition" in scores else 1
    seeds = f" x {n_seeds} seeds (repetitions with different seeds)" if n_seeds > 1 else ""
    body.append(f"Run: {len(scores)} tasks over {n_folds} fold{'' if n_folds == 1 else 's'}{seeds} ({n_fail} failed), "
                f"{sec.seconds / 60:.1f} min of run time on "
                f"{(man.get('platform') or {}).get('cpu_count', '?')} CPUs.")
    if n_fail:
        err = str(scores[scores["status"] != "ok"]["error"].iloc[0]).splitlines()[0]
        sec.problems.append(f"{r.name}: {n_fail} of {len(scores)} tasks failed ({err})")
    body.append("")
    rows = _expected_rows(proto, scores, preds, r.out)
    if rows:
        agg = proto.expected.aggregate
        over = ('mean over folds' if agg == 'mean' else 'pooled over the folds') + (' and seeds' if seeds else '')
        body += [f"Accuracy in % ({over}" + ("; where a row has several seeds, ours gives their number and the range "
                                            "of the per-seed accuracies" if seeds else "") + "):", "",
                 "| table cell | features | classifier | paper | ours | difference | tolerance | within | cause |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for e in rows:
            within = {True: "yes", False: "**NO**", None: "not run"}[e["within"]]
            diff = "—" if e["difference"] is None else f"{e['difference']:+.2f}"
            body.append(f"| {e['cell']} | {e['features']} | {e['classifier']} | {e['expected']:.2f} | "
                        f"{fmt(e['observed'], 2)}{seed_spread(e['seeds'])} | {diff} | {e['tolerance']:g} | {within} | {e['cause']} |")
            if e["within"] is not None:
                sec.compared += 1
                sec.within += bool(e["within"])
            if e["within"] is False:
                sec.kinds.append(e["kind"])
                flags.append(f"{e['cell']} (`{r.name}`): ours {e['observed']:.2f} %, paper "
                             f"{e['expected']:.2f} %, {e['difference']:+.2f} points (tolerance {e['tolerance']:g}); "
                             f"{KIND_SHORT[e['kind']]}")
        body.append("")
    body += audit_section(proto, r.out)
    others = other_sections(proto, scores, preds, flags)
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
            + f"{sec.seconds / 60:.1f} | `{rel(r.path)}` |")

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
        f"computed them)." + (" " + timing_text(timing) if timing else ""),
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
            f"what was excluded, each with its command and what this row gave), {c['unexplained']} unexplained "
            "(no cause known; on a synthetic scene, the scene's data). Each number's cause is in its table's cause "
            f"column. **The rule:** {KIND_RULE}")


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
