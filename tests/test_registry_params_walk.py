"""Every registered feature set's and classifier's declared numeric parameters, walked at and beyond
their bounds.

For each ``Interval`` of a set's ``_parameter_constraints``: a value beyond a closed bound (one
less for an integer, a little less for a real) or at an open one is refused when the protocol is
read, naming the field; a value at a closed bound is accepted. Running every accepted value on
``scene:tiny`` would take minutes, so a sample runs (``RUN``: the lowest window, step or rate a
set allows, where a run is the likeliest to break); the rest are validated only.
"""

from __future__ import annotations

from numbers import Integral

import numpy as np
import pytest
from sklearn.utils._param_validation import Interval, make_constraint

from touchbench.classifiers import CLASSIFIERS
from touchbench.core.errors import TouchbenchError
from touchbench.core.versions import missing_extra
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


# ----------------------------------------------------------------- every classifier's declared bounds
#: the at-bound cases of classifiers that run on scene:tiny (the fewest trees, neighbours, kernels,
#: groups and shapelets a classifier allows)
RUN_CLASSIFIERS = {("gaus-rf", "n_estimators", "left"), ("zhou-knn", "n_neighbors", "left"),
                   ("minirocket", "n_kernels", "left"), ("multirocket-hydra", "n_groups", "left"),
                   ("rdst", "max_shapelets", "left")}


#: what a classifier needs stated to be valid at all (the methods a fusion or a selection is over)
NEEDS_CLASSIFIER = {"fusion": {"parts": ["touch-et-fast", "touch-et"]},
                    "nested-select": {"candidates": ["touch-et-fast", "touch-et"]}}


def _built(name: str):
    """The estimator the registered classifier ``name`` builds with its defaults (None without its extra)."""
    extra = CLASSIFIERS.entry(name).tags.get("extra")
    return None if extra and missing_extra(extra) else CLASSIFIERS.get(name)(random_state=0)


def _beyond(bound: float, side: str, integer: bool):
    step = 1 if integer else 1e-6 * max(1.0, abs(bound))
    beyond = bound - step if side == "left" else bound + step
    return int(beyond) if integer else float(beyond)


def _classifier_cases():
    """(classifier, parameter, side, bound, closed, integer) for each bound of each ``Interval`` a
    registered classifier's estimator declares for a parameter a protocol may set, where the value
    beyond it is one that no other alternative of the parameter's domain takes."""
    for name in CLASSIFIERS.names():
        est = _built(name)
        if est is None:
            continue
        constraints = getattr(est, "_parameter_constraints", {})
        for param in sorted(set(est.get_params(deep=False)) - {"random_state", "sensor"}):
            domain = constraints.get(param)
            for c in domain if isinstance(domain, list) else []:
                if not isinstance(c, Interval):
                    continue
                integer = c.type is Integral
                for side, bound in (("left", c.left), ("right", c.right)):
                    if bound is None or not np.isfinite(bound):
                        continue
                    beyond = _beyond(bound, side, integer)
                    if any(make_constraint(o).is_satisfied_by(beyond) for o in domain if o is not c):
                        continue
                    yield pytest.param(name, param, side, bound, c.closed in (side, "both"), integer,
                                       id=f"{name}-{param}-{side}")


CLASSIFIER_CASES = list(_classifier_cases())


def _classifier_text(name: str, params: dict) -> tuple[str, str]:
    """A protocol giving classifier ``name`` ``params`` on line 6, and the section it is in."""
    head = "name: walk\ndataset: scene:tiny\nscheme: loso\nseed: 1\n"
    params = {**NEEDS_CLASSIFIER.get(name, {}), **params}
    entry = f"[{{name: {name}, params: {params!r}}}]".replace("'", '"')
    if CLASSIFIERS.entry(name).tags.get("input") == "captures":
        return head + "methods:\n  - " + entry[1:-1] + "\n", "methods"
    return head + "features: [[msd]]\nclassifiers: " + entry + "\n", "classifiers"


def test_every_registered_classifier_is_built_and_most_declare_bounds():
    # with every extra installed (as in CI), each classifier is built; the ones with no numeric bound
    # a protocol may set: the naive Bayes and LDA have none (worked out from scikit-learn's and
    # touchbench's declarations), two-stage and nested-select take names and mappings
    walked = {c.values[0] for c in CLASSIFIER_CASES}
    if not missing_extra("peers,deep"):
        assert set(CLASSIFIERS.names()) - walked <= {"two-stage", "nested-select", "jung-naive-bayes", "zhou-lda",
                                                     "example-nearest-centroid"}


@pytest.mark.parametrize("name,param,side,bound,closed,integer", CLASSIFIER_CASES)
def test_a_classifier_parameter_at_and_beyond_its_bound(tmp_path, name, param, side, bound, closed, integer):
    text, section = _classifier_text(name, {param: _beyond(bound, side, integer)})
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(text, "p.yaml")
    assert f"{section}[0].params.{param}: " in str(e.value), str(e.value)
    at = int(bound) if integer else float(bound)
    text, _ = _classifier_text(name, {param: at})
    if not closed:
        with pytest.raises(TouchbenchError, match=f"params.{param}: "):
            parse_protocol(text, "p.yaml")
        return
    protocol = parse_protocol(text, tmp_path / "p.yaml")
    if (name, param, side) in RUN_CLASSIFIERS:
        result = run_protocol(protocol, tmp_path / "out", jobs=1, progress=False)
        assert (result.scores["status"] == "ok").all()
