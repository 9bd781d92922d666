"""What the Dask and Ray tests share (no tests here): a small LOSO protocol
over real feature sets and classifiers, its data, and the comparison of two
runs' results."""

from __future__ import annotations

import pandas as pd
import pytest

from touchbench.engine.testing import random_dataset
from touchbench.protocols.loading import parse_protocol

PROTOCOL = """\
name: dist-small
dataset: {data}
scheme: loso
features:
  - [msd]
  - [{{name: sd, params: {{preset: haart}}}}, {{name: bmh, params: {{preset: haart}}}}]
{extra}classifiers:
  - {{name: gaus-rf, params: {{n_estimators: 20}}, label: rf20}}
  - zhou-knn
seed: 11
"""
METRICS = ["accuracy", "balanced_accuracy", "macro_f1", "n_train", "n_test", "status", "seed"]
KEY = ["task_id", "capture_id"]


@pytest.fixture()
def env(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    # 36 captures: the feature cache is computed in two chunks of 32, in parallel too
    random_dataset(subjects=("s1", "s2", "s3"), per_cell=4, frames=(16, 20)).to_parquet(tmp_path / "data.parquet")
    return tmp_path


def write_protocol(tmp_path, extra=""):
    text = PROTOCOL.format(data=tmp_path / "data.parquet", extra=extra)
    (tmp_path / "p.yaml").write_text(text)
    return parse_protocol(text, tmp_path / "p.yaml")


def assert_same_results(a, b):
    """Same predictions and probabilities (bit for bit) and the same scores."""
    pa = pd.read_parquet(a / "predictions.parquet").sort_values(KEY).reset_index(drop=True)
    pb = pd.read_parquet(b / "predictions.parquet").sort_values(KEY).reset_index(drop=True)
    assert len(pa) > 0
    pd.testing.assert_frame_equal(pa, pb)
    sa = pd.read_parquet(a / "scores.parquet").sort_values("task_id").reset_index(drop=True)
    sb = pd.read_parquet(b / "scores.parquet").sort_values("task_id").reset_index(drop=True)
    pd.testing.assert_frame_equal(sa[["task_id"] + METRICS], sb[["task_id"] + METRICS])
    assert (sa["status"] == "ok").all()
