"""Every registered scheme's declared numeric parameters, walked at and beyond their bounds.

For each bound (``ge``/``gt``/``le``/``lt``) a field's parameter model declares: a value beyond a
closed bound (one less or more for an integer, a little for a real) or at an open one is refused
when the protocol is read, at ``file:line: scheme.FIELD``; a value at a closed bound is accepted.
A sample of the accepted values runs (``RUN``: the fewest folds, draws and windows a scheme allows,
where a run is likeliest to break), on scene:tiny or, for the stream scheme, which needs an idle
class, on haart-sample.
"""

from __future__ import annotations

import annotated_types as at
import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.engine import run_protocol
from touchbench.protocols.loading import parse_protocol
from touchbench.protocols.schemes.base import SPLITTERS

#: what each scheme needs stated beside the field walked, to be a valid entry
NEEDS = {
    "calibration": {"base": "loso", "per_class": [1]},
    "early": {"base": "loso", "frames": [8]},
    "learning-curve": {"base": "loso", "subjects": [2]},
    "stream": {"base": "loso", "idle": "notouch"},
    "window-kfold": {"frames": 8, "k": 2, "per_capture": 2},
}
#: a field that replaces another one of NEEDS (window-kfold takes frames or seconds)
INSTEAD = {("window-kfold", "seconds"): "frames"}
#: the accepted bounds that run: (scheme, field, side)
RUN = {("kfold", "k", "left"), ("within-subject", "k", "left"), ("person-independent", "k", "left"),
       ("window-kfold", "frames", "left"), ("window-kfold", "per_capture", "left"),
       ("learning-curve", "draws", "left"), ("calibration", "draws", "left"), ("stream", "per_stream", "left")}
_SIDES = {at.Ge: ("left", True, "ge"), at.Gt: ("left", False, "gt"), at.Le: ("right", True, "le"),
          at.Lt: ("right", False, "lt")}


def _integer(annotation) -> bool:
    return annotation is int or "int" in str(annotation).replace("Optional", "").split("|")[0]


def _cases():
    for name in SPLITTERS.names():
        for field, info in SPLITTERS.get(name).Params.model_fields.items():
            for m in info.metadata:
                if type(m) in _SIDES:
                    side, closed, attr = _SIDES[type(m)]
                    yield pytest.param(name, field, side, float(getattr(m, attr)), closed,
                                       _integer(info.annotation), id=f"{name}-{field}-{side}")


CASES = list(_cases())


def _text(name: str, params: dict) -> str:
    dataset = "haart-sample" if name == "stream" else "scene:tiny"
    entry = ", ".join(f"{k}: {v}" for k, v in {"name": name, **params}.items())
    return (f"name: walk\ndataset: {dataset}\nseed: 1\nscheme: {{{entry}}}\n"  # the scheme on line 4
            "features: [[msd]]\nclassifiers: [{name: flagg-rf, params: {n_estimators: 5}}]\n")


def _params(name: str, field: str, value) -> dict:
    needs = {k: v for k, v in NEEDS.get(name, {}).items() if k != INSTEAD.get((name, field))}
    return {**needs, field: value}


def test_every_scheme_with_a_bound_is_walked():
    # the schemes whose models declare numeric bounds (worked out from their documented parameters)
    assert {c.values[0] for c in CASES} == {"calibration", "kfold", "learning-curve", "person-independent",
                                            "stream", "window-kfold", "within-subject"}


@pytest.mark.parametrize("name,field,side,bound,closed,integer", CASES)
def test_a_scheme_parameter_at_and_beyond_its_bound(tmp_path, name, field, side, bound, closed, integer):
    step = 1 if integer else 1e-6 * max(1.0, abs(bound))
    beyond = bound - step if side == "left" else bound + step
    beyond = int(beyond) if integer else beyond
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(_text(name, _params(name, field, beyond)), "p.yaml")
    assert f"p.yaml:4: scheme.{field}: " in str(e.value), str(e.value)
    if not closed:
        with pytest.raises(TouchbenchError, match=f"scheme.{field}: "):
            parse_protocol(_text(name, _params(name, field, int(bound) if integer else bound)), "p.yaml")
        return
    value = int(bound) if integer else bound
    protocol = parse_protocol(_text(name, _params(name, field, value)), tmp_path / "p.yaml")
    if (name, field, side) in RUN:
        result = run_protocol(protocol, tmp_path / "out", jobs=1, progress=False)
        assert (result.scores["status"] == "ok").all()
