"""Cross-dataset transfer on real HAART: the challenge's training subjects (`haart-challenge`) to
another study's recordings read with the raw-format reader; no test capture is ever a training one.

The "other study" is HAART recordings of two challenge test subjects (participants 1 and 9),
copied and renamed as study 150301's participants 31 and 39: so the test captures are known to be
people the training data never saw. A recording of a training subject (participant 3) copied in
the same way must be refused, since it would be tested on what was trained on.
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from touchbench.datasets.model import frames_checksum
from touchbench.engine import run_protocol
from touchbench.engine.planning import plan_run
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import load_protocol

STEMS = ("curvefurpat", "foamfurstroke", "nonenonetickle", "curveshortrub")
TRAINING_SUBJECTS = {"s03", "s04", "s05", "s06", "s07", "s08", "s10"}


def _copy(real_haart_dir, out, participant: int, new: int) -> None:
    folder = out / f"150301-{new}"
    folder.mkdir(parents=True, exist_ok=True)
    for stem in STEMS:  # the organisers' files end in .gz or .csv.gz
        (src,) = (real_haart_dir / "raw" / f"140729-{participant}").glob(f"140729-{participant}{stem}.*")
        shutil.copy(src, folder / f"150301-{new}{stem}{src.name[len(f'140729-{participant}{stem}'):]}")


def _protocol(tmp_path, study):
    p = tmp_path / "to-study.yaml"
    p.write_text(f"""name: to-study
dataset: {{name: haart-challenge, filters: {{split: [train]}}}}
scheme:
  name: cross-dataset
  test: {{name: {study}, format: haart-raw, options: {{recording_window: challenge}}}}
repetitions: 1  # one seed: what is checked here is which captures train and test
methods:
  - {{features: [zhou-basic], estimator: zhou-lda}}
""")
    return p


@pytest.fixture
def env(real_haart_dir, tb_cache, tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tb_cache))
    monkeypatch.chdir(tmp_path)


def test_challenge_training_subjects_to_another_studys_folder(env, real_haart_dir, real_haart_challenge, tmp_path):
    study = tmp_path / "study"
    _copy(real_haart_dir, study, 1, 31)
    _copy(real_haart_dir, study, 9, 39)
    p = _protocol(tmp_path, study)
    plan = plan_run(load_protocol(p))
    (task,) = plan.tasks
    meta = plan.dataset.meta
    train, test = task.fold.train, task.fold.test
    assert len(train) == int((real_haart_challenge.meta["split"] == "train").sum()) == 578
    assert set(meta["subject"].to_numpy()[train]) == TRAINING_SUBJECTS
    assert sorted(set(meta["subject"].to_numpy()[test])) == ["150301-s31", "150301-s39"] and len(test) == 8
    # no test capture is a training capture: by id, and by the frames themselves
    assert not set(meta["capture_id"].to_numpy()[test]) & set(meta["capture_id"].to_numpy()[train])
    train_frames = {frames_checksum(plan.dataset.captures[i]) for i in train}
    assert not {frames_checksum(plan.dataset.captures[i]) for i in test} & train_frames
    # the test captures are the challenge's own frames of those recordings (the same window)
    ch = real_haart_challenge.meta
    s01 = int(np.flatnonzero((ch["subject"] == "s01") & (ch["substrate"] == "curve") & (ch["cover"] == "fur")
                             & (ch["gesture"] == "pat"))[0])
    i = int(np.flatnonzero(meta["capture_id"] == "test:150301-s31-curve-fur-pat")[0])
    np.testing.assert_array_equal(plan.dataset.captures[i], real_haart_challenge.captures[s01])
    res = run_protocol(p, out=tmp_path / "out", progress=False)
    assert res.scores["status"].tolist() == ["ok"] and res.scores["n_test"].tolist() == [8]


def test_a_training_subjects_recording_in_the_test_folder_is_refused(env, real_haart_dir, tmp_path):
    study = tmp_path / "study"
    _copy(real_haart_dir, study, 1, 31)
    _copy(real_haart_dir, study, 3, 33)  # s03 is a challenge training subject
    with pytest.raises(ProtocolError, match="4 test capture\\(s\\) have the frames of a training capture"):
        plan_run(load_protocol(_protocol(tmp_path, study)))
