"""Hostile and careless protocols: one clear message each, nothing left behind.

Every case here was once a crash, a hang or a file written where the user
did not ask: nested YAML aliases, duplicate keys, a billion repetitions, an
810,000-entry grid, ``--jobs 1000``, parameter values that fail every task,
a protocol naming a cache folder.
"""

from __future__ import annotations

import os
from functools import partial

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from touchbench.cli.main import cli
from touchbench.core import versions
from touchbench.core.errors import TouchbenchError
from touchbench.core.threads import available_cpus
from touchbench.core.yamlsafe import (
    MAX_ALIASES,
    MAX_BYTES,
    MAX_DEPTH,
    MAX_NODES,
    load_bounded,
)
from touchbench.engine import backends, cache, runner
from touchbench.features.base import make_feature_set
from touchbench.protocols import checks, schema
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import load_protocol, parse_protocol
from touchbench.protocols.schema import MAX_ENTRIES, MAX_REPETITIONS

HEAD = "dataset: scene:tiny\nscheme: loso\n"
BASE = HEAD + "features: [sd]\nclassifiers: [zhou-lda]\n"  # lines 1-4

LAUGHS = "a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
    f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi"))


def invoke(*args):
    return CliRunner().invoke(cli, list(args))


def refused(text: str, name: str = "p.yaml") -> str:
    with pytest.raises(ProtocolError) as e:
        parse_protocol(text, name)
    return str(e.value)


# ----------------------------------------------------------------- bounded YAML
def test_billion_laughs_is_refused_at_the_line_that_crosses_the_bound(tmp_path):
    assert len(LAUGHS) < 400  # 9 ** 9 strings once expanded
    msg = refused(BASE + LAUGHS)
    sizes = [10]  # nodes each line stands for: a list of 9 strings, then lists of 9 aliases to the line above
    for _ in range(8):
        sizes.append(1 + 9 * sizes[-1])
    assert sizes[3] < MAX_NODES < sizes[4]  # d (line 8) is within the bound, e (line 9) is not
    assert msg == (f"p.yaml:9: the document stands for more than {MAX_NODES} values once its aliases are expanded: "
                   "write a smaller one")
    f = tmp_path / "laughs.yaml"
    f.write_text(BASE + LAUGHS)
    r = invoke("protocols", "validate", "--schema-only", str(f))
    assert r.exit_code == 3 and r.output.startswith(f"error: {f}:9: the document stands for more than")
    assert "Traceback" not in r.output


def test_description_of_a_hostile_file_in_protocols_list(tmp_path, monkeypatch):
    (tmp_path / "laughs.yaml").write_text(BASE + LAUGHS)
    monkeypatch.setenv("TOUCHBENCH_PROTOCOLS", str(tmp_path))
    r = invoke("protocols", "list")
    assert r.exit_code == 0
    assert [line for line in r.output.splitlines() if "laughs.yaml" in line][0].endswith("(not valid YAML)")


def test_duplicate_keys_are_refused_at_the_second_one():
    assert refused(BASE + "seed: 1\nseed: 2\n") == (
        "p.yaml:6: the key 'seed' is given twice in this mapping (first on line 5): give each key once")
    nested = HEAD + "features: [sd]\nclassifiers:\n  - name: gaus-rf\n    params: {n_estimators: 5, n_estimators: 6}\n"
    assert refused(nested).startswith("p.yaml:6: the key 'n_estimators' is given twice in this mapping (first on line 6)")


def test_merge_keys_still_fill_what_a_mapping_does_not_give():
    data, _ = load_bounded("base: &b {x: 1, y: 2}\nc:\n  <<: *b\n  x: 3\n")
    assert data == {"base": {"x": 1, "y": 2}, "c": {"x": 3, "y": 2}}


def test_recursive_aliases_depth_and_alias_count():
    assert refused(BASE + "description: &d [1, *d]\n") == (
        "p.yaml:5: the alias *d is inside the node it names (a recursive document)")
    deep = BASE + "description: " + "[" * (MAX_DEPTH + 5) + "]" * (MAX_DEPTH + 5) + "\n"
    assert refused(deep) == f"p.yaml:5: nested more than {MAX_DEPTH} levels deep"
    many = BASE + "x: &x 1\ny: [" + ", ".join(["*x"] * (MAX_ALIASES + 1)) + "]\n"
    assert refused(many).startswith(f"p.yaml:6: more than {MAX_ALIASES} aliases (*name)")


def test_a_file_over_the_size_limit_is_refused_before_it_is_read(tmp_path):
    f = tmp_path / "big.yaml"
    f.write_text(BASE + "# " + "x" * MAX_BYTES + "\n")
    size = f.stat().st_size
    with pytest.raises(ProtocolError) as e:
        load_protocol(f)
    assert str(e.value) == f"{f}: the file has {size} bytes: a protocol has at most {MAX_BYTES}"
    assert refused(BASE + "# " + "x" * MAX_BYTES) == f"p.yaml: the file has {size - 1} bytes: at most {MAX_BYTES} are read"


def test_syntax_errors_still_read_as_invalid_yaml():
    assert refused(BASE + "features: [oops\n").startswith("p.yaml:6: invalid YAML:")


# ----------------------------------------------------------------- runaway sizes
def test_a_billion_repetitions_are_refused_at_validation():
    assert refused(BASE + "repetitions: 1000000000\n") == (
        f"p.yaml:5: repetitions: 1000000000 repetitions: at most {MAX_REPETITIONS} (each repeats the whole evaluation)")
    # YAML reads 1e9 (no dot) as a string: refused as not an integer
    assert "p.yaml:5: repetitions: Input should be a valid integer" in refused(BASE + "repetitions: 1e9\n")
    assert parse_protocol(BASE + f"repetitions: {MAX_REPETITIONS}\n", "p.yaml", deep=False).repetitions == MAX_REPETITIONS


def test_a_huge_grid_is_refused_with_its_count_before_anything_expands(monkeypatch):
    values = list(range(1, 901))
    text = HEAD + ("features: [sd, msd]\nclassifiers:\n  - name: gaus-rf\n"
                   f"    params: {{n_estimators: {{grid: {values}}}, max_depth: {{grid: {values}}}}}\n")

    def no_expansion(*a, **k):  # the count comes from the grids' lengths alone
        raise AssertionError("expanded")

    monkeypatch.setattr(schema, "expand_grid", no_expansion)
    monkeypatch.setattr(checks, "expand_grid", no_expansion)
    assert refused(text) == (
        f"p.yaml:6: classifiers[0].params: the protocol expands to {2 * 900 * 900} entries (2 feature combination(s) "
        f"x {900 * 900} classifier entries, grids expanded): at most {MAX_ENTRIES}; this grid gives {900 * 900}: "
        "make the grids smaller or split the protocol")


def test_the_entry_bound_counts_features_classifiers_and_methods():
    k = MAX_ENTRIES // 2 + 1  # two combinations x k classifiers > MAX_ENTRIES, one combination x k is not
    grid = f"{{grid: {list(range(1, k + 1))}}}"
    one = HEAD + f"features: [sd]\nclassifiers:\n  - {{name: gaus-rf, params: {{n_estimators: {grid}}}}}\n"
    assert checks._size_issues(parse_protocol(one, "p.yaml", deep=False)) == []
    two = HEAD + f"features: [sd, msd]\nclassifiers:\n  - {{name: gaus-rf, params: {{n_estimators: {grid}}}}}\n"
    assert f"expands to {2 * k} entries" in refused(two)
    methods = HEAD + f"methods:\n  - {{name: touch-et, params: {{n_estimators: {grid}}}}}\n  - {{name: touch-et, params: {{n_estimators: {grid}}}}}\n"
    assert refused(methods).startswith(f"p.yaml:4: methods[0].params: the protocol expands to {2 * k} entries "
                                       f"(0 feature combination(s) x 0 classifier entries + {2 * k} method entries")


# ----------------------------------------------------------------- parameter values
@pytest.mark.parametrize("value, shown", [("-5", "-5"), ('"many"', "'many'"), ("1e8", "'1e8'"), ("2.5", "2.5")])
def test_feature_set_values_are_checked_at_validation(value, shown):
    text = HEAD + f"features:\n  - [{{name: raw-window, params: {{frames: {value}}}}}]\nclassifiers: [zhou-lda]\n"
    said = (f"p.yaml:4: features[0][0].params.frames: The 'frames' parameter of raw-window must be an int in the "
            f"range [1, inf) or None. Got {shown} instead.")
    if value == "1e8":  # YAML 1.1 reads 1e8 as text: the message says so and how to write the number
        said += " (YAML read '1e8' as a string, not a number: YAML 1.1 reads an exponent as a number only after a dot " \
                "and with a sign; write 1.0e+8)"
    assert refused(text) == said


def test_a_set_that_needs_the_sensor_is_left_to_the_plan():
    # sd takes its thresholds from the sensor's preset: nothing to refuse without the sensor
    assert parse_protocol(HEAD + "features: [sd, touch-rhythm, flagg-stats]\nclassifiers: [zhou-lda]\n", "p.yaml").name
    bad = HEAD + "features:\n  - [{name: touch-rhythm, params: {frame_rate: -3}}]\nclassifiers: [zhou-lda]\n"
    assert refused(bad) == ("p.yaml:4: features[0][0].params.frame_rate: The 'frame_rate' parameter of touch-rhythm "
                            "must be a float in the range (0.0, inf) or None. Got -3 instead.")


def test_inline_method_features_are_checked_too():
    text = HEAD + "methods:\n  - features: [{name: raw-window, params: {frames: 0}}]\n    estimator: zhou-lda\n"
    assert refused(text).startswith("p.yaml:4: methods[0].features[0].params.frames: The 'frames' parameter of "
                                    "raw-window must be an int in the range [1, inf)")


def test_scikit_learn_parameter_validation_without_fitting():
    text = HEAD + "features: [sd]\nclassifiers:\n  - name: gaus-rf\n    params: {n_estimators: -1}\n"
    assert refused(text) == ("p.yaml:6: classifiers[0].params.n_estimators: classifier 'gaus-rf' rejects "
                             "{'n_estimators': -1}: The 'n_estimators' parameter of WekaRandomForestClassifier must "
                             "be an int in the range [1, inf). Got -1 instead.")
    grid = HEAD + "features: [sd]\nclassifiers:\n  - {name: gaus-rf, params: {max_depth: {grid: [3, 0]}}}\n"
    assert "classifiers[0].params.max_depth: classifier 'gaus-rf' rejects {'max_depth': 0}: " \
           "The 'max_depth' parameter" in refused(grid)
    # gaus-rf's own default (max_features 'weka') is outside its parent's constraints: not the user's doing
    assert parse_protocol(HEAD + "features: [sd]\nclassifiers: [gaus-rf]\n", "p.yaml").name


def test_a_missing_extra_is_refused_with_its_install_hint_for_the_methods_that_need_it(monkeypatch):
    monkeypatch.setattr(checks, "missing_extra", lambda extra: ["torch"] if extra == "deep" else [])
    text = HEAD + "features:\n  - [{name: raw-window, params: {frames: 50}}]\nclassifiers: [zhou-lda, cnn]\n"
    proto = parse_protocol(text, "p.yaml")  # reading it needs no extra: running the CNN does
    checks.require_extras(proto, {"zhou-lda"})
    with pytest.raises(ProtocolError) as e:
        checks.require_extras(proto)
    assert str(e.value) == ("p.yaml:5: classifiers[1]: classifier 'cnn' needs the optional 'deep' extra, not "
                            "installed here (torch missing): pip install 'touchbench[deep]'")


class _NoModule:
    """An import finder for which ``names`` are not installed (a core install)."""

    def __init__(self, *names):
        self.names = names

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in self.names:
            raise ModuleNotFoundError(f"No module named {name!r}")
        return None


def test_a_core_install_runs_the_methods_asked_for_and_refuses_the_others_naming_their_extra(tmp_path,
                                                                                             monkeypatch):
    import sys

    import pandas as pd

    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(checks, "missing_extra", lambda extra: ["xgboost"] if extra == "xgboost" else [])
    monkeypatch.setattr(sys, "meta_path", [_NoModule("xgboost"), *sys.meta_path])
    p = tmp_path / "p.yaml"
    p.write_text("name: core\n" + HEAD + "features: [sd]\nclassifiers: [zhou-lda, xgboost]\nseed: 0\n")
    r = CliRunner().invoke(cli, ["run", str(p), "--method", "zhou-lda", "--out", str(tmp_path / "a"), "--jobs", "1",
                                 "--no-progress"])
    assert r.exit_code == 0, r.output
    scores = pd.read_parquet(tmp_path / "a" / "scores.parquet")
    assert set(scores["classifier"]) == {"zhou-lda"} and (scores["status"] == "ok").all()
    r = CliRunner().invoke(cli, ["run", str(p), "--out", str(tmp_path / "b"), "--jobs", "1", "--no-progress"])
    assert r.exit_code == 3, r.output
    assert (f"{p}:5: classifiers[1]: classifier 'xgboost' needs the optional 'xgboost' extra, not installed here "
            "(xgboost missing): pip install 'touchbench[xgboost]'") in r.output
    assert "Traceback" not in r.output and not (tmp_path / "b" / "scores.parquet").exists()


def test_missing_extra_reads_the_installed_metadata(monkeypatch):
    reqs = ["numpy>=1.26", 'surely-not-installed-dist>=1; extra == "deep"', 'numpy>=1; extra == "deep"',
            'another-absent-dist; extra == "peers"']
    monkeypatch.setattr(versions.metadata, "requires", lambda dist: reqs)
    assert versions.missing_extra("deep") == ["surely-not-installed-dist"]
    assert versions.missing_extra("peers") == ["another-absent-dist"]
    assert versions.missing_extra("dist") == []


# ----------------------------------------------------------------- write locations
def test_a_protocol_cannot_choose_where_touchbench_writes(tmp_path):
    target = tmp_path / "elsewhere"
    f = tmp_path / "p.yaml"
    f.write_text(f"dataset:\n  name: haart-sample\n  options: {{cache_dir: {target}}}\n"
                 "scheme: loso\nfeatures: [sd]\nclassifiers: [zhou-lda]\n")
    r = invoke("protocols", "validate", str(f))
    assert r.exit_code == 3
    assert r.output == (f"error: {f}:3: dataset.options.cache_dir: a protocol cannot choose where touchbench writes: "
                        "remove cache_dir; set the TOUCHBENCH_CACHE_DIR environment variable to move the cache\n")
    assert not target.exists()


# ----------------------------------------------------------------- --jobs
@pytest.mark.parametrize("jobs", ["0", "-2", "-50"])
def test_jobs_zero_or_below_minus_one_is_a_usage_error(jobs, tmp_path):
    r = invoke("run", "tiny", "--jobs", jobs, "--out", str(tmp_path / "out"))
    assert r.exit_code == 2
    assert f"Invalid value for '--jobs' / '-j': {jobs} is not a number of parallel tasks" in r.output
    assert not (tmp_path / "out").exists()
    with pytest.raises(TouchbenchError, match=f"--jobs must be a positive number of parallel tasks, or -1 for one "
                                              f"per CPU; got {jobs}"):
        backends.check_jobs(int(jobs))


def test_available_cpus_is_the_affinity_mask():
    expected = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert available_cpus() == expected


def test_jobs_are_capped_at_the_cpus_with_a_warning(monkeypatch):
    monkeypatch.setattr(backends, "available_cpus", lambda: 3)
    assert backends.local_jobs(1000) == (3, "--jobs 1000 is more than the 3 CPU(s) available to this process: "
                                            "running 3 at a time")
    assert backends.local_jobs(-1) == (3, None)
    assert backends.local_jobs(2) == (2, None)
    assert backends.local_jobs(3) == (3, None)


class Recording:
    """joblib.Parallel run in this process, recording the workers asked for."""

    calls: list[int] = []

    def __init__(self, n_jobs, **kwargs):
        self.calls.append(n_jobs)

    def __call__(self, jobs):
        return [f(*a, **k) for f, a, k in jobs]


def test_no_more_workers_than_feature_chunks(tmp_path, monkeypatch):
    monkeypatch.setattr(backends, "Parallel", Recording)
    monkeypatch.setattr(Recording, "calls", calls := [])
    caps = [np.full((3, 2, 2), i, dtype=np.uint16) for i in range(2 * cache.CHUNK + 1)]  # 3 chunks
    [(matrix, _)] = cache.FeatureCache(tmp_path).compute(
        [("k" * 64, partial(make_feature_set, "raw-window", {"frames": 3}, None), {})], caps, jobs=1000)
    assert calls == [3]
    assert matrix.shape == (len(caps), 12) and matrix[-1].tolist() == [2.0 * cache.CHUNK] * 12


def test_no_more_workers_than_tasks(engine_env, monkeypatch):
    monkeypatch.setattr(backends, "Parallel", Recording)
    monkeypatch.setattr(Recording, "calls", calls := [])
    monkeypatch.setattr(backends, "available_cpus", lambda: 64)
    proto = parse_protocol(HEAD + "features: [sd]\nclassifiers: [zhou-lda]\n", "p.yaml")
    plan = runner.plan_run(proto)
    with pytest.warns(RuntimeWarning, match="--jobs 1000 is more than the 64 CPU"):
        res = runner.run_plan(plan, "out", jobs=1000, progress=False)
    assert res.n_ran == len(plan.tasks) and res.n_failed == 0
    assert 1 < len(plan.tasks) < 64 and calls == [len(plan.tasks)]


def test_run_warns_and_caps_jobs(engine_env, monkeypatch):
    monkeypatch.setattr(backends, "available_cpus", lambda: 1)
    with open("p.yaml", "w") as f:  # engine_env: the test's folder is the working directory
        f.write(HEAD + "features: [sd]\nclassifiers: [zhou-lda]\n")
    r = invoke("run", "p.yaml", "--jobs", "1000", "--out", "out", "--no-progress")
    assert r.exit_code == 0, r.output
    assert "warning: --jobs 1000 is more than the 1 CPU(s) available to this process: running 1 at a time" in r.output


# ----------------------------------------------------------------- the parser never crashes
VALID = BASE + "seed: 3\nrepetitions: 2\ndescription: a protocol\n"


def _outcome(text: str) -> None:
    try:
        parse_protocol(text, "p.yaml", deep=False)
    except ProtocolError as e:
        assert str(e).startswith("p.yaml")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=300))
def test_random_text_is_a_protocol_or_one_protocol_error(text):
    _outcome(text)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, len(VALID)), st.integers(0, 6),
                          st.sampled_from(["", "&a ", "*a", "[", "]", "{", "}", ":", "\n", "- ", "  ", "<<: *a", "\t",
                                           "!!python/object:os.system", "? ", "'", '"', "#", "{grid: [1, 2]}", "-1",
                                           "1e9", "%YAML 1.1\n---\n", "...\n", "---\n"])), max_size=5))
def test_mutated_protocols_are_a_protocol_or_one_protocol_error(edits):
    text = VALID
    for at, cut, insert in edits:
        at = min(at, len(text))
        text = text[:at] + insert + text[at + cut:]
    _outcome(text)


values = st.recursive(st.none() | st.booleans() | st.integers(-10, 10**12) | st.floats(allow_nan=True)
                      | st.text(max_size=12),
                      lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
                      max_leaves=20)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.dictionaries(st.sampled_from(["name", "dataset", "scheme", "features", "classifiers", "methods", "seed",
                                        "repetitions", "target", "expected", "description", "other"]),
                       values, max_size=8))
def test_random_documents_are_a_protocol_or_one_protocol_error(doc):
    base = yaml.safe_load(BASE)
    _outcome(yaml.safe_dump({**base, **doc}))


def test_training_one_method_needs_only_its_own_extra(tmp_path, monkeypatch):
    from touchbench.deploy.train import train_from_protocol

    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(checks, "missing_extra", lambda extra: ["xgboost"] if extra == "xgboost" else [])
    p = tmp_path / "p.yaml"
    p.write_text("name: core\n" + HEAD + "features: [sd]\nclassifiers: [zhou-lda, xgboost]\nseed: 0\n")
    assert train_from_protocol(p, "zhou-lda") is not None
    with pytest.raises(ProtocolError, match=r"p.yaml:5: classifiers\[1\]: classifier 'xgboost' needs the optional "
                                            r"'xgboost' extra"):
        train_from_protocol(p, "xgboost")
