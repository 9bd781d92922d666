"""Every registered feature set's and classifier's declared numeric parameters, walked at and beyond
their bounds (the schemes' and the decision rules' are walked by tests/test_schemes_params_walk.py and
tests/test_stream_rules_params.py).

For each bound of each ``Interval`` of a component's ``_parameter_constraints`` (a classifier's: those
of the estimator it builds, for a parameter a protocol may set): a value beyond a closed bound (one
less or more for an integer, a little for a real) or at an open one is refused when the protocol is
read, naming the field; a value at a closed bound is accepted, and then computes on ``scene:tiny``
as a task would: the feature set on the captures, the classifier fitted on three of its people and
predicting the fourth (the method's path: feature sets, then the estimator built with the sensor;
every other parameter at the entry's cheap settings). A cap on a count (at most so many trees,
kernels, epochs, networks) and on the cores used is validated, not run: at the cap a run takes hours.
"""

from __future__ import annotations

import functools
from numbers import Integral

import numpy as np
import pytest
from sklearn.utils._param_validation import Interval, make_constraint

from touchbench.classifiers import CLASSIFIERS
from touchbench.core.errors import TouchbenchError
from touchbench.core.versions import missing_extra
from touchbench.classifiers.fitting import fit_features
from touchbench.features import FEATURES
from touchbench.methods.base import MethodSpec
from touchbench.methods.fitting import fit_method
from touchbench.protocols.loading import parse_protocol
from touchbench.scenes import generate_scene

#: what a set needs stated to run at all (``raw-window``'s window)
NEEDS = {"raw-window": {"frames": 4, "shorter": "pad"}}


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
    parse_protocol(_text(name, {**NEEDS.get(name, {}), param: at}), tmp_path / "p.yaml")
    # accepted: the set computes on scene:tiny's captures as a task computes it (built with the sensor)
    ds = _tiny()
    _, X = fit_features([(name, {**NEEDS.get(name, {}), param: at})], list(ds.captures), ds.meta["gesture"].to_numpy(),
                        ds.sensor)
    assert X.shape[0] == len(ds.captures) and np.isfinite(X).all()


def test_a_window_of_no_frame_is_refused_where_the_rate_is_known(tmp_path):
    # touch-windows at 50 Hz (frame_rate given): 0.009 s is 0.45 frames, rounded none; 0.011 s (0.55) is one
    bad = _text("touch-windows", {"frame_rate": 50.0, "window_s": 0.009})
    with pytest.raises(TouchbenchError, match=r"window_s 0.009 s is 0 frames at 50 Hz: a window is at least one "
                                              r"frame \(0.02 s\)"):
        parse_protocol(bad, "p.yaml")
    parse_protocol(_text("touch-windows", {"frame_rate": 50.0, "window_s": 0.011}), "p.yaml")


# ----------------------------------------------------------------- every classifier's declared bounds
#: what a classifier needs stated to be valid at all (the methods a fusion or a selection is over)
#: or for every value of a walked parameter to be valid with it (the rules across fields: a
#: capture of ``length`` frames holds the CNN's ``L`` windows; LDA shrinks with the lsqr solver)
NEEDS_CLASSIFIER = {"fusion": {"parts": ["touch-et-fast", "touch-et"]},
                    "nested-select": {"candidates": ["touch-et-fast", "touch-et"]},
                    "cnn": {"L": 1}, "zhou-lda": {"solver": "lsqr"}}


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


def _classifier_text(name: str, params: dict, needs: bool = True) -> tuple[str, str]:
    """A protocol giving classifier ``name`` ``params`` (over what it ``needs``, :data:`NEEDS_CLASSIFIER`)
    on line 6, and the section it is in."""
    head = "name: walk\ndataset: scene:tiny\nscheme: loso\nseed: 1\n"
    params = {**(NEEDS_CLASSIFIER.get(name, {}) if needs else {}), **params}
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
    parse_protocol(text, tmp_path / "p.yaml")
    if integer and side == "right" or param == "n_jobs":
        return  # a cap on a count (trees, kernels, epochs, networks...) or on the cores used: validated only
    # accepted: it fits and predicts on scene:tiny as a task would (the method's path: its feature
    # sets, then the estimator built with the sensor), every other parameter at the entry's cheap
    # settings; trained on three of tiny's people, tested on the fourth
    ds, params = _tiny(), {**NEEDS_CLASSIFIER.get(name, {}), **CLASSIFIERS.entry(name).tags.get("cheap_params", {}),
                           param: at}
    sets = () if CLASSIFIERS.entry(name).tags.get("input") == "captures" else (("msd", {}),)
    subjects = ds.meta["subject"].astype(str).to_numpy()
    train, test = np.flatnonzero(subjects != subjects[-1]), np.flatnonzero(subjects == subjects[-1])
    fitted = fit_method(MethodSpec(name, sets, name, params), 0, [ds.captures[i] for i in train],
                        ds.meta["gesture"].to_numpy()[train], subjects[train], sensor=ds.sensor)
    predicted = fitted.predict([ds.captures[i] for i in test])
    assert len(predicted) == len(test) and set(map(str, predicted)) <= set(ds.meta["gesture"].astype(str))


@functools.cache
def _tiny():
    return generate_scene("tiny")


@pytest.mark.parametrize("name,params,field,words", [
    # the CNN cuts a capture of `length` frames into L windows of at least one frame: 29 < 30
    ("cnn", {"length": 29}, "length", "length 29 leaves no frame per window for L=30"),
    # scikit-learn's LDA takes shrinkage with the lsqr or eigen solver only; zhou-lda's is svd
    ("zhou-lda", {"shrinkage": 0.5}, "shrinkage", "shrinkage needs solver: lsqr or eigen"),
])
def test_a_rule_across_fields_is_checked_when_the_protocol_is_read(name, params, field, words):
    text, section = _classifier_text(name, params, needs=False)
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(text, "p.yaml")
    assert f"p.yaml:6: {section}[0].params.{field}: " in str(e.value) and words in str(e.value), str(e.value)
    fixed = {"cnn": {"length": 30}, "zhou-lda": {"shrinkage": 0.5, "solver": "lsqr"}}[name]
    parse_protocol(_classifier_text(name, fixed, needs=False)[0], "p.yaml")
