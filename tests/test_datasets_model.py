"""The dataset model: Parquet round trip, hashing, validation."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from touchbench.datasets.model import SensorSpec, TouchDataset, concat
from touchbench.core.errors import DataError

from helpers import make_dataset


@pytest.mark.parametrize("dtype", [np.uint16, np.int16, np.float32, np.float64, np.uint8])
def test_parquet_round_trip_keeps_arrays_dtypes_and_hash(tmp_path, dtype):
    ds = make_dataset(frames=(1, 40), dtype=dtype, substrate="foam")
    ds.provenance = {"note": "x"}
    p = ds.to_parquet(tmp_path / "d.parquet")
    back = TouchDataset.from_parquet(p, verify=True)
    assert len(back) == len(ds)
    for a, b in zip(ds.captures, back.captures):
        assert a.dtype == b.dtype and a.shape == b.shape
        np.testing.assert_array_equal(a, b)
    pd.testing.assert_frame_equal(back.meta, ds.meta, check_dtype=False)
    assert back.content_hash == ds.content_hash
    assert back.sensor == ds.sensor
    assert back.provenance == {"note": "x"}
    assert list(tmp_path.iterdir()) == [p]  # no temporary left behind


def test_hash_changes_with_any_value_or_label():
    ds = make_dataset()
    h = ds.content_hash
    caps = [c.copy() for c in ds.captures]
    caps[3][5, 1, 2] += 1
    assert TouchDataset("toy", caps, ds.meta, ds.sensor).content_hash != h
    meta = ds.meta.copy()
    meta.loc[2, "gesture"] = "pat" if meta.loc[2, "gesture"] != "pat" else "stroke"
    assert TouchDataset("toy", ds.captures, meta, ds.sensor).content_hash != h
    # same content under another name: same hash
    assert TouchDataset("other", ds.captures, ds.meta, ds.sensor).content_hash == h
    # dtype is part of the content
    caps32 = [c.astype(np.float32) for c in ds.captures]
    assert TouchDataset("toy", caps32, ds.meta, ds.sensor).content_hash != h


def test_failed_write_leaves_nothing(tmp_path, monkeypatch):
    import touchbench.datasets.model as model

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(model.pq, "write_table", boom)
    with pytest.raises(OSError):
        make_dataset().to_parquet(tmp_path / "d.parquet")
    assert list(tmp_path.iterdir()) == []


def test_bad_files_name_the_file(tmp_path):
    with pytest.raises(DataError, match="nope.parquet"):
        TouchDataset.from_parquet(tmp_path / "nope.parquet")
    junk = tmp_path / "junk.parquet"
    junk.write_bytes(b"not parquet at all")
    with pytest.raises(DataError, match="junk.parquet"):
        TouchDataset.from_parquet(junk)


def test_verify_detects_edited_content(tmp_path):
    import json

    import pyarrow.parquet as pq

    p = make_dataset().to_parquet(tmp_path / "d.parquet")
    t = pq.read_table(p)
    info = json.loads(t.schema.metadata[b"touchbench"])
    info["content_hash"] = "0" * 64
    pq.write_table(t.replace_schema_metadata({b"touchbench": json.dumps(info).encode()}), p)
    with pytest.raises(DataError, match="does not match"):
        TouchDataset.from_parquet(p, verify=True)


def test_a_file_edited_in_place_is_loaded_as_new_data(tmp_path):
    import warnings

    import pyarrow as pa
    import pyarrow.parquet as pq

    from touchbench.datasets.model import DatasetChangedWarning

    ds = make_dataset()
    p = ds.to_parquet(tmp_path / "d.parquet")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an intact file loads without a word
        assert TouchDataset.from_parquet(p).content_hash == ds.content_hash
    # change one capture's label in the file; the stored hash stays the old one
    t = pq.read_table(p)
    gestures = t.column("gesture").to_pylist()
    new_label = next(g for g in sorted(set(gestures)) if g != gestures[0])
    t = t.set_column(t.column_names.index("gesture"), "gesture", pa.array([new_label] + gestures[1:]))
    pq.write_table(t, p)
    meta = ds.meta.copy()
    meta.loc[0, "gesture"] = new_label
    edited = TouchDataset(ds.name, ds.captures, meta, ds.sensor)
    with pytest.warns(DatasetChangedWarning, match="d.parquet: the content changed since"):
        back = TouchDataset.from_parquet(p)
    assert back.content_hash == edited.content_hash != ds.content_hash


def test_validation_of_shapes_and_ids():
    sensor = SensorSpec("s", (2, 3), 10.0)
    meta = pd.DataFrame({"capture_id": ["a", "b"], "subject": ["x", "x"], "gesture": ["g", "g"]})
    with pytest.raises(ValueError, match="expects"):
        TouchDataset("d", [np.zeros((4, 2, 3)), np.zeros((4, 3, 2))], meta, sensor)
    with pytest.raises(ValueError, match="more than once"):
        TouchDataset("d", [np.zeros((4, 2, 3))] * 2, meta.assign(capture_id=["a", "a"]), sensor)
    with pytest.raises(ValueError, match="lacks"):
        TouchDataset("d", [np.zeros((4, 2, 3))] * 2, meta.drop(columns="subject"), sensor)
    with pytest.raises(ValueError, match="channel sensor"):
        SensorSpec("fur", (1, 3), 50.0, channels=("x", "y", "pressure", "fur"))
    assert SensorSpec("fur", (1, 4), 50.0, channels=("x", "y", "pressure", "fur")).n_cells == 4


def test_subset_and_concat():
    ds = make_dataset()
    sub = ds.subset([3, 1])
    assert list(sub.meta["capture_id"]) == [ds.meta["capture_id"][3], ds.meta["capture_id"][1]]
    np.testing.assert_array_equal(sub.captures[0], ds.captures[3])
    both = concat([ds.subset([0]), ds.subset([1, 2])], "c")
    assert list(both.meta["capture_id"]) == list(ds.meta["capture_id"][:3])


def test_info_counts():
    ds = make_dataset(n_subjects=2, gestures=("a", "b", "c"), reps=2, frames=7)
    inf = ds.info()
    assert inf["captures"] == 12 and inf["subjects"] == 2 and inf["gestures"] == 3
    assert inf["frames_per_capture"] == {"min": 7, "median": 7.0, "max": 7}
    assert inf["by_gesture"] == {"a": 4, "b": 4, "c": 4}


@pytest.mark.parametrize("rate, value_range", [(float("inf"), (0, 255)), (float("nan"), (0, 255)), (0.0, (0, 255)),
                                               (10.0, (0.0, float("inf"))), (10.0, (float("-inf"), 1.0))])
def test_a_sensor_needs_a_finite_frame_rate_and_value_range(rate, value_range):
    with pytest.raises(ValueError, match="must be positive|must have low < high"):
        SensorSpec("s", (2, 2), rate, value_range)
