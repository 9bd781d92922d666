"""Latency you can compare across runs: besides the wall-clock time of labelling one capture, the CPU
time of the labelling thread (which other processes' load changes far less), the machine's load
average, the CPUs the run could use and the CPU model are recorded; the Pareto front (star and
figure) is on CPU time, results without it fall back to wall-clock time with a note, and a run
measured on a machine busier than its CPUs says so."""

from __future__ import annotations

import json
import os
import platform
import time

import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.engine import run_protocol
from touchbench.engine.tasks import _measure_latency
from touchbench.engine.testing import random_dataset
from touchbench.reports.leaderboard import build_leaderboards
from touchbench.reports.results import load_results
from touchbench.reports.testing import FakeMethod, write_fake_run
from touchbench.results import manifest
from touchbench.results.store import write_results_table

SLEEP_S = 0.004  # what a capture costs the fake methods below: 4 ms asleep, or 4 ms of CPU


class _Sleeps:
    """Labels a capture by waiting: wall-clock time passes, the thread uses (almost) no CPU."""

    def predict(self, captures):
        time.sleep(SLEEP_S)
        return ["pat"] * len(captures)


class _Busy:
    """Labels a capture by computing until the thread has used SLEEP_S seconds of CPU."""

    def predict(self, captures):
        end = time.thread_time() + SLEEP_S
        while time.thread_time() < end:
            pass
        return ["pat"] * len(captures)


def test_cpu_time_is_that_of_the_labelling_thread_not_the_clock():
    caps = [None] * 3
    wall, cpu = _measure_latency(_Sleeps(), caps)
    assert wall >= 1000 * SLEEP_S and cpu < 1.0  # 4 ms on the clock, well under 1 ms of CPU
    wall, cpu = _measure_latency(_Busy(), caps)
    assert 1000 * SLEEP_S <= cpu <= wall  # at least the 4 ms burnt; never more CPU than time passed


def test_cpu_model_from_proc_cpuinfo_else_the_platform(monkeypatch, tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Test CPU @ 2.00GHz\n\n"
                    "processor\t: 1\nmodel name\t: Test CPU @ 2.00GHz\n")
    assert manifest.cpu_model(str(info)) == "Test CPU @ 2.00GHz"
    info.unlink()  # no /proc/cpuinfo (macOS, Windows): the platform's name
    monkeypatch.setattr(platform, "processor", lambda: "arm")
    assert manifest.cpu_model(str(info)) == "arm"


@pytest.fixture
def busy_run(engine_env, tmp_path, monkeypatch):
    """A real run (3 folds) while the machine's load average is 10.5 on 2 usable CPUs."""
    monkeypatch.setattr(os, "getloadavg", lambda: (10.5, 9.0, 8.0))
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    data = tmp_path / "data.parquet"
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=2).to_parquet(data)
    p = tmp_path / "p.yaml"
    p.write_text(f"name: p\ndataset: {data}\nscheme: loso\nfeatures: [[test-mean]]\nclassifiers: [test-logreg]\n")
    run_protocol(p, out=tmp_path / "results" / "p", progress=False)
    return tmp_path / "results" / "p"


def test_a_run_records_cpu_time_load_and_cpus_and_says_when_the_machine_was_busy(busy_run):
    scores = pd.read_parquet(busy_run / "scores.parquet")
    timed = scores[scores["latency_ms"].notna()]
    assert len(timed) == 1 and timed["latency_cpu_ms"].notna().all() and (timed["latency_cpu_ms"] > 0).all()
    assert scores["latency_cpu_ms"].notna().sum() == 1  # measured once per method and run, like latency_ms
    assert (scores["load_avg"] == 10.5).all() and (scores["usable_cpus"] == 2).all()
    platform_block = json.loads((busy_run / "manifest.json").read_text())["platform"]
    assert platform_block["cpu_model"] == manifest.cpu_model() and platform_block["usable_cpus"] == 2
    lb = build_leaderboards(load_results([busy_run]))[0]
    model = manifest.cpu_model()  # the machine is described by its CPU model where the system names it
    assert model is None or f", {model}, " in next(iter(lb.machines.values()))
    assert any("busier than its CPUs (load average 10.5 on 2 usable CPUs)" in n for n in lb.notes)
    assert lb.rows["latency_cpu_ms"].iloc[0] == pytest.approx(timed["latency_cpu_ms"].iloc[0])


def _two_methods(tmp_path, **kw):
    """A (fold accuracies 1, 5/6, 1, 5/6) and B (5/6, 4/6, 5/6, 4/6): A is more accurate; on the wall
    clock A took 5 ms and B 1 ms (both on the front), in CPU time A 1 ms and B 2 ms (A dominates B)."""
    caps = pd.DataFrame([(f"{s}-{g}-{r}", s, g) for s in ("s1", "s2", "s3", "s4") for g in ("pat", "rub", "stroke")
                         for r in range(2)], columns=["capture_id", "subject", "gesture"])
    folds = {f"subject={s}": caps[caps["subject"] == s]["capture_id"].tolist() for s in ("s1", "s2", "s3", "s4")}
    wrong = lambda counts: {f: ids[:c] for (f, ids), c in zip(folds.items(), counts)}  # noqa: E731
    return write_fake_run(tmp_path / "results" / "run", caps, folds, [
        FakeMethod("msd", "rf", wrong=wrong([0, 1, 0, 1]), latency_ms=5.0, latency_cpu_ms=1.0, **kw),
        FakeMethod("sd", "rf", wrong=wrong([1, 2, 1, 2]), latency_ms=1.0, latency_cpu_ms=2.0, **kw),
    ], scheme={"name": "loso"})


def _front(lb) -> set[str]:
    return set(lb.rows.loc[lb.rows["pareto"], "features"])


def test_the_pareto_front_is_on_cpu_time(tmp_path):
    lb = build_leaderboards(load_results([_two_methods(tmp_path)]))[0]
    assert _front(lb) == {"msd"}
    assert not any("busier" in n or "wall-clock latency" in n for n in lb.notes)  # load 0 on 2 CPUs


def test_results_without_cpu_time_load_and_fall_back_to_wall_time_with_a_note(tmp_path):
    run = _two_methods(tmp_path)
    old = pd.read_parquet(run / "scores.parquet").drop(columns=["latency_cpu_ms", "load_avg", "usable_cpus"])
    write_results_table(run / "scores.parquet", old)  # as touchbench wrote it before it measured them
    assert "latency_cpu_ms" not in pq.read_schema(run / "scores.parquet").names
    rs = load_results([run])
    assert rs.scores["latency_cpu_ms"].isna().all() and rs.scores["load_avg"].isna().all()
    lb = build_leaderboards(rs)[0]
    assert _front(lb) == {"msd", "sd"}  # on the wall clock B is faster: both on the front
    assert any("Pareto front is on wall-clock latency" in n for n in lb.notes)


def test_the_pareto_figure_plots_cpu_time_or_says_it_is_wall_time(tmp_path):
    run = _two_methods(tmp_path)

    def plot() -> str:
        res = CliRunner().invoke(cli, ["plot", str(run), "--out", str(tmp_path / "pl"), "--kind", "pareto",
                                       "--format", "svg"])
        assert res.exit_code == 0, res.output
        return next((tmp_path / "pl").glob("*pareto.svg")).read_text()

    assert "CPU time per capture (ms)" in plot()
    old = pd.read_parquet(run / "scores.parquet").drop(columns=["latency_cpu_ms"])
    write_results_table(run / "scores.parquet", old)
    assert "wall-clock latency per capture (ms)" in plot()

