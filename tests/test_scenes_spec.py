"""Scene YAML validation: every error names the field (touchbench.scenes.spec)."""

from __future__ import annotations

import copy

import pytest
import yaml

from snapshots.registries import snapshot

from touchbench.core.errors import DataError, UnknownNameError
from touchbench.scenes import SCENES, SPECS_DIR, generate_scene, load_scene
from touchbench.scenes.loading import parse_spec
from touchbench.scenes.spec import n_captures, property_value, subject_ids


def tiny_raw():
    return yaml.safe_load((SPECS_DIR / "tiny.yaml").read_text())


def haart_raw():
    return yaml.safe_load((SPECS_DIR / "haart-like.yaml").read_text())


def refused(raw, match):
    with pytest.raises(DataError, match=match):
        parse_spec(raw, "scene.yaml")


def test_shipped_scenes_are_registered_and_valid():
    assert SCENES.names() == snapshot()["scenes"] == ["cost-like", "fur-like", "haart-like", "tiny", "tpm-like"]
    for name in SCENES.names():
        spec = load_scene(name)
        assert spec.name == name
        assert SCENES.entry(name).description


@pytest.mark.parametrize(
    "name,expected",
    [("cost-like", 7805), ("tpm-like", 24 * 2 * 7 * 16 + 5 * 7 * 16), ("fur-like", 16 * 9 * 25), ("haart-like", 840), ("tiny", 32)],
)
def test_shipped_scene_sizes_are_those_of_the_real_datasets(name, expected):
    spec = load_scene(name)
    assert n_captures(spec) - spec.protocol.lost == expected


def test_shipped_scene_facts():
    cost = load_scene("cost-like")
    assert (len(cost.gestures), cost.protocol.repetitions, len(cost.protocol.variants)) == (14, 6, 3)
    assert cost.sensor.frame_rate == 135 and tuple(cost.sensor.grid) == (8, 8) and cost.sensor.curvature is not None
    assert (cost.protocol.segmentation.min_s, cost.protocol.segmentation.max_s) == (0.075, 9.6)
    tpm = load_scene("tpm-like")
    assert tuple(tpm.sensor.grid) == (20, 20) and tpm.sensor.frame_rate == 50 and len(tpm.gestures) == 7
    assert tpm.protocol.groups["A"].instructions["scratch"]["cycles"] == 3
    fur = load_scene("fur-like")
    assert fur.sensor.channels == ["x", "y", "pressure", "fur"] and fur.sensor.frame_rate == 50
    assert fur.protocol.segmentation.frames == 100 and len(fur.gestures) == 9
    haart = load_scene("haart-like")
    assert (len(haart.protocol.substrates), len(haart.protocol.covers)) == (3, 4)
    assert haart.protocol.segmentation.frames == 432 and haart.sensor.frame_rate == 54


def test_subject_ids_follow_haart():
    assert subject_ids(load_scene("haart-like")) == [f"s{i:02d}" for i in range(1, 11)]


def test_a_scene_models_only_what_it_lists():
    # a cover block without the cover effect, and the reverse
    raw = haart_raw()
    raw["effects"].remove("cover")
    refused(raw, r"protocol\.covers: given, but effect 'cover' is not listed")
    raw = tiny_raw()
    raw["effects"].append("substrate")
    refused(raw, r"effects: 'substrate' is listed but protocol\.substrates is not given")
    raw = tiny_raw()
    raw["effects"].append("curvature")
    refused(raw, r"'curvature' is listed but neither sensor\.curvature")
    raw = tiny_raw()
    raw["protocol"]["sessions"] = 2
    refused(raw, r"protocol\.sessions: more than one session, but effect 'session'")
    raw = tiny_raw()
    raw["effects"].append("session")
    refused(raw, r"'session' is listed but every subject has one session")
    raw = tiny_raw()
    raw["effects"].remove("noise")
    refused(raw, r"sensor\.noise_sd: given, but effect 'noise'")


def test_errors_name_the_field():
    raw = tiny_raw()
    raw["protocol"]["covers"] = {"fur": {"transmission": 1.5}}
    raw["effects"].append("cover")
    refused(raw, r"protocol\.covers\.fur\.transmission")
    raw = tiny_raw()
    raw["gestures"]["pat"] = {"force_n": -1}
    refused(raw, r"gestures\.pat\.force_n: must be positive")
    raw = tiny_raw()
    raw["gestures"]["pat"] = {"forse_n": 3}
    refused(raw, r"gestures\.pat\.forse_n: unknown gesture parameter")
    raw = tiny_raw()
    raw["gestures"]["strok"] = None
    refused(raw, r"strok: unknown gesture; did you mean stroke")
    raw = haart_raw()
    raw["protocol"]["substrates"]["foam"]["tension"] = 2.0
    refused(raw, r"protocol\.substrates\.foam: .*only a curved substrate")
    raw = tiny_raw()
    del raw["sensor"]["gain"]
    refused(raw, r"sensor: .*a grid sensor needs its gain")
    raw = tiny_raw()
    raw["sensor"]["grid"] = [0, 8]
    refused(raw, r"sensor\.grid")
    raw = tiny_raw()
    raw["effects"].append("wind")
    refused(raw, r"effects\.3: Input should be 'style'.*got 'wind'")
    raw = tiny_raw()
    raw["protocol"]["segmentation"] = {"mode": "fixed"}
    refused(raw, r"frames: a fixed segmentation needs the window length")
    raw = tiny_raw()
    raw["sensorr"] = raw.pop("sensor")
    refused(raw, r"sensor: Field required.*sensorr: Extra inputs are not permitted")


def test_split_and_groups_are_checked():
    raw = haart_raw()
    raw["protocol"]["split"]["test"].append("s11")
    refused(raw, r"protocol\.split: unknown subjects \['s11'\]")
    raw = haart_raw()
    raw["protocol"]["split"]["test"].append("s03")
    refused(raw, r"subjects \['s03'\] are in both train and test")
    raw = yaml.safe_load((SPECS_DIR / "tpm-like.yaml").read_text())
    raw["protocol"]["groups"]["A"]["instructions"]["pat"] = {"cycles": 3}
    refused(raw, r"protocol\.groups\.A\.instructions\.pat: not one of the scene's gestures")
    raw = yaml.safe_load((SPECS_DIR / "tpm-like.yaml").read_text())
    raw["protocol"]["groups"]["A"]["instructions"]["stroke"] = {"cycles": 0}
    refused(raw, r"instructions\.stroke\.cycles: must be a whole number")


def test_channel_sensor_rules():
    raw = yaml.safe_load((SPECS_DIR / "fur-like.yaml").read_text())
    bad = copy.deepcopy(raw)
    bad["sensor"]["channels"] = ["x", "y", "pressure"]
    refused(bad, r"channels: a channel sensor has channels")
    bad = copy.deepcopy(raw)
    bad["sensor"]["gain"] = 5.0
    refused(bad, r"gain: a channel sensor's gains are in its response")
    bad = copy.deepcopy(raw)
    bad["effects"].append("crosstalk")
    bad["sensor"]["crosstalk"] = 0.05
    refused(bad, r"crosstalk and curvature apply to grid sensors only")
    bad = copy.deepcopy(raw)
    bad["sensor"]["response"]["rest"].pop("fur")
    refused(bad, r"sensor\.response\.rest: .*missing \['fur'\]")


def test_file_errors_name_file_and_line(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("name: x\ndescription: y\neffects: [noise\n")
    with pytest.raises(DataError, match=r"bad\.yaml:\d+: invalid YAML"):
        load_scene(p)
    raw = tiny_raw()
    raw["protocol"]["repetitions"] = 0
    p.write_text(yaml.safe_dump(raw, sort_keys=False))
    with pytest.raises(DataError, match=r"bad\.yaml:\d+: invalid scene: protocol\.repetitions"):
        load_scene(p)
    with pytest.raises(DataError, match="no such scene file"):
        load_scene(tmp_path / "missing.yaml")


def test_unknown_scene_name_suggests_the_nearest():
    with pytest.raises(UnknownNameError, match="did you mean 'haart-like'"):
        generate_scene("haart-lik")


def test_overrides():
    spec = load_scene("cost-like", subjects=3, repetitions=2, gestures=["pat", "rub"])
    assert spec.population.subjects == 3 and spec.protocol.repetitions == 2
    assert list(spec.gestures) == ["pat", "rub"] and spec.gestures["rub"]["osc_hz"] == 2.0
    assert spec.protocol.split.train == ["s01", "s02", "s03"] and spec.protocol.split.test == []
    spec = load_scene("tiny", protocol__segmentation__frames=20, **{"sensor.noise_sd": 2.0})
    assert spec.protocol.segmentation.frames == 20 and spec.sensor.noise_sd == 2.0
    with pytest.raises(DataError, match="protocol.repetitions"):
        load_scene("tiny", repetitions=-1)


def test_a_calibrated_property_must_be_one_the_scene_has():
    cal = {"table": "T3", "protocols": ["p"], "measured_by": "touchbench run x.yaml"}
    raw = tiny_raw()
    raw["population"]["style"] = {"sd": 0.4}
    raw["calibrated"] = {"population.style.sd": cal}
    spec = parse_spec(raw, "scene.yaml")
    assert property_value(spec, "population.style.sd") == 0.4
    assert spec.calibrated["population.style.sd"].protocols == ["p"]
    raw["calibrated"] = {"population.style.sdd": cal}
    refused(raw, r"calibrated\.population\.style\.sdd: the scene has no such property")
    raw["calibrated"] = {"style": cal}
    refused(raw, r"style: a property's dotted path")
    raw["calibrated"] = {"population.style.sd": {**cal, "protocols": []}}
    refused(raw, r"calibrated\.population\.style\.sd\.protocols")
