"""``touchbench papers reproduce``: run the shipped paper protocols (``touchbench/protocols/papers/``) and write ``REPORT.md``.

Every one of them reproduces one table or figure of one of four papers
(Gaus et al. 2015, Al-mashhadani et al. 2021, Flagg 2012, Zhou et al. 2017)
and carries the paper's numbers in its ``expected:`` block: accuracies,
standard deviations, confusion matrices, the best value of a sweep
(:class:`touchbench.protocols.expected.Expected`).
:func:`reproduce` runs them all through the run engine
(:func:`touchbench.engine.runner.run_protocol`) under a *profile*, then
:func:`write_report` compares each expected number with ours.

The profiles are in :mod:`touchbench.papers.profiles`, the report in
:mod:`touchbench.papers.report`.
"""

from __future__ import annotations

import json
import os
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Callable

from joblib.externals.loky import get_reusable_executor

from ..catalog import load_dataset
from ..core.errors import TouchbenchError
from ..engine.audit import run_audit
from ..engine.runner import fill_features, plan_protocol, run_protocol
from ..protocols.loading import load_protocol
from ..protocols.schema import resolve_dataset_ref
from ..reports.audit import write_audit
from ..results.manifest import LoadSampler, platform_info
from .profiles import PROFILES, apply_profile, paper_protocols
from .comparisons import audit_dir
from .report import ProtocolRun, write_report
from .timing import cpu_seconds, folder_timing, load_now, peak_rss_mb, record_invocation

__all__ = ["reproduce"]


def _dataset_key(protocol) -> str:
    return json.dumps([resolve_dataset_ref(protocol), protocol.dataset.options], sort_keys=True, default=str)


def reproduce(profile: str = "quick", out: str | Path = "results/papers", *, only: list[str] | None = None,
              jobs: int = 1, progress: bool | None = None, report: str | Path | None = None,
              echo: Callable[[str], None] = print, protocols_dir: Path | None = None,
              failed: list[str] | None = None, audit: bool = False) -> Path:
    """Run every paper protocol under ``profile`` and write the report; returns its path.

    Results go to ``out/<profile>/<protocol name>/`` (resumable: a rerun
    skips finished tasks). Each dataset is loaded once for the protocols that
    share it, and their feature-cache entries are computed together before the
    first of them runs (:func:`_fill_features`). A protocol that fails to run is reported, and the others go on;
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
    cpu0 = cpu_seconds()
    load0 = load_now()
    planned = _planned_protocols(protocols_dir, prof)
    chosen = _chosen(planned, only)
    runs: list[ProtocolRun] = []
    t_all = time.perf_counter()
    loaded = _LoadedDataset()
    audit_options = dict(prof.audit_options) if audit else None
    filled: set[str] = set()
    with LoadSampler() as sampler:
        for proto, changes, f in chosen:
            if _dataset_key(proto) not in filled:  # the first protocol of its dataset
                filled.add(_dataset_key(proto))
                group = [(p, out / profile / p.name) for p, _, _ in chosen if _dataset_key(p) == _dataset_key(proto)]
                if len(group) > 1:  # one protocol fills its own
                    _fill_features(group, loaded, echo=echo, jobs=jobs, progress=progress)
            r = ProtocolRun(path=f, name=proto.name, out=out / profile / proto.name, changes=changes)
            earlier = [run.out for (p, _, _), run in zip(chosen, runs) if _dataset_key(p) == _dataset_key(proto)]
            _run_guarded(proto, r, loaded, echo=echo, jobs=jobs, progress=progress, failed=failed,
                         audit=audit_options, reuse=earlier)
            runs.append(r)
        wall = time.perf_counter() - t_all
        _stop_workers()
    timing = {"wall_seconds": wall, "cpu_seconds": cpu_seconds() - cpu0, "load": [load0, load_now()], "jobs": jobs,
              "load_sampled": sampler.summary(), "machine": platform_info(), "cpus": os.cpu_count(),
              "tasks_ran": sum(r.n_ran for r in runs), "protocols": len(runs), "only": list(only or []),
              "finished_at": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    if only:
        runs = _with_earlier_results(runs, planned, out / profile)
    report_path = Path(report) if report is not None else out / "REPORT.md"
    folder = out / profile
    write_report(runs, prof, report_path, timing=folder_timing(folder, timing))
    timing["peak_rss_mb"] = peak_rss_mb()  # after the report: its memory counts
    if timing["tasks_ran"]:
        record_invocation(folder, timing)
    write_report(runs, prof, report_path, timing=folder_timing(folder, timing))
    return report_path


def _planned_protocols(protocols_dir: Path | None, prof) -> list[tuple]:
    """Every paper protocol under the profile, each with its changes and file, ordered so that the
    protocols of one dataset run together."""
    planned = []
    for f in paper_protocols(protocols_dir):
        proto, changes = apply_profile(load_protocol(f), prof)
        planned.append((proto, changes, f))
    planned.sort(key=lambda t: (_dataset_key(t[0]), t[2].name))  # one dataset in memory at a time
    return planned


def _chosen(planned: list[tuple], only: list[str] | None) -> list[tuple]:
    """The planned protocols whose file name contains one of ``only`` (all of them without ``only``)."""
    if not only:
        return planned
    return [p for p in planned if p[2] in set(chosen_files([f for _, _, f in planned], only))]


def chosen_files(files: list[Path], only: list[str]) -> list[Path]:
    """The paper protocol ``files`` whose name contains one of ``only``; an empty name (which every
    name contains) or one that names no protocol is refused, naming the protocols."""
    names = ", ".join(f.stem for f in files)
    if any(not o.strip() for o in only):
        raise TouchbenchError(f"--only: an empty name would select every protocol; give part of a "
                              f"protocol's name (one of: {names})")
    unmatched = [o for o in only if not any(o in f.stem for f in files)]
    if unmatched:
        raise TouchbenchError(f"--only: no paper protocol's name contains {unmatched[0]!r} (the protocols: {names})")
    return [f for f in files if any(o in f.stem for o in only)]


def _with_earlier_results(runs: list[ProtocolRun], planned: list[tuple], folder: Path) -> list[ProtocolRun]:
    """The runs a partial invocation (``only``) reports: every planned protocol in order, those just
    run as they ran and the others whose results an earlier invocation left in ``folder``, so that
    rerunning one paper does not drop the others from REPORT.md."""
    ran = {r.name: r for r in runs}
    out = []
    for proto, changes, f in planned:
        if proto.name in ran:
            out.append(ran[proto.name])
        elif (folder / proto.name / "manifest.json").is_file():
            out.append(ProtocolRun(path=f, name=proto.name, out=folder / proto.name, changes=changes))
    return out


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


def _fill_features(group: list[tuple[Any, Path]], loaded: "_LoadedDataset", *, echo: Callable[[str], None],
                   jobs: int, progress: bool | None) -> None:
    """The feature-cache entries of the protocols of one dataset (``group``: each with its results
    folder), computed together before the first of them runs
    (:func:`touchbench.engine.runner.fill_features`: Zhou's tables compute their frame descriptors
    once). A protocol that cannot be planned, or a set that fails, is left to the protocol's own
    run, which reports it."""
    plans = []
    for proto, folder in group:
        try:
            plans += plan_protocol(proto, folder, dataset=loaded.get(proto, echo))
        except Exception:  # noqa: BLE001 -- reported by the protocol's own run
            continue
    try:
        for note in fill_features(plans, jobs=jobs, progress=progress):
            echo(note)
    except Exception:  # noqa: BLE001 -- the set fails again in its protocol's run, which reports it
        pass


def _run_guarded(proto, r: ProtocolRun, loaded: _LoadedDataset, *, echo: Callable[[str], None], jobs: int,
                 progress: bool | None, failed: list[str] | None, audit: dict[str, Any] | None,
                 reuse: list[Path]) -> None:
    """Run one protocol into ``r``: any error is recorded in ``r.error`` (and the protocol's name in
    ``failed``) instead of raised, so that the other reproductions go on. ``reuse``: the results
    folders of the protocols run before it on its dataset (a task finished there is not run again)."""
    t0 = time.perf_counter()
    try:
        dataset = loaded.get(proto, echo)
        _run_one(proto, r, dataset, echo=echo, jobs=jobs, progress=progress, failed=failed, audit=audit,
                 reuse=reuse)
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
             failed: list[str] | None, audit: dict[str, Any] | None, reuse: list[Path]) -> None:
    """Run one protocol on ``dataset`` into ``r.out``, and its leakage audit when asked (``audit``: the
    profile's options of :func:`touchbench.engine.audit.run_audit`, None: no audit). A task finished
    in a folder of ``reuse``, or for the audit in the protocol's own run, is taken from there."""
    echo(f"{proto.name}: running -> {r.out}")
    res = run_protocol(proto, r.out, jobs=jobs, progress=progress, dataset=dataset, reuse=reuse)
    r.n_ran = res.n_ran
    echo(f"{proto.name}: {res.n_ran} ran, {res.n_skipped} finished before, {res.n_failed} failed, "
         f"{res.seconds:.0f} s")
    if res.n_failed and failed is not None:
        failed.append(proto.name)
    if audit is not None and proto.audit is not None:
        echo(f"{proto.name}: leakage audit -> {audit_dir(r.out)}")
        a = run_audit(proto, audit_dir(r.out), jobs=jobs, k=proto.audit.k,
                      window_seconds=proto.audit.window_seconds, tune=proto.audit.tune,
                      variants=tuple(proto.audit.variants), progress=progress, reuse=[r.out], **audit)
        write_audit(a.table, audit_dir(r.out), a.published, a.notes, title=f"Leakage audit: {proto.name}")


def _stop_workers() -> None:
    """Shut joblib's worker processes down, so their CPU time is counted."""
    try:
        get_reusable_executor().shutdown(wait=True)
    except Exception:  # no executor was started, or another backend
        pass
