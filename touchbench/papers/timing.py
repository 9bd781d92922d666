"""The time line of the paper report: what each invocation of ``touchbench papers reproduce`` into
one results folder cost (wall and CPU time, the load sampled during it, peak memory, the machine),
kept in the folder's ``invocations.jsonl`` (one JSON object a line, appended by every invocation
that ran tasks), and the report's sentence about it: one invocation's figures, or the sum (wall,
CPU, tasks) and the largest (peak memory, load) of several, so that ``--only`` runs into one folder
are all counted. Peak memory is read after the report is written (:func:`touchbench.papers.reproduce.reproduce`)."""

from __future__ import annotations

import json
import math
import resource
from pathlib import Path
from typing import Any

from ..results.manifest import load_average

__all__ = ["LOG", "cpu_seconds", "folder_timing", "load_now", "peak_rss_mb", "record_invocation", "timing_text"]

#: The file of a results folder (``out/<profile>/``) that lists its invocations.
LOG = "invocations.jsonl"
#: The single record an earlier version kept (the last full invocation), read where there is no log.
_LEGACY = "invocation.json"


def record_invocation(folder: Path, timing: dict[str, Any]) -> None:
    """Append one invocation's ``timing`` to ``folder``'s log."""
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / LOG, "a", encoding="utf-8") as f:
        f.write(json.dumps(timing, sort_keys=True) + "\n")


def _entries(folder: Path) -> list[dict[str, Any]]:
    """The invocations recorded in ``folder``, in order: the legacy record first (an earlier version's
    last full invocation, where there is one), then the log's (unreadable lines skipped)."""
    out = []
    if (folder / _LEGACY).is_file():
        try:
            out.append(json.loads((folder / _LEGACY).read_text(encoding="utf-8")))
        except (OSError, ValueError):
            pass
    if (folder / LOG).is_file():
        for line in (folder / LOG).read_text(encoding="utf-8").splitlines():
            try:
                out.append(json.loads(line))
            except ValueError:
                continue
    return [e for e in out if isinstance(e, dict) and "wall_seconds" in e]


def folder_timing(folder: Path, current: dict[str, Any]) -> dict[str, Any]:
    """The timing the report shows: every invocation recorded in ``folder`` (one, or several summed:
    wall and CPU seconds and tasks; the largest peak memory; the load's range over their samples; the
    last one's machine and end), marked ``reused`` unless it is ``current`` alone; ``current`` where
    none is recorded."""
    entries = _entries(folder)
    if not entries:
        return current
    if len(entries) == 1:
        only = entries[0]
        this = (only.get("finished_at"), only.get("wall_seconds")) == (current.get("finished_at"),
                                                                       current.get("wall_seconds"))
        return {**only, "invocations": 1, **({} if this else {"reused": True})}
    last = entries[-1]
    peaks = [e["peak_rss_mb"] for e in entries if e.get("peak_rss_mb") is not None]
    cpus = [e["cpu_seconds"] for e in entries if e.get("cpu_seconds") is not None]
    sampled = [e["load_sampled"] for e in entries if e.get("load_sampled")]
    return {
        **last, "invocations": len(entries), "reused": True,
        "wall_seconds": sum(float(e["wall_seconds"]) for e in entries),
        "cpu_seconds": sum(cpus) if len(cpus) == len(entries) else None,
        "tasks_ran": sum(int(e.get("tasks_ran") or 0) for e in entries),
        "peak_rss_mb": max(peaks) if peaks else None,
        "load_sampled": {"n": sum(x["n"] for x in sampled), "interval_s": sampled[-1]["interval_s"],
                         "min": min(x["min"] for x in sampled), "max": max(x["max"] for x in sampled),
                         "median": None} if sampled else None,
        "load": [entries[0].get("load", [None, None])[0], last.get("load", [None, None])[-1]],
    }


def cpu_seconds() -> float:
    """User + system CPU seconds of this process and its finished child processes."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def peak_rss_mb() -> float:
    """The largest resident memory of this process or of any of its finished child processes, MiB
    (Linux reports ``ru_maxrss`` in KiB)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return max(me.ru_maxrss, kids.ru_maxrss) / 1024.0


def load_now() -> float | None:
    """The load average for the timing record (JSON: None where the system keeps none)."""
    value = load_average()
    return None if math.isnan(value) else value


def timing_text(t: dict[str, Any]) -> str:
    n = int(t.get("invocations") or 1)
    if n > 1:
        who = (f"The {n} invocations that computed them (into this folder, each with the tasks it ran; the last "
               f"finished {t.get('finished_at')}, {t.get('tasks_ran')} tasks in all) took, summed,")
    elif t.get("reused"):
        who = f"The invocation that computed them (finished {t.get('finished_at')}, {t.get('tasks_ran')} tasks) took"
    else:
        who = "This invocation took"
    text = f"{who} {t['wall_seconds'] / 60:.1f} min of wall time, dataset loading and scene generation included"
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
        median = f" (median {sampled['median']:.1f})" if sampled.get("median") is not None else ""
        out += (f" The machine's 1-minute load average, sampled every {sampled['interval_s']:g} s during the run "
                f"({sampled['n']} samples), was {sampled['min']:.1f} to {sampled['max']:.1f}{median}"
                + (f": above {cpus}, other jobs shared the CPUs." if sampled["max"] > cpus else "."))
    elif len(load) == 2 and None not in load:
        out += (f" The machine's 1-minute load average was {load[0]:.1f} at the start and {load[1]:.1f} at the end"
                + (f" (above {cpus}: other jobs shared the CPUs)." if max(load) > cpus else "."))
    if t.get("peak_rss_mb") is not None:
        out += (f" Peak memory (resident, the largest process, read after the report was written"
                + (", the largest of the invocations" if int(t.get("invocations") or 1) > 1 else "")
                + f"): {t['peak_rss_mb']:.0f} MiB.")
    m = t.get("machine") or {}
    if m:
        out += (f" Machine: {m.get('cpu_model') or m.get('processor') or m.get('machine')}, {m.get('cpu_count')} CPUs "
                f"({m.get('usable_cpus')} usable), {m.get('platform')}, Python {m.get('python')}.")
    return out
