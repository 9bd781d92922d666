"""Feature-cache rows shared between selections of the same captures (engine/cache.py).

A capture's row depends on the capture, the set and the sensor only, so an entry
for a selection of captures (a table on the training split) takes its rows from
an entry of the whole dataset: the values below are worked out by hand, or
computed without any sharing (another cache folder, each capture alone).
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pandas as pd
import pytest

from touchbench.engine.cache import FeatureCache, capture_digest
from touchbench.engine.runner import run_protocol
from touchbench.features.base import FeatureSet

from helpers import make_set

FAMILY = "f" * 32


class MeanMax(FeatureSet):
    """Each capture's mean and largest value; counts the captures it computes."""

    computed: list[int] = []

    def _transform_batch(self, stack):
        MeanMax.computed.append(len(stack))
        return super()._transform_batch(stack)

    def _transform_one(self, capture):
        return [capture.mean(), capture.max()]

    def feature_names(self, grid):
        return ["mean", "max"]


def capture(k: int, frames: int = 3, dtype=np.uint16) -> np.ndarray:
    """Zeros except 4 k at frame 0, cell (0, 0): mean 4 k / (frames * 4), largest 4 k."""
    c = np.zeros((frames, 2, 2), dtype=dtype)
    c[0, 0, 0] = 4 * k
    return c


def hand(k: int, frames: int = 3) -> list[float]:
    return [4 * k / (frames * 4), 4 * k]


@pytest.fixture
def counted():
    MeanMax.computed = []
    return MeanMax.computed


def entry(key: str, family: str | None = FAMILY):
    return (key, MeanMax, {"family": family} if family else {})


def whole(cache: FeatureCache) -> list[np.ndarray]:
    caps = [capture(k) for k in (1, 2, 3)] + [capture(k, frames=5) for k in (4, 5, 6)]
    cache.compute([entry("whole")], caps)
    return caps


def test_a_selection_takes_every_row_from_the_whole_datasets_entry(tmp_path, counted):
    cache = FeatureCache(tmp_path)
    caps = whole(cache)
    assert sum(counted) == 6
    chosen = [5, 0, 2]  # another order than the whole dataset's
    [(X, info)] = cache.compute([entry("train")], [caps[i] for i in chosen])
    assert sum(counted) == 6  # nothing computed
    assert info["reused_rows"] == 3
    assert np.asarray(X).tolist() == [hand(6, 5), hand(1), hand(3)]
    assert info["columns"] == ["mean", "max"]
    assert cache.load("train") is not None


def test_a_changed_capture_is_computed_and_the_others_taken(tmp_path, counted):
    cache = FeatureCache(tmp_path)
    caps = whole(cache)
    counted.clear()
    changed = caps[1].copy()
    changed[2, 1, 1] = 40  # mean (8 + 40) / 12, largest 40
    [(X, info)] = cache.compute([entry("edited")], [caps[0], changed, caps[4]])
    assert counted == [1]  # the changed capture alone
    assert info["reused_rows"] == 2
    assert np.asarray(X).tolist() == [hand(1), [48 / 12, 40], hand(5, 5)]


def test_rows_of_another_family_another_type_or_an_entry_without_family_are_not_taken(tmp_path, counted):
    cache = FeatureCache(tmp_path)
    caps = whole(cache)
    counted.clear()
    [(X, info)] = cache.compute([entry("other", family="e" * 32)], caps[:2])
    assert sum(counted) == 2 and info["reused_rows"] == 0
    assert np.asarray(X).tolist() == [hand(1), hand(2)]
    counted.clear()
    cache.compute([entry("float", family=FAMILY)], [c.astype(np.float64) for c in caps[:2]])
    assert sum(counted) == 2  # the same values in another type: other captures
    counted.clear()
    cache.compute([entry("plain", family=None)], caps[:2])
    assert sum(counted) == 2
    assert capture_digest(caps[0]) != capture_digest(caps[0].astype(np.float64))


def test_a_damaged_source_is_not_used(tmp_path, counted):
    cache = FeatureCache(tmp_path)
    caps = whole(cache)
    rows = tmp_path / "rows" / FAMILY / "whole.rows"
    data = bytearray(rows.read_bytes())
    data[0] ^= 1  # the first capture's digest no longer matches the entry's checksum of its rows
    rows.write_bytes(bytes(data))
    counted.clear()
    [(X, info)] = cache.compute([entry("again")], caps[:2])
    assert sum(counted) == 2 and info["reused_rows"] == 0
    assert np.asarray(X).tolist() == [hand(1), hand(2)]


def test_sets_of_one_pass_compute_together_the_captures_some_set_lacks(tmp_path, counted):
    cache = FeatureCache(tmp_path)
    caps = whole(cache)
    counted.clear()
    got = cache.compute([entry("a"), entry("b", family="d" * 32)], caps[:2])
    assert counted == [2]  # "a" finds both rows: only "b" is computed
    assert [info["reused_rows"] for _, info in got] == [2, 0]
    counted.clear()
    got = cache.compute([entry("c"), entry("d", family="c" * 32)], [caps[0], capture(7)])
    # "c" lacks the new capture, "d" both: one pass over both captures for both sets
    assert counted == [2, 2] and [info["reused_rows"] for _, info in got] == [0, 0]
    for X, _ in got:
        assert np.asarray(X).tolist() == [hand(1), hand(7)]


# --------------------------------------------------------------- the run engine
PROTOCOL = """name: {name}
dataset:
  name: {data}
{filters}target: gesture
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
    ds.meta["split"] = ["train" if i % 3 else "test" for i in range(len(ds))]
    path = tmp_path / "toy.parquet"
    ds.to_parquet(path)
    return path


def _run(tmp_path, data, name, filtered: bool, out):
    p = tmp_path / f"{name}.yaml"
    p.write_text(PROTOCOL.format(name=name, data=data, filters="  filters:\n    split: [train]\n" if filtered else ""))
    run_protocol(p, out=out, progress=False)
    return pd.read_parquet(out / "scores.parquet").sort_values("task_id").reset_index(drop=True)


def _entries(cache_dir):
    import json

    return {p.stem: json.loads(p.read_text()) for p in (cache_dir / "features").glob("*.json")}


def test_a_filtered_protocol_after_the_whole_dataset_takes_its_rows_with_the_same_scores(tmp_path, monkeypatch):
    data = _toy(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "alone"))
    alone = _run(tmp_path, data, "train-only", True, tmp_path / "r-alone")
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "shared"))
    _run(tmp_path, data, "whole", False, tmp_path / "r-whole")
    shared = _run(tmp_path, data, "train-only", True, tmp_path / "r-shared")
    [filtered] = [e for e in _entries(tmp_path / "shared").values() if e["n_rows"] == 16]
    assert filtered["reused_rows"] == 16  # 16 of the 24 captures are "train"
    [computed] = _entries(tmp_path / "alone").values()
    assert computed["reused_rows"] == 0 and computed["sha256"] == filtered["sha256"]  # the same matrix
    assert alone["task_id"].tolist() == shared["task_id"].tolist()
    for col in ("accuracy", "macro_f1"):
        assert alone[col].tolist() == shared[col].tolist()


# --------------------------------------------------------------- real data
GAUS = ["sd", "bmh", "msd", "smmhh", "lbptop"]


@pytest.mark.realdata
def test_gaus_sets_of_haarts_training_split_equal_the_rows_of_the_whole_and_each_capture_alone(
        real_haart_challenge, tmp_path):
    ds = real_haart_challenge
    split = ds.meta["split"].to_numpy()
    pick = np.r_[np.flatnonzero(split == "train")[:10], np.flatnonzero(split == "test")[:6]]
    caps = [ds.captures[i] for i in pick]
    train = [c for c, i in zip(caps, pick) if split[i] == "train"]

    def entries(prefix):
        return [(f"{prefix}-{n}", partial(make_set, n, ds.sensor), {"family": n * 4}) for n in GAUS]

    shared = FeatureCache(tmp_path / "shared")
    shared.compute(entries("whole"), caps)
    got = shared.compute(entries("train"), train)
    alone = FeatureCache(tmp_path / "alone").compute(entries("train"), train)
    for n, (X, info), (Y, info_alone) in zip(GAUS, got, alone):
        assert info["reused_rows"] == 10 and info_alone["reused_rows"] == 0
        assert np.asarray(X).tobytes() == np.asarray(Y).tobytes(), n  # bit for bit
        one = np.vstack([make_set(n, ds.sensor).fit([c]).transform([c]) for c in train[:3]])
        assert np.asarray(X)[:3].tobytes() == one.tobytes(), n


# --------------------------------------------------------------- several plans of one dataset
def _zhou_protocol(tmp_path, data, name, feature):
    p = tmp_path / f"{name}.yaml"
    p.write_text(PROTOCOL.format(name=name, data=data, filters="").replace("[zhou-basic]", feature))
    return p


def test_plans_of_one_dataset_fill_the_cache_in_one_pass_and_their_runs_find_it(tmp_path, monkeypatch):
    from touchbench.engine.runner import fill_features, plan_protocol
    from touchbench.features import zhou

    data = _toy(tmp_path)
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    a = _zhou_protocol(tmp_path, data, "basic", "[zhou-basic]")
    b = _zhou_protocol(tmp_path, data, "wavelet", "[{name: zhou-wavelet, params: {levels: 4}}]")
    calls = []
    original = zhou.frame_descriptors
    monkeypatch.setattr(zhou, "frame_descriptors", lambda *x: calls.append(1) or original(*x))
    from touchbench.protocols.loading import load_protocol

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


def test_the_sets_of_finished_tasks_are_not_computed_again(tmp_path, monkeypatch):
    from touchbench.engine.runner import fill_features, plan_protocol
    from touchbench.protocols.loading import load_protocol

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
