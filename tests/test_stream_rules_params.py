"""Decision rules' declared parameters: checked once when the protocol is read (file:line: field),
every rule's parameters walked at and beyond their bounds. Values worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.datasets.model import SensorSpec
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import parse_protocol
from touchbench.streams.rules import RULES, RuleError, make_rule, needs_fitting

SENSOR = SensorSpec(name="t", grid=(1, 1), frame_rate=10.0, value_range=(0, 100))
CLASSES = np.array(["a", "b", "idle"], dtype=object)
#: a tiny probability stream over CLASSES
STREAM = [np.array([0.6, 0.3, 0.1]), np.array([0.2, 0.7, 0.1]), np.array([0.1, 0.1, 0.8])]

# the protocol's first seven lines; what a case adds starts at line 8
BASE = """name: t
dataset: haart-sample
target: gesture
scheme:
  name: stream
  base: loso
  idle: idle
{extra}methods: [touch-et-fast]
"""


def _refused(extra: str) -> str:
    with pytest.raises(ProtocolError) as e:
        parse_protocol(BASE.format(extra=extra), "p.yaml")
    return str(e.value)


# ----------------------------------------------------------------- the measured problems, by line and field
@pytest.mark.parametrize("extra, where, words", [
    ("  rules:\n    - {name: hmm, swich: 0.01}\n", "p.yaml:9: scheme.rules[0].swich:",
     "unknown field; did you mean 'switch'?"),
    ("  rules:\n    - {name: max, threshold: high}\n", "p.yaml:9: scheme.rules[0].threshold:", "'high'"),
    ("  rules:\n    - {name: hmm, switch: true}\n", "p.yaml:9: scheme.rules[0].switch:", "valid number"),
    ("  rules:\n    - {name: gate, idle: idle, level: true}\n", "p.yaml:9: scheme.rules[0].level:", "[0, 1], or auto"),
    ("  rules:\n    - {name: gate, idle: notouch}\n", "p.yaml:9: scheme.rules[0].idle:",
     "'notouch' is not the scheme's ('idle')"),
    ("  rules:\n    - {name: touch, idle: rest}\n", "p.yaml:9: scheme.rules[0].idle:", "not the scheme's"),
    # `max` and `max` with its default threshold are the same rule
    ("  rules:\n    - max\n    - {name: max, threshold: 0.5}\n", "p.yaml:10: scheme.rules[1]:", "same rule as rules[0]"),
    ("  rules:\n    - {name: hmmm}\n", "p.yaml:9: scheme.rules[0].name:", "did you mean 'hmm'?"),
    ("  rules:\n    - {name: touch, idle: idle, begin: 0.4, end: 0.6}\n", "p.yaml:9: scheme.rules[0].end:",
     "end (0.6) must not be above begin (0.4)"),
    ("  hop_s: .inf\n", "p.yaml:8: scheme.hop_s:", "finite"),
    ("  hop_s: 0\n", "p.yaml:8: scheme.hop_s:", "greater than 0"),
    ("  hop_s: true\n", "p.yaml:8: scheme.hop_s:", "valid number"),
    ("  windows_s: [1.0e+9]\n", "p.yaml:8: scheme.windows_s[0]:", "less than or equal to 60"),
    ("  windows_s: [0.5, 60.5]\n", "p.yaml:8: scheme.windows_s[1]:", "less than or equal to 60"),
    ("  windows_s: [.nan]\n", "p.yaml:8: scheme.windows_s[0]:", "finite"),
    ("  windows_s: [yes]\n", "p.yaml:8: scheme.windows_s[0]:", "valid number"),
    ("  gap_s: [1, 100]\n", "p.yaml:8: scheme.gap_s[1]:", "at most 60 s (the scheme's cap), got 100 s"),
    ("  gap_s: [1, 1.0e+9]\n", "p.yaml:8: scheme.gap_s[1]:", "at most 60 s"),
    ("  gap_s: [true, 2]\n", "p.yaml:8: scheme.gap_s[0]:", "valid number"),
    ("  max_false_per_min: true\n", "p.yaml:8: scheme.max_false_per_min:", "valid number"),
])
def test_the_protocol_refuses_each_value_at_its_line_and_field(extra, where, words):
    msg = _refused(extra)
    assert where in msg and words in msg, msg


def test_every_problem_of_a_rule_is_reported_at_its_field():
    msg = _refused("  rules:\n    - {name: hmm, swich: 0.01, threshold: high}\n")
    assert "p.yaml:9: scheme.rules[0].swich: unknown field" in msg
    assert "p.yaml:9: scheme.rules[0].threshold:" in msg


def test_the_caps_themselves_are_accepted():
    p = parse_protocol(BASE.format(extra="  windows_s: [60]\n  gap_s: [60, 60]\n  hop_s: 0.05\n"), "p.yaml")
    params = p.scheme.params
    assert params["windows_s"] == [60] and params["gap_s"] == [60, 60]


def test_protocols_validate_names_the_file_line_and_field(tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text(BASE.format(extra="  rules:\n    - {name: hmm, swich: 0.01}\n"))
    res = CliRunner().invoke(cli, ["protocols", "validate", str(f)])
    assert res.exit_code != 0
    assert f"{f}:9: scheme.rules[0].swich: unknown field; did you mean 'switch'?" in res.output


# ----------------------------------------------------------------- every rule's parameters at their bounds
PROBABILITY = ([0, 0.5, 1, 1.0], [-0.001, 1.001, True, "0.5", math.nan, math.inf])
SECONDS = ([0, 0.5, 3599.5], [-1e-9, 3600, math.inf, True, "1"])
#: field -> (accepted values, refused values), worked out from each parameter's documented range
BOUNDS: dict[str, tuple[list, list]] = {
    "threshold": PROBABILITY, "switch": PROBABILITY, "begin": PROBABILITY, "end": PROBABILITY,
    "n": ([1, 2, 50], [0, -1, 1.5, True, "3"]),
    "gate_s": ([1e-9, 0.25, 3599.5], [0, -1, 3600, math.inf, True, "0.25"]),
    "bridge_s": SECONDS, "begin_s": SECONDS, "end_s": SECONDS, "memory": SECONDS,
    "level": (["auto", 0, 0.3, 1], [-0.1, 1.1, True, "high", math.nan]),
    "idle": (["idle"], ["", True, 3]),
}


def _base(name: str, field: str) -> dict:
    """The least declaration of rule ``name`` around ``field``: its required idle class; the touch
    rule's begin / end set so that the other may take any probability."""
    fields = RULES.get(name).Params.model_fields
    d = {"name": name, **({"idle": "idle"} if "idle" in fields else {})}
    if name == "touch" and field in ("begin", "end"):
        d["begin" if field == "end" else "end"] = 1.0 if field == "end" else 0.0
    return d


WALK = [(name, field) for name in RULES.names() for field in RULES.get(name).Params.model_fields]


def test_every_declared_parameter_has_its_bounds_here():
    assert {f for _, f in WALK} <= set(BOUNDS)
    assert {"max", "gate", "majority", "hmm", "onset", "touch"} <= set(RULES.names())


def _run(rule) -> list[str]:
    if needs_fitting(rule):  # level: auto, chosen on a rest capture and a touch
        rule.fit([np.zeros((10, 1, 1)), np.full((10, 1, 1), 50.0)], ["idle", "a"], SENSOR)
    rule.start(CLASSES, "none", 10.0, SENSOR)
    rule.set_hop(1)
    return [rule.decide(p) for p in STREAM]


@pytest.mark.parametrize("name, field", WALK)
def test_accepted_values_build_a_rule_that_decides(name, field):
    for value in BOUNDS[field][0]:
        rule = make_rule({**_base(name, field), field: value})
        assert getattr(rule, field) == value
        assert set(_run(rule)) <= {"a", "b", "idle", "none"}


@pytest.mark.parametrize("name, field", WALK)
def test_refused_values_name_the_field_in_make_rule_and_in_the_protocol(name, field):
    for value in BOUNDS[field][1]:
        with pytest.raises(RuleError) as e:
            make_rule({**_base(name, field), field: value})
        assert [loc for loc, _ in e.value.issues] == [(field,)], (value, e.value.issues)
    value = BOUNDS[field][1][0]  # the first refused value, through a protocol
    rules = yaml.safe_dump([{**_base(name, field), field: value}], default_flow_style=True).strip()
    msg = _refused(f"  rules: {rules}\n")
    assert f"p.yaml:8: scheme.rules[0].{field}:" in msg, msg


def test_the_bounds_decide_as_worked_out_by_hand():
    # max: threshold 1 names a class only at probability 1; 0 always the most probable
    assert _run(make_rule({"name": "max", "threshold": 1})) == ["none", "none", "none"]
    assert _run(make_rule({"name": "max", "threshold": 0})) == ["a", "b", "idle"]
    # hmm with switch 0 keeps the first class: posteriors (0.6, 0.3, 0.1), then times (0.2, 0.7, 0.1)
    # -> (0.12, 0.21, 0.01) / 0.34: b 0.62; then times (0.1, 0.1, 0.8) -> (0.012, 0.021, 0.008) / 0.041:
    # b 0.51 (switch 0 is the plain product of the emissions)
    assert _run(make_rule({"name": "hmm", "switch": 0, "threshold": 0})) == ["a", "b", "b"]
    # majority over n=1 is max itself
    assert _run(make_rule({"name": "majority", "n": 1, "threshold": 0})) == ["a", "b", "idle"]
    # touch with begin 0: P(touch) = 0.9 >= 0 from the first decision (begin_s 0: one decision);
    # the gesture so far over a and b (renormalised without idle): log(2/3) + log(2/9) < log(1/3) + log(7/9)
    touch = make_rule({"name": "touch", "idle": "idle", "begin": 0, "end": 0, "begin_s": 0})
    assert _run(touch)[:2] == ["a", "b"]
