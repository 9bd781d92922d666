"""A small protocol of each newer peer (MultiRocket-Hydra, QUANT, RDST, InceptionTime) through the run engine.

On two subjects of the synthetic ``tiny`` scene, leave one subject out, each peer with the
small settings its registry entry declares: every task finishes ``ok``,
predicts a class the training fold holds for every test capture, and the
method's latency is measured in its first task, as for every other
method. The peers need the ``peers`` and ``deep`` extras, which CI
installs: there a missing one fails, elsewhere these tests skip.
"""

from __future__ import annotations

import os

import pandas as pd
import pytest

if os.environ.get("CI", "").lower() == "true":
    import aeon  # noqa: F401
    import torch  # noqa: F401
else:
    pytest.importorskip("aeon")
    pytest.importorskip("torch")

from touchbench.classifiers import CLASSIFIERS  # noqa: E402
from touchbench.engine import run_protocol  # noqa: E402

PEERS = ["multirocket-hydra", "quant", "rdst", "inception-time"]


@pytest.fixture(autouse=True)
def env(engine_env):
    yield


def _flow(params: dict) -> str:
    return "{" + ", ".join(f"{k}: {list(v) if isinstance(v, tuple) else v}" for k, v in params.items()) + "}"


@pytest.mark.parametrize("name", PEERS)
def test_peer_runs_through_the_engine(tmp_path, name):
    cheap = CLASSIFIERS.entry(name).tags.get("cheap_params", {})
    p = tmp_path / "smoke.yaml"
    # two of the scene's four subjects: two tasks, the first one measuring the latency
    p.write_text(f"name: smoke\ndataset: {{name: scene:tiny, filters: {{subject: [s01, s02]}}}}\nscheme: loso\n"
                 f"methods:\n  - {{name: {name}, params: {_flow(cheap)}}}\n")
    res = run_protocol(p, out=tmp_path / "results", progress=False)
    scores = res.scores
    assert (scores["status"] == "ok").all(), scores["error"].tolist()
    assert scores["classifier_name"].unique().tolist() == [name]
    assert scores["latency_ms"].notna().sum() == 1  # measured once per method, in its first task
    preds = pd.read_parquet(res.out / "predictions.parquet")
    assert len(preds) == int(scores["n_test"].sum())
    assert set(preds["predicted_label"]) <= set(preds["gesture"]) and (preds["true_label"] == preds["gesture"]).all()
