"""The engine on the real HAART recordings (needs ../shared/data; fails under CI=true without it)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.engine import run_protocol
from touchbench.protocols.loading import parse_protocol

pytestmark = pytest.mark.realdata

TEXT = """\
name: real-small
dataset:
  name: haart
  filters:
    subject: [s01, s02, s03]
    gesture: [constant, notouch, pat, scratch]
scheme: loso
features:
  - [msd]
classifiers:
  - {name: gaus-rf, params: {n_estimators: 20}}
seed: 0
"""


def test_loso_on_real_haart_subset(real_haart, tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    p = parse_protocol(TEXT, tmp_path / "real-small.yaml")
    res = run_protocol(p, out=tmp_path / "out", dataset=real_haart, progress=False)
    keep = real_haart.meta["subject"].isin(["s01", "s02", "s03"]) & real_haart.meta["gesture"].isin(
        ["constant", "notouch", "pat", "scratch"])
    n = int(keep.sum())
    assert n == 3 * 4 * 12 - 1  # s02's none/fur/constant is a placeholder copy (data README)
    assert list(res.scores["fold"]) == ["subject=s01", "subject=s02", "subject=s03"]
    assert res.scores["n_test"].sum() == n and (res.scores["status"] == "ok").all()
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")
    assert preds["capture_id"].is_unique and len(preds) == n
    # no subject is both trained and tested: each fold's test captures are one subject
    assert (preds.groupby("fold")["subject"].nunique() == 1).all()
    # constant and notouch are easy (Gaus Table 6): well above chance (25 %) overall
    assert np.mean(preds["true_label"] == preds["predicted_label"]) > 0.5
    again = run_protocol(p, out=tmp_path / "out", dataset=real_haart, progress=False)
    assert again.noop
