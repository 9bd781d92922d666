"""Every script of benchmarks/ runs to the end with its smallest arguments, so none rots unnoticed.

The scripts are found in the folder: a new one fails here until SMOKE gives its smallest arguments
(a few seconds of work: the 14 captures of ``haart-sample``, the ``tiny`` scene, one repeat). A
module without ``if __name__ == "__main__":`` is a helper the scripts import, not a script. Each
script runs in a process of its own, in an empty folder, with a cache folder of its own (the
scripts write under ``cache_dir() / "benchmarks"``); the scripts that compare two versions of the
code are given this checkout's folder as the other version, so no git worktree is made.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import SUBPROCESS_HANG_S

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"

#: script -> its smallest arguments; {root}: the repository, {tmp}: the test's folder,
#: {results}: a results folder written by touchbench.reports.testing
SMOKE = {
    "bench_cli_startup.py": ["--runs", "1"],
    "bench_cnn_loso.py": ["--dataset", "haart-sample", "--subjects", "s01", "--max-epochs", "1", "--patience", "1",
                          "--no-groups"],
    "bench_cnn_lsweep.py": ["--dataset", "haart-sample", "--L", "30", "--subjects", "s01", "--max-epochs", "1",
                            "--patience", "1", "--no-groups"],
    "bench_dataset_cache.py": ["--name", "haart-sample", "--repeats", "1"],
    "bench_dataset_hash.py": ["--name", "haart-sample", "--repeats", "1"],
    "bench_engine.py": ["--what", "overhead", "--repeats", "1", "--dataset", "haart-sample"],
    "bench_engine_versions.py": ["--base", "{root}", "--protocol", "tiny", "--jobs", "1", "--runs", "1",
                                 "--filter", "subject=s01,s02"],
    "bench_features.py": ["--dataset", "haart-sample", "--runs", "1", "--no-tsfresh"],
    "bench_forest_wrapped.py": ["--dataset", "haart-sample", "--method", "touch-et-fast", "--runs", "1",
                                "--decisions", "2"],
    "bench_kill_resume.py": ["--kills", "1", "--jobs", "1", "--dataset", "haart-sample"],
    "bench_listing.py": ["--runs", "1", "--command", "data list"],
    "bench_memory_cost.py": ["--scene", "tiny", "--trees", "2"],
    "bench_papers_profile.py": ["--out", "{tmp}", "--profile", "quick", "--protocol", "flagg-fig4-6-combined-fur"],
    "bench_scenes.py": ["--scene", "tiny", "--runs", "1"],
    "bench_stream.py": ["--dataset", "haart-sample", "--trees", "2", "--sklearn-decisions", "2"],
    "bench_stream_replay.py": ["--dataset", "haart-sample", "--per-stream", "1", "--repeats", "1"],
    "bench_tests.py": ["--workers", "1", "--", "tests/test_docs_links.py", "-k", "index"],
    "bench_touch_latency.py": ["--dataset", "haart-sample", "--runs", "1", "--captures", "1",
                               "--methods", "touch-et-fast"],
    "compare_runs.py": ["--base", "{root}", "--protocol", "tiny", "--max-seconds", str(SUBPROCESS_HANG_S)],
    "compare_verdicts.py": ["--base", "{root}", "{results}"],
    "make_sample.py": ["--out", "{tmp}/sample.parquet"],
    "trace_protocol_route.py": [],
}
#: what each script prints when it ran to the end (beside exit status 0)
DONE = {
    "bench_cli_startup.py": "touchbench --help",
    "bench_cnn_loso.py": "mean accuracy over 1 folds",
    "bench_cnn_lsweep.py": "s/fold",
    "bench_dataset_cache.py": "warm load median",
    "bench_dataset_hash.py": "content hash alone",
    "bench_engine.py": "overhead: 4 tasks",
    "bench_engine_versions.py": "accuracy % (mean over folds)",
    "bench_features.py": "five Gaus sets together",
    "bench_forest_wrapped.py": "flat walk",
    "bench_kill_resume.py": "SIGKILLs: 1",
    "bench_listing.py": "data list (no index)",
    "bench_memory_cost.py": "peak RSS",
    "bench_papers_profile.py": "quick profile",
    "bench_scenes.py": "tiny: median wall",
    "bench_stream.py": "1s+2s",
    "bench_stream_replay.py": "load average",
    "bench_tests.py": "1 worker(s), warm: median",
    "bench_touch_latency.py": "touch-et-fast",
    "compare_runs.py": "all identical",
    "compare_verdicts.py": "verdicts changed: 0",
    "make_sample.py": "14 captures",
    "trace_protocol_route.py": "stream rule, YAML to first decision",
}
#: scripts that need the real HAART recordings
REAL_DATA = {"make_sample.py"}
#: scripts that need the deep extra (torch)
TORCH = {"bench_cnn_loso.py", "bench_cnn_lsweep.py"}


def scripts() -> list[str]:
    return sorted(p.name for p in BENCH.glob("*.py") if 'if __name__ == "__main__":' in p.read_text(encoding="utf-8"))


def test_every_benchmark_script_has_smallest_arguments():
    assert scripts() == sorted(SMOKE) == sorted(DONE), "give a new script's smallest arguments in SMOKE and DONE"
    helpers = sorted(p.stem for p in BENCH.glob("*.py") if p.name not in SMOKE)
    for name in helpers:  # a module that is no script is one the scripts import
        assert any(f"from {name} import" in (BENCH / s).read_text(encoding="utf-8") for s in SMOKE), name


def _fake_results(folder: Path) -> Path:
    import pandas as pd

    from touchbench.reports.testing import FakeMethod, write_fake_run

    captures = pd.DataFrame({"capture_id": [f"c{i}" for i in range(8)], "subject": ["a"] * 4 + ["b"] * 4,
                             "gesture": ["pat", "stroke"] * 4})
    folds = {"a": ["c0", "c1", "c2", "c3"], "b": ["c4", "c5", "c6", "c7"]}
    methods = [FakeMethod("msd", "rf", wrong={"a": ["c3"]}), FakeMethod("sd", "rf", wrong={"a": ["c0", "c1"], "b": ["c4"]})]
    write_fake_run(folder, captures, folds, methods)
    return folder


@pytest.mark.parametrize("script", scripts())
def test_benchmark_script_runs_with_its_smallest_arguments(script, tmp_path, request):
    if script in REAL_DATA:
        request.getfixturevalue("real_haart")  # skips (fails under CI=true) without the data
    if script in TORCH:
        pytest.importorskip("torch")
    fill = {"root": str(ROOT), "tmp": str(tmp_path)}
    if "{results}" in SMOKE[script]:
        fill["results"] = str(_fake_results(tmp_path / "results"))
    args = [a.format(**fill) for a in SMOKE[script]]
    env = dict(os.environ, TOUCHBENCH_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p))
    if script in REAL_DATA:
        env["TOUCHBENCH_CACHE_DIR"] = os.environ["TOUCHBENCH_CACHE_DIR"]  # the session's: HAART converted once
    work = tmp_path / "work"
    work.mkdir()
    r = subprocess.run([sys.executable, str(BENCH / script), *args], cwd=work, env=env, capture_output=True,
                       text=True, timeout=SUBPROCESS_HANG_S)
    assert r.returncode == 0, f"{script} {' '.join(args)}:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    assert DONE[script] in r.stdout, r.stdout[-3000:]
