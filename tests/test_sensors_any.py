"""Every component on sensors that are not HAART's: it uses that sensor's grid
and frame rate, or the protocol is refused before any task with a message
naming the component, the sensor and the reason.

Four small synthetic datasets (12 captures each): a 6 x 6 grid at 20 Hz, a
1 x 16 channel sensor at 25 Hz, a 19 x 24 grid at 12 Hz with ragged lengths
(3..60 frames) and a 32 x 32 grid at 10 Hz. Expected output sizes are
worked out by hand for each grid (below); which component refuses which
sensor, and why, is listed in ``REFUSED``. A registered feature set or
classifier missing from the tables fails the test: nothing is skipped
silently. A last test reads the package's code (ast) for HAART's numbers
(432 frames, 54 Hz, an 8 x 8 grid) used as defaults.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import touchbench
from touchbench.classifiers import CLASSIFIERS, make_classifier
from touchbench.cli.main import cli
from touchbench.core.introspect import sensor_problem
from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.engine.planning import plan_run
from touchbench.engine.testing import random_dataset
from touchbench.features.base import FEATURES, FeatureInputError, make_feature_set
from touchbench.methods import METHODS, FeaturePipeline, method_spec
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol

SENSORS = {
    "6x6": (SensorSpec("grid-6x6", (6, 6), 20.0, (0, 255)), (40, 60)),
    "1x16": (SensorSpec("strip-16", (1, 16), 25.0, (0, 1023), channels=tuple(f"c{i}" for i in range(16))), (50, 70)),
    "19x24": (SensorSpec("wide-19x24", (19, 24), 12.0, (0, 4095)), (3, 60)),
    "32x32": (SensorSpec("big-32x32", (32, 32), 10.0, (0, 255)), (20, 24)),
}
#: the ragged dataset's capture lengths (its shortest and longest are the stated 3 and 60)
RAGGED = (3, 60, 12, 41, 7, 33, 25, 50, 18, 9, 44, 30)


@functools.cache
def dataset(key: str) -> TouchDataset:
    sensor, frames = SENSORS[key]
    if key == "19x24":
        frames = (max(RAGGED), max(RAGGED))  # then cut to the RAGGED lengths
    ds = random_dataset(subjects=("s1", "s2"), gestures=("pat", "rub"), per_cell=3, frames=frames, sensor=sensor, seed=1)
    if key == "19x24":
        ds = TouchDataset(ds.name, [c[:n] for c, n in zip(ds.captures, RAGGED)], ds.meta, sensor)
    return ds


def shortest(ds: TouchDataset) -> int:
    return int(ds.n_frames.min())


def pyramid_cells(grid: tuple[int, int]) -> int:
    """Cells of smmhh's scales down to 1 x 1, each halving the sides with ceil
    (6x6: 36 + 9 + 4 + 1 = 50; 19x24: 456 + 120 + 30 + 9 + 4 + 1 = 620)."""
    h, w = grid
    total = h * w
    while (h, w) != (1, 1):
        h, w = -(-h // 2), -(-w // 2)
        total += h * w
    return total


def expected_size(name: str, sensor: SensorSpec, frames: int) -> int:
    """Output size worked out by hand from each set's definition (see its docstring)."""
    h, w = sensor.grid
    cells = h * w
    own = {"touch-rhythm": 11 * 35 + 7 + 3 * 8 + 2, "cell-rhythm": 9 + 11, "contact-motion": 3 * (12 + 4 + 2) + 1}
    sizes = {
        "sd": 12 + 12 + 14 + 12 + 12,  # HAART's Table 4 bins, scaled to the grid: as many bins on any grid
        "bmh": cells,
        "msd": 12 * cells,
        "smmhh": 5 * 5 * pyramid_cells(sensor.grid),  # 5 skips x 5 run lengths per pooled cell
        "lbptop": 3 * 59,
        "zhou-basic": 5 * 6,
        "zhou-wavelet": 6 * 39,
        "flagg-stats": 7 * len(sensor.channels) if sensor.channels else 7 * 4,
        "raw-window": frames * cells,
        **own,
        "touch-windows": 2 * sum(own.values()),
        "contact-evidence": 6 + 3 * 3 + 4,  # 6 levels, 3 counts at each of 3 noise units, 4 ratios
        "live-summary": 9 * 7 + 1,  # 9 frame-level series x 7 statistics, and the window in seconds
        "example-pressure-stats": 4,  # the example plugin: mean, sd, min, max of the per-frame mean pressure
    }
    assert name in sizes, f"feature set {name!r}: add its size for any grid to this test"
    return sizes[name]


#: (component, sensor) -> what the refusal must say
REFUSED: dict[tuple[str, str], str] = {
    **{(n, "1x16"): r"is a channel sensor \(c0, .*not cells of a pressure surface"
       for n in ("sd", "bmh", "smmhh", "contact-evidence", "touch-et-contact", "touch-et-adapt",
                 "shift-augmented", "touch-et-shift", "touch-rocket-fusion", "quiet-gated", "touch-et-quiet", "touch-et-quiet-win",
                 "two-stage", "touch-live", "touch-live-fast", "live-summary")},
    ("touch-windows", "19x24"): r"2-s windows \(24 frames at 12 Hz\) are longer than the shortest capture \(3 frames\)",
    ("touch-et-win", "19x24"): r"2-s windows \(24 frames at 12 Hz\) are longer than the shortest capture \(3 frames\)",
    ("cnn", "19x24"): r"L=30 windows need captures of at least 30 frames.*the shortest has 3",
    ("cnn", "32x32"): r"L=30 windows need captures of at least 30 frames.*the shortest has 20",
}
#: the classifiers that read raw frames: they record the grid (and rate) they used
RAW_FRAME = {"minirocket", "multirocket", "multirocket-hydra", "quant", "rdst", "cnn", "inception-time"}
#: the classifiers that take the captures and compute feature sets inside (a search over methods,
#: the training for shift)
ON_CAPTURES = {n for n in CLASSIFIERS.names() if CLASSIFIERS.entry(n).tags.get("input") == "captures"} - RAW_FRAME
RATE_SETS = {"touch-rhythm", "cell-rhythm", "contact-motion", "touch-windows"}


def stated(name: str, ds: TouchDataset) -> dict:
    """Parameters a set needs stated: raw-window's length (the shortest capture, nothing padded)."""
    return {"frames": shortest(ds), "shorter": "refuse"} if name == "raw-window" else {}


def test_the_ragged_dataset_is_ragged():
    assert (shortest(dataset("19x24")), int(dataset("19x24").n_frames.max())) == (3, 60)


# ------------------------------------------------------------------ feature sets
@pytest.mark.parametrize("key", list(SENSORS))
@pytest.mark.parametrize("name", FEATURES.names())
def test_every_feature_set_uses_the_sensor_or_is_refused(name, key):
    ds = dataset(key)
    sensor, n0 = ds.sensor, shortest(ds)
    fs = make_feature_set(name, stated(name, ds), sensor)
    problem = sensor_problem(fs, sensor, n0)
    if (name, key) in REFUSED:
        assert problem is not None and re.search(REFUSED[name, key], problem), problem
        if name in ("sd", "bmh", "smmhh"):  # named, HAART's values serve any sensor, as published
            fs = make_feature_set(name, {"preset": "haart"}, sensor)
            assert sensor_problem(fs, sensor, n0) is None
        else:
            return
    else:
        assert problem is None, problem
    out = fs.fit_transform(ds.captures)
    assert out.shape == (len(ds), expected_size(name, sensor, n0)) and np.isfinite(out).all()
    if name in RATE_SETS:  # the sensor's rate is the one used: as if given, unlike another
        given = {"frame_rate": sensor.frame_rate, "value_range": sensor.value_range}
        same = make_feature_set(name, given, None).fit_transform(ds.captures)
        other = make_feature_set(name, {**given, "frame_rate": 2 * sensor.frame_rate}, None).fit_transform(ds.captures)
        assert np.array_equal(out, same) and not np.array_equal(out, other)


@pytest.mark.parametrize("name", sorted(RATE_SETS | {"flagg-stats", "sd", "bmh", "smmhh", "raw-window"}))
def test_without_a_sensor_a_set_needing_one_says_what_to_give(name):
    fs = FEATURES.get(name)()
    with pytest.raises(FeatureInputError, match=r"sensor=|frames=|preset"):
        fs.fit_transform(dataset("6x6").captures)


def test_gaus_presets_follow_the_recording_setting():
    haart = SensorSpec("haart-like", (8, 8), 54.0, (0, 1023))
    cost = SensorSpec("cost-like", (8, 8), 135.0, (0, 1023))
    # HAART's Table 4 gives 62 values, CoST's 64 (its second touched histogram)
    assert make_feature_set("sd", {}, haart).n_features((8, 8)) == 62
    assert make_feature_set("sd", {}, cost).n_features((8, 8)) == 64
    c = np.array([[[100, 96, 0]]], dtype=np.uint16)  # bmh: HAART offset 5 (>= 95), CoST 100 (>= 0)
    assert make_feature_set("bmh", {}, haart).fit_transform([c])[0].tolist() == [1, 1, 0]
    assert make_feature_set("bmh", {}, cost).fit_transform([c])[0].tolist() == [1, 1, 1]


def test_raw_window_rule_for_shorter_captures_is_stated():
    ds = dataset("19x24")
    pad = make_feature_set("raw-window", {"frames": 5, "shorter": "pad"}, ds.sensor)
    out = pad.fit_transform([ds.captures[0]])[0].reshape(5, 19, 24)  # 3 frames, then the last repeated
    assert np.array_equal(out[:3], ds.captures[0]) and np.array_equal(out[3], ds.captures[0][2])
    refuse = make_feature_set("raw-window", {"frames": 5}, ds.sensor)
    assert re.search("shortest capture has 3 frames, the window needs 5", sensor_problem(refuse, ds.sensor, 3))
    with pytest.raises(FeatureInputError, match="3 frames, the window needs 5"):
        refuse.fit_transform([ds.captures[0]])


# ------------------------------------------------------------------ classifiers
def _frames(ds: TouchDataset) -> np.ndarray:
    fs = make_feature_set("raw-window", stated("raw-window", ds), ds.sensor)
    return fs.fit_transform(ds.captures)


def _cheap(name: str) -> dict:
    return dict(CLASSIFIERS.entry(name).tags.get("cheap_params", {}))


@pytest.mark.parametrize("key", list(SENSORS))
@pytest.mark.parametrize("name", CLASSIFIERS.names())
def test_every_classifier_uses_the_sensor_or_is_refused(name, key):
    ds = dataset(key)
    sensor, n0 = ds.sensor, shortest(ds)
    est = make_classifier(name, random_state=0, sensor=sensor, **_cheap(name))
    problem = sensor_problem(est, sensor, n0)
    if (name, key) in REFUSED:
        assert problem is not None and re.search(REFUSED[name, key], problem), problem
        return
    assert problem is None, problem
    # raw-frame classifiers read raw-window's frames; the others any feature matrix (flagg-stats here)
    if name in ON_CAPTURES:  # a search over methods, the training for shift: the captures themselves
        X = ds.captures
    else:
        X = _frames(ds) if name in RAW_FRAME else make_feature_set("flagg-stats", {}, sensor).fit_transform(ds.captures)
    y = (ds.meta["gesture"].to_numpy() == "rub").astype(np.int64)
    est.fit(X, y)
    if CLASSIFIERS.entry(name).tags.get("unlabelled_test"):  # adapts to a session before it predicts
        est.adapt(X)
    pred = np.asarray(est.predict(X))
    assert pred.shape == (len(ds),) and set(pred.tolist()) <= {0, 1}
    if name in RAW_FRAME:
        assert tuple(est.grid_) == sensor.grid


# ------------------------------------------------------------------ named methods
#: named methods that search over candidate methods (their candidates' sets are the other methods')
SEARCHES = [n for n in METHODS.names() if CLASSIFIERS.entry(METHODS.entry(n).tags["estimator"]).tags.get("candidates")]


#: named methods whose estimator takes the captures and computes the feature sets it names inside
INSIDE = [n for n in METHODS.names() if n not in SEARCHES and not method_spec(n).feature_sets]


@pytest.mark.parametrize("key", list(SENSORS))
@pytest.mark.parametrize("name", [n for n in METHODS.names() if n not in SEARCHES + INSIDE])
def test_every_method_uses_the_sensor_or_is_refused(name, key):
    """A named method's feature sets get the sensor (their sizes for this grid, worked out by hand)."""
    ds = dataset(key)
    sensor, n0 = ds.sensor, shortest(ds)
    spec = method_spec(name, **_cheap(METHODS.entry(name).tags["estimator"]))  # its estimator's quick settings
    problems = [sensor_problem(make_feature_set(n, p, sensor), sensor, n0) for n, p in spec.feature_sets]
    if (name, key) in REFUSED:
        assert any(p and re.search(REFUSED[name, key], p) for p in problems), problems
        return
    assert not any(problems), problems
    y = np.where(ds.meta["gesture"].to_numpy() == "rub", "rub", "other")
    pipe = FeaturePipeline(spec, random_state=0, sensor=sensor).fit(ds.captures, y)
    if CLASSIFIERS.entry(spec.estimator).tags.get("unlabelled_test"):  # adapts to a session before it predicts
        pipe.adapt(ds.captures)
    assert pipe.transform(ds.captures).shape == (len(ds), sum(expected_size(n, sensor, n0) for n in spec.feature_names))
    assert set(pipe.predict(ds.captures).tolist()) <= {"rub", "other"}


@pytest.mark.parametrize("key", list(SENSORS))
@pytest.mark.parametrize("name", SEARCHES)
def test_a_search_serves_a_sensor_when_one_of_its_candidates_does(name, key):
    """A search (nested-select) serves when one candidate does; a fusion only when every part does."""
    ds = dataset(key)
    sensor, n0 = ds.sensor, shortest(ds)
    spec = method_spec(name)
    tags = CLASSIFIERS.entry(spec.estimator).tags
    refused = []
    for c in spec.estimator_params[tags["candidates"]]:
        problems = [sensor_problem(make_feature_set(n, p, sensor), sensor, n0) for n, p in c["features"]]
        problems.append(sensor_problem(make_classifier(c["estimator"], random_state=0, sensor=sensor, **c["params"]),
                                       sensor, n0))
        refused.append(any(problems))
    est = make_classifier(spec.estimator, random_state=0, sensor=sensor, **spec.estimator_params)
    serves = not any(refused) if tags.get("needs_every_candidate") else not all(refused)
    assert (sensor_problem(est, sensor, n0) is None) == serves
    if (name, key) in REFUSED:
        assert not serves and re.search(REFUSED[name, key], sensor_problem(est, sensor, n0))


@pytest.mark.parametrize("key", list(SENSORS))
@pytest.mark.parametrize("name", INSIDE)
def test_a_method_on_captures_serves_a_sensor_when_its_feature_sets_do(name, key):
    """Its estimator is refused for a sensor exactly when (REFUSED says why), and otherwise it fits and
    labels the captures, its inner feature sets sized for this grid as worked out by hand."""
    ds = dataset(key)
    sensor, n0 = ds.sensor, shortest(ds)
    spec = method_spec(name)
    est = make_classifier(spec.estimator, random_state=0, sensor=sensor, **spec.estimator_params)
    problem = sensor_problem(est, sensor, n0)
    if (name, key) in REFUSED:
        assert problem is not None and re.search(REFUSED[name, key], problem), problem
        return
    assert problem is None, problem
    fewer = {"copies": 1} if "copies" in CLASSIFIERS.entry(spec.estimator).tags.get("defaults", {}) else {}
    cheap = {**spec.estimator_params, **fewer, "params": {"n_estimators": 5}}
    est = make_classifier(spec.estimator, random_state=0, sensor=sensor, **cheap)
    y = np.where(ds.meta["gesture"].to_numpy() == "rub", "rub", "other")
    est.fit(ds.captures, y)
    sets = est.method_.sets
    assert est.method_.transform(ds.captures).shape == (len(ds), sum(expected_size(n, sensor, n0) for n in cheap["features"]))
    assert len(sets) == len(cheap["features"]) and set(est.predict(ds.captures).tolist()) <= {"rub", "other"}


@pytest.mark.parametrize("name", sorted(RAW_FRAME))
def test_raw_frame_classifiers_without_a_sensor_say_to_pass_one(name):
    ds = dataset("6x6")
    X, y = _frames(ds), (ds.meta["gesture"].to_numpy() == "rub").astype(np.int64)
    with pytest.raises(ValueError, match=r"pass sensor=SensorSpec\(\.\.\.\) \(or grid=\(H, W\)"):
        make_classifier(name, random_state=0, **_cheap(name)).fit(X, y)
    wrong = make_classifier(name, random_state=0, sensor=ds.sensor, grid=(8, 8), **_cheap(name))
    assert "grid (8, 8) is not the grid of sensor 'grid-6x6' (6 x 6 at 20 Hz)" in sensor_problem(wrong, ds.sensor, 40)


def test_every_component_is_covered():
    assert set(RAW_FRAME) <= set(CLASSIFIERS.names())
    for name in FEATURES.names():
        expected_size(name, SENSORS["6x6"][0], 1)  # fails for a set this test does not know


# ------------------------------------------------------------------ the engine
PROTOCOL = """\
name: any-sensor
dataset: {data}
scheme: loso
features:
  - [{{name: raw-window, params: {{frames: {frames}}}}}]
classifiers:
  - {clf}
seed: 0
"""


@pytest.mark.parametrize("name,key", sorted(k for k in REFUSED if k[0] != "sd"))
def test_the_plan_refuses_before_any_task(name, key, tmp_path):
    ds = dataset(key)
    if name in CLASSIFIERS.names() or name in METHODS.names():
        text = PROTOCOL.format(data="scene:tiny", frames=shortest(ds), clf=name)
    else:
        text = PROTOCOL.format(data="scene:tiny", frames=shortest(ds), clf="zhou-lda").replace(
            "  - [{name: raw-window", f"  - [{name}]\n  - [{{name: raw-window", 1)
    with pytest.raises(ProtocolError) as e:
        plan_run(parse_protocol(text), cache_root=tmp_path, dataset=ds)
    msg = str(e.value)
    kind = "classifier" if name in CLASSIFIERS.names() else "method" if name in METHODS.names() else "feature set"
    sensor = ds.sensor
    assert f"{kind} {name!r} cannot serve sensor {sensor.name!r} ({sensor.grid[0]} x {sensor.grid[1]}" in msg
    assert f"at {sensor.frame_rate:g} Hz" in msg and re.search(REFUSED[name, key], msg)


def test_validate_and_run_refuse_on_the_command_line(tmp_path):
    ds = dataset("19x24")
    data = ds.to_parquet(tmp_path / "wide.parquet")
    proto = tmp_path / "p.yaml"
    proto.write_text(PROTOCOL.format(data=data, frames=3, clf="touch-et-win"))
    for args in (["protocols", "validate", str(proto)], ["run", str(proto), "--out", str(tmp_path / "out")]):
        r = CliRunner().invoke(cli, args)
        assert r.exit_code == 3, r.output
        assert "method 'touch-et-win' cannot serve sensor 'wide-19x24' (19 x 24 at 12 Hz)" in r.output
        assert "longer than the shortest capture (3 frames)" in r.output
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.parquet"))


def test_a_run_on_another_sensor_gives_the_classifier_that_sensor(tmp_path):
    from touchbench.engine.runner import run_protocol

    ds = dataset("6x6")
    data = ds.to_parquet(tmp_path / "six.parquet")
    proto = tmp_path / "p.yaml"
    text = PROTOCOL.format(data=data, frames=40, clf="{name: touch-et-fast, params: {n_estimators: 5}}")
    proto.write_text(text)
    res = run_protocol(proto, out=tmp_path / "out", cache_root=tmp_path / "cache", jobs=1, progress=False)
    assert (res.scores["status"] == "ok").all(), res.scores["error"].tolist()


# ------------------------------------------------------------------ HAART's numbers in code
#: modules allowed to hold HAART's numbers as constants: the HAART readers and
#: CoST's reader (CoST's own sensor is 8 x 8 too)
ALLOWED = {"datasets/haart.py", "datasets/challenge_csv.py", "datasets/cost.py"}


def _haart_numbers(node: ast.AST) -> list[str]:
    """HAART's numbers in an expression: 432, 54 (a frame rate), a (8, 8) tuple or list."""
    found = []
    for n in ast.walk(node):
        if isinstance(n, ast.Constant) and type(n.value) in (int, float) and n.value in (432, 54):
            found.append(repr(n.value))
        elif isinstance(n, (ast.Tuple, ast.List)) and len(n.elts) == 2 and all(
                isinstance(e, ast.Constant) and type(e.value) is int and e.value == 8 for e in n.elts):
            found.append("(8, 8)")
    return found


def _defaults_and_constants(tree: ast.Module):
    """(line, what) of every parameter default, module-level and class-level constant."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            for d in [*node.args.defaults, *[d for d in node.args.kw_defaults if d is not None]]:
                yield d.lineno, "parameter default", d
    bodies = [tree.body] + [n.body for n in ast.walk(tree) if isinstance(n, ast.ClassDef)]
    for body in bodies:
        for stmt in body:
            if isinstance(stmt, (ast.Assign, ast.AnnAssign)) and stmt.value is not None:
                yield stmt.lineno, "constant", stmt.value


def test_no_haart_numbers_as_defaults_in_code():
    root = Path(touchbench.__file__).parent
    hits = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel in ALLOWED:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for line, what, node in _defaults_and_constants(tree):
            for number in _haart_numbers(node):
                hits.append(f"{rel}:{line}: {what} holds {number}")
    assert not hits, "HAART's numbers used as defaults:\n" + "\n".join(hits)


def test_the_haart_number_check_finds_them():
    tree = ast.parse("GRID = (8, 8)\ndef f(frames=432, rate=54.0):\n    pass\nclass A:\n    x = {'g': [8, 8]}\n")
    found = [(line, n) for line, _, node in _defaults_and_constants(tree) for n in _haart_numbers(node)]
    assert sorted(found) == [(1, "(8, 8)"), (2, "432"), (2, "54.0"), (5, "(8, 8)")]
