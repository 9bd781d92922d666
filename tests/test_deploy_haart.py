"""Live recognition of a real HAART capture by a model that never saw its subject.

The capture is fixed by a rule chosen before looking at any result: subject
s01's ``constant`` gesture on the bare sensor (substrate ``none``, cover
``none``), a distinctive gesture (steady pressure) on the plainest
condition. The model: Gaus et al.'s cheap sets ``sd`` + ``msd`` and their
random forest with 100 trees (not 1000, to keep the test short), trained
on 2-second windows of every capture of subjects s02..s10. The capture is
replayed from a Parquet file (as fast as possible) through ``touchbench
stream``; the label emitted most often must be the capture's gesture.
"""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli

CAPTURE = "s01-none-none-constant"

PROTOCOL = """\
name: haart-stream-test
dataset: haart
scheme: loso
features:
  - [sd, msd]
classifiers:
  - {name: gaus-rf, params: {n_estimators: 100}, label: rf100}
seed: 0
"""


@pytest.mark.realdata
@pytest.mark.slow
def test_stream_labels_an_unseen_subjects_capture(real_haart, tmp_path):
    ids = real_haart.meta["capture_id"].tolist()
    assert CAPTURE in ids
    proto = tmp_path / "p.yaml"
    proto.write_text(PROTOCOL)
    model = tmp_path / "m.joblib"
    res = CliRunner().invoke(cli, ["train", str(proto), "--exclude", "subject=s01", "--window", "2",
                                   "--train-hop", "2", "--out", str(model)], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    manifest = json.loads((tmp_path / "m.joblib.json").read_text())
    assert manifest["dataset"]["n_captures"] == int((real_haart.meta["subject"] != "s01").sum())
    assert manifest["dataset"]["by_class"]["constant"] > 0

    one = real_haart.subset([ids.index(CAPTURE)])
    one.to_parquet(tmp_path / "capture.parquet")
    res = CliRunner().invoke(cli, ["stream", str(model), str(tmp_path / "capture.parquet"), "--no-realtime",
                                   "--hop", "0.5", "--jsonl"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    decisions = [json.loads(line) for line in res.stdout.splitlines()]
    # 432 frames, 2-s window = 108 frames, hop 27 frames: (432 - 108) / 27 + 1 = 13 decisions
    assert len(decisions) == 13
    counts = Counter(d["label"] for d in decisions)
    assert counts.most_common(1)[0][0] == "constant", counts
    assert all(np.isfinite(d["latency_ms"]) for d in decisions)

    # every HAART capture: only s01's are scored, the ones the model was trained on are counted apart
    n_s01 = int((real_haart.meta["subject"] == "s01").sum())
    res = CliRunner().invoke(cli, ["predict", str(model), "haart", "--out", str(tmp_path / "p.csv")],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    assert (f"on {n_s01} captures of unseen subjects; {len(real_haart) - n_s01} captures the model was trained on are "
            "not scored" in res.stderr)

    # the challenge release of the same recordings (other frames: another cut, a few values changed): its
    # captures of s02..s10 are of people the model was trained on, and never called unseen
    from touchbench.catalog import load_dataset

    challenge = load_dataset("haart-challenge")
    n_new = int((challenge.meta["subject"] == "s01").sum())
    res = CliRunner().invoke(cli, ["predict", str(model), "haart-challenge", "--out", str(tmp_path / "c.csv")],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    assert f"on {n_new} captures of unseen subjects;" in res.stderr
    assert (f"on {len(challenge) - n_new} captures of subjects the model was trained on (" in res.stderr
            and "this accuracy is not on unseen people" in res.stderr), res.stderr
    assert "unseen captures" not in res.stderr
