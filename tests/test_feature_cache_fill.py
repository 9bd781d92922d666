"""Several plans of one dataset fill the feature cache together (engine.runner.fill_features), as
``papers reproduce`` does for the protocols of one dataset: one pass, the same matrices bit for bit
as each protocol's run computes alone, and nothing for a finished task; a task an earlier protocol
of the run finished is taken from its folder."""

from __future__ import annotations

import json

import pandas as pd

from touchbench.engine.runner import fill_features, plan_protocol, run_protocol
from touchbench.protocols.loading import load_protocol

PROTOCOL = """name: {name}
dataset: {data}
target: gesture
scheme:
  name: kfold
  k: 2
features:
  - [zhou-basic]
classifiers:
  - {{name: zhou-knn, params: {{n_neighbors: 1}}}}
seed: 0
"""


def _toy(tmp_path):
    from helpers import make_dataset

    ds = make_dataset(n_subjects=3, reps=4, frames=(12, 20), grid=(4, 4))
    path = tmp_path / "toy.parquet"
    ds.to_parquet(path)
    return path


def _zhou_protocol(tmp_path, data, name, feature):
    p = tmp_path / f"{name}.yaml"
    p.write_text(PROTOCOL.format(name=name, data=data).replace("[zhou-basic]", feature))
    return p


def _matrices(cache):
    return {p.name: p.read_bytes() for p in (cache / "features").glob("*.npy")}


def test_plans_of_one_dataset_fill_the_cache_in_one_pass_and_their_runs_find_it(tmp_path, monkeypatch):
    from touchbench.features import zhou

    data = _toy(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    a = _zhou_protocol(tmp_path, data, "basic", "[zhou-basic]")
    b = _zhou_protocol(tmp_path, data, "wavelet", "[{name: zhou-wavelet, params: {levels: 4}}]")
    calls = []
    original = zhou.frame_descriptors
    monkeypatch.setattr(zhou, "frame_descriptors", lambda *x: calls.append(1) or original(*x))
    one = plan_protocol(load_protocol(a), tmp_path / "r-basic")
    fill_features(one, progress=False, jobs=1)
    per_pass = len(calls)  # one per batch of captures of one length
    assert per_pass >= 2
    plans = one + plan_protocol(load_protocol(b), tmp_path / "r-wavelet")
    calls.clear()
    fill_features(plans, progress=False, jobs=1)
    assert len(calls) == per_pass  # the wavelet set alone was missing: one pass
    filled = {p.name: p.read_text() for p in (tmp_path / "cache" / "features").glob("*.json")}
    assert len(filled) == 2
    run_protocol(a, out=tmp_path / "r-basic", progress=False)
    run_protocol(b, out=tmp_path / "r-wavelet", progress=False)
    after = {p.name: p.read_text() for p in (tmp_path / "cache" / "features").glob("*.json")}
    assert after == filled  # each run found its entries: none written again
    # the same matrices, bit for bit, as each protocol's run computes alone
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "alone"))
    run_protocol(a, out=tmp_path / "alone-basic", progress=False)
    run_protocol(b, out=tmp_path / "alone-wavelet", progress=False)
    assert _matrices(tmp_path / "alone") == _matrices(tmp_path / "cache")


def test_the_sets_of_finished_tasks_are_not_computed_again(tmp_path, monkeypatch):
    data = _toy(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    a = _zhou_protocol(tmp_path, data, "basic", "[zhou-basic]")
    run_protocol(a, out=tmp_path / "r", progress=False)
    for f in (tmp_path / "cache" / "features").glob("*.*"):
        f.unlink()
    fill_features(plan_protocol(load_protocol(a), tmp_path / "r"), progress=False)
    assert not list((tmp_path / "cache" / "features").glob("*.json"))  # every task finished
    fill_features(plan_protocol(load_protocol(a), tmp_path / "elsewhere"), progress=False)
    assert len(list((tmp_path / "cache" / "features").glob("*.json"))) == 1


def test_papers_reproduce_fills_the_cache_once_for_the_protocols_of_one_dataset(tmp_path, monkeypatch):
    import touchbench.papers.reproduce as R

    data = _toy(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    d = tmp_path / "papers"
    d.mkdir()
    expected = ("expected:\n  metric: accuracy\n  tolerance: 100.0\n  results:\n"
                "    - {features: [zhou-basic], classifier: zhou-knn, value: 50.0, source: made up}\n")
    for name in ("zhou-one", "zhou-two"):
        (d / f"{name}.yaml").write_text(PROTOCOL.format(name=name, data=data) + expected)
    calls = []
    original = R.fill_features
    monkeypatch.setattr(R, "fill_features", lambda plans, **kw: calls.append(
        sorted(p.protocol.name for p, _ in plans)) or original(plans, **kw))
    R.reproduce("quick", tmp_path / "res", protocols_dir=d, echo=lambda s: None)
    assert calls == [["zhou-one", "zhou-two"]]  # once, before the first of them ran
    for name in ("zhou-one", "zhou-two"):
        assert (tmp_path / "res" / "quick" / name / "scores.parquet").is_file()
    # the two protocols hold the same tasks: the second takes them from the first's folder
    two = json.loads((tmp_path / "res" / "quick" / "zhou-two" / "manifest.json").read_text())
    assert two["sessions"][-1]["ran"] == 0 and any("zhou-one" in n for n in two["notes"]), two["notes"]
    one_scores, two_scores = (pd.read_parquet(tmp_path / "res" / "quick" / n / "scores.parquet")
                              for n in ("zhou-one", "zhou-two"))
    assert len(two_scores) == 2 and (two_scores["protocol"] == "zhou-two").all()
    cols = ["task_id", "accuracy", "macro_f1"]
    pd.testing.assert_frame_equal(one_scores[cols], two_scores[cols], check_exact=True)
