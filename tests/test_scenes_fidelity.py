"""How faithful a scene is to real data (touchbench.scoring.fidelity)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.scoring.fidelity import _folds, capture_metrics, compare_distributions


def test_capture_metrics_by_hand():
    # 4 frames of 3 x 3 at 10 frames/s, threshold 10
    c = np.zeros((4, 3, 3))
    c[0, 0, 0] = 30  # one cell: centroid (0, 0)
    c[1, 0, 2] = 30  # moves 2 cells in x
    c[2, 2, 2] = 30  # moves 2 cells in y
    c[3] = 5  # everything below the threshold: no contact
    total, area, speed = capture_metrics(c, frame_rate=10.0, threshold=10.0)
    assert total == pytest.approx((30 + 30 + 30 + 45) / 4)
    assert area == pytest.approx(3 / 4)
    # two steps of 2 cells between contact frames, 10 frames/s
    assert speed == pytest.approx(20.0)


def test_capture_metrics_weights_above_threshold():
    c = np.zeros((2, 1, 3))
    c[:, 0, 0] = 20  # weight 10
    c[0, 0, 2] = 20  # weight 10: centroid x = 1 in frame 0
    c[1, 0, 2] = 40  # weight 30: centroid x = (0*10 + 2*30) / 40 = 1.5
    _, area, speed = capture_metrics(c, frame_rate=2.0, threshold=10.0)
    assert area == 2.0
    assert speed == pytest.approx(0.5 * 2.0)


def test_no_contact_has_zero_speed():
    assert capture_metrics(np.full((5, 2, 2), 3.0), 54.0) == (12.0, 0.0, 0.0)


def test_compare_distributions():
    real = pd.DataFrame({"gesture": ["a"] * 5, "total": [1, 2, 3, 4, 5], "area": [0, 0, 1, 1, 1], "speed": [1.0] * 5})
    synth = pd.DataFrame({"gesture": ["a"] * 3, "total": [3.5, 4.5, 9], "area": [2, 2, 2], "speed": [1.0] * 3})
    d = compare_distributions(real, synth).set_index("metric")
    # real total quartiles 2, 3, 4; scene median 4.5: outside
    assert d.loc["total", ["real_q25", "real_median", "real_q75", "scene_median"]].tolist() == [2, 3, 4, 4.5]
    assert not d.loc["total", "within_iqr"]
    assert not d.loc["area", "within_iqr"] and d.loc["speed", "within_iqr"]


def test_folds():
    meta = pd.DataFrame({"subject": ["a", "a", "b", "c", "c"], "gesture": list("xyxyx"), "split": ["train", "train", "test", "none", "train"]})
    loso = _folds(meta, "loso", 0)
    assert [te.tolist() for _, te in loso] == [[0, 1], [2], [3, 4]]
    (tr, te), = _folds(meta, "challenge", 0)
    assert tr.tolist() == [0, 1, 4] and te.tolist() == [2]
    # more folds than subjects: one per subject
    assert len(_folds(meta, "subject-kfold:5", 0)) == 3
    with pytest.raises(ValueError, match="unknown scheme"):
        _folds(meta, "bootstrap", 0)


@pytest.mark.realdata
def test_haart_like_medians_within_the_real_iqr(real_haart):
    """The calibration target: every per-gesture median of haart-like within the
    real interquartile range (total pressure, contact area, centroid speed)."""
    from touchbench.scenes import generate_scene
    from touchbench.scoring.fidelity import metric_table

    d = compare_distributions(metric_table(real_haart), metric_table(generate_scene("haart-like")))
    assert len(d) == 21
    out = d.loc[~d["within_iqr"], ["gesture", "metric", "real_q25", "real_q75", "scene_median"]]
    assert out.empty, out.to_string()
