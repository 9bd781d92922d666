"""``manifest.json``: what a results directory was produced with.

touchbench version, git revision (and whether the working tree had
uncommitted changes), versions of the packages results depend on, platform,
CPU model and count (and how many the run could use), the protocol's text
and hashes, the dataset's reference and hash, the identity of the run's components (``identity``: every package version
that entered a task id, and the modules whose source did, per component),
and the start and end of every session that worked on the run (a resumed
run has several sessions; ``started_at`` is the first one's start and
``finished_at`` the last one's end).
"""

from __future__ import annotations

import math
import os
import platform
import subprocess
import sys
import threading
from datetime import datetime, timezone
from typing import Any

from ..core.version import __version__
from ..core.paths import REPO_ROOT
from ..core.threads import available_cpus
from ..core.versions import package_versions
from .store import SCHEMA_VERSION

__all__ = ["LoadSampler", "cpu_model", "git_revision", "load_average", "now_iso", "package_versions", "platform_info",
           "update_manifest"]

def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


#: how a run's notes begin for a component left out of one of several evaluations (its sensor refused it)
LEFT_OUT = "left out of evaluation "


def git_revision() -> dict[str, Any]:
    """``{"revision": sha or None, "dirty": bool or None}`` of the touchbench checkout."""
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO_ROOT, capture_output=True, text=True, timeout=10)
        if rev.returncode != 0:
            return {"revision": None, "dirty": None}
        st = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO_ROOT,
                            capture_output=True, text=True, timeout=10)
        return {"revision": rev.stdout.strip(), "dirty": bool(st.stdout.strip()) if st.returncode == 0 else None}
    except (OSError, subprocess.SubprocessError):
        return {"revision": None, "dirty": None}


def cpu_model(cpuinfo: str = "/proc/cpuinfo") -> str | None:
    """The CPU's model name: the first ``model name`` of ``cpuinfo`` (Linux's), else the
    platform's processor name (None when neither says)."""
    try:
        with open(cpuinfo, encoding="utf-8", errors="replace") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key.strip() == "model name" and value.strip():
                    return value.strip()
    except OSError:
        pass
    return platform.processor() or None


def load_average() -> float:
    """The machine's 1-minute load average (NaN where the system keeps none)."""
    try:
        return float(os.getloadavg()[0])
    except (OSError, AttributeError):
        return math.nan


class LoadSampler:
    """The 1-minute load average sampled every ``interval`` seconds in a thread of its own while the
    ``with`` block runs (one sample at the start and one at the end as well), so that a long run can
    say how busy the machine was throughout, not only at its ends."""

    def __init__(self, interval: float = 30.0, read: Any = None):
        self.interval = float(interval)
        self.read = read or load_average
        self.samples: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="touchbench-load", daemon=True)

    def _loop(self) -> None:
        while not self._stop.wait(self.interval):
            self._take()

    def _take(self) -> None:
        v = self.read()
        if v is not None and math.isfinite(v):
            self.samples.append(float(v))

    def __enter__(self) -> "LoadSampler":
        self._take()
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join()
        self._take()

    def summary(self) -> dict[str, Any] | None:
        """``{n, interval_s, min, median, max}`` of the samples (None without any)."""
        if not self.samples:
            return None
        a = sorted(self.samples)
        mid = len(a) // 2
        median = a[mid] if len(a) % 2 else (a[mid - 1] + a[mid]) / 2.0
        return {"n": len(a), "interval_s": self.interval, "min": a[0], "median": median, "max": a[-1]}


def platform_info() -> dict[str, Any]:
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "cpu_model": cpu_model(),
        "python": sys.version.split()[0],
        "cpu_count": os.cpu_count(),
        "usable_cpus": available_cpus(),
    }


def update_manifest(previous: dict[str, Any] | None, *, run: dict[str, Any], protocol: dict[str, Any],
                    dataset: dict[str, Any], session: dict[str, Any], tasks: dict[str, Any],
                    notes: list[str], expected: list[dict[str, Any]] | None = None,
                    identity: dict[str, Any] | None = None) -> dict[str, Any]:
    """A manifest for this run, keeping the sessions of ``previous`` when it is the same run."""
    sessions = []
    if previous and previous.get("run", {}).get("run_id") == run.get("run_id"):
        sessions = list(previous.get("sessions", []))
    sessions.append(session)
    return {
        "touchbench_version": __version__,
        "results_schema": SCHEMA_VERSION,
        "git": git_revision(),
        "packages": package_versions(),
        "platform": platform_info(),
        "run": run,
        "protocol": protocol,
        "dataset": dataset,
        "identity": identity or {},
        "started_at": sessions[0].get("started_at"),
        "finished_at": session.get("finished_at"),
        "sessions": sessions,
        "tasks": tasks,
        "notes": notes,
        "expected": expected or [],
    }
