"""Every registered feature set's declared numeric parameters, walked at and beyond their bounds.

For each ``Interval`` of a set's ``_parameter_constraints``: a value beyond a closed bound (one
less for an integer, a little less for a real) or at an open one is refused when the protocol is
read, naming the field; a value at a closed bound is accepted. Running every accepted value on
``scene:tiny`` would take minutes, so a sample runs (``RUN``: the lowest window, step or rate a
set allows, where a run is the likeliest to break); the rest are validated only.
"""

from __future__ import annotations

from numbers import Integral

import pytest
from sklearn.utils._param_validation import Interval

from touchbench.core.errors import TouchbenchError
from touchbench.engine import run_protocol
from touchbench.features import FEATURES
from touchbench.protocols.loading import parse_protocol

#: what a set needs stated to run at all (``raw-window``'s window)
NEEDS = {"raw-window": {"frames": 4, "shorter": "pad"}}
#: the at-bound cases run on scene:tiny
RUN = {("raw-window", "frames", "left"), ("touch-windows", "n_windows", "left"), ("zhou-basic", "upsample", "left")}


def _cases():
    for name in FEATURES.names():
        for param, constraints in getattr(FEATURES.get(name), "_parameter_constraints", {}).items():
            for c in constraints:
                if not isinstance(c, Interval):
                    continue
                for side, bound in (("left", c.left), ("right", c.right)):
                    if bound is not None:
                        closed = c.closed in (side, "both")
                        yield pytest.param(name, param, side, bound, closed, c.type is Integral,
                                           id=f"{name}-{param}-{side}")


def _text(name: str, params: dict) -> str:
    return ("name: walk\ndataset: scene:tiny\nscheme: loso\nseed: 1\nfeatures:\n"
            f"  - [{{name: {name}, params: {params!r}}}]\n"  # line 6
            "classifiers:\n  - {name: flagg-rf, params: {n_estimators: 5}}\n").replace("'", '"')


@pytest.mark.parametrize("name,param,side,bound,closed,integer", list(_cases()))
def test_a_parameter_at_and_beyond_its_bound(tmp_path, name, param, side, bound, closed, integer):
    step = 1 if integer else 1e-6 * max(1.0, abs(bound))
    beyond = bound - step if side == "left" else bound + step
    beyond = int(beyond) if integer else beyond
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(_text(name, {**NEEDS.get(name, {}), param: beyond}), "p.yaml")
    assert f"p.yaml:6: features[0][0].params.{param}: The {param!r} parameter of {name}" in str(e.value)
    if not closed:
        with pytest.raises(TouchbenchError, match=f"params.{param}: "):
            parse_protocol(_text(name, {**NEEDS.get(name, {}), param: bound}), "p.yaml")
        return
    at = int(bound) if integer else float(bound)
    protocol = parse_protocol(_text(name, {**NEEDS.get(name, {}), param: at}), tmp_path / "p.yaml")
    if (name, param, side) in RUN:
        result = run_protocol(protocol, tmp_path / "out", jobs=1, progress=False)
        assert (result.scores["status"] == "ok").all()


def test_a_window_of_no_frame_is_refused_where_the_rate_is_known(tmp_path):
    # touch-windows at 50 Hz (frame_rate given): 0.009 s is 0.45 frames, rounded none; 0.011 s (0.55) is one
    bad = _text("touch-windows", {"frame_rate": 50.0, "window_s": 0.009})
    with pytest.raises(TouchbenchError, match=r"window_s 0.009 s is 0 frames at 50 Hz: a window is at least one "
                                              r"frame \(0.02 s\)"):
        parse_protocol(bad, "p.yaml")
    parse_protocol(_text("touch-windows", {"frame_rate": 50.0, "window_s": 0.011}), "p.yaml")
