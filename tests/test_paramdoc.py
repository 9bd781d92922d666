"""Every registered scheme, decision rule, feature set, classifier and method documents exactly the
parameters it declares, in a "Parameters" section generated from the declaration
(touchbench.core.paramdoc); a method's are its classifier's and those it sets."""

from __future__ import annotations

import re
from numbers import Integral, Real

import pytest
from pydantic import BaseModel, Field
from sklearn.utils._param_validation import Interval, StrOptions

from touchbench.classifiers.base import CLASSIFIERS
from touchbench.core.paramdoc import constraint_words, model_params, render, with_parameters
from touchbench.features.base import FEATURES
from touchbench.methods import METHODS
from touchbench.protocols.schemes.base import SPLITTERS
from touchbench.streams.rules import RULES


def documented(doc: str) -> list[str]:
    """The parameter names of ``doc``'s "Parameters" section, in order."""
    m = re.search(r"^Parameters\n-{10}\n(.*?)(?:\n\w[\w ]*\n-{3,}\n|\Z)", doc, re.M | re.S)
    assert m, "no Parameters section"
    return re.findall(r"^(\w+) : ", m.group(1), re.M)


def declared(registry, entry) -> list[str]:
    if registry is CLASSIFIERS:
        return list(entry.tags["defaults"])
    if registry is METHODS:  # its classifier's parameters, and any it gives that classifier beside them
        return sorted(set(CLASSIFIERS.entry(entry.tags["estimator"]).tags["defaults"]) | set(entry.tags["defaults"]))
    if registry is FEATURES:
        return list(entry.obj._get_param_names())  # scikit-learn's reading of __init__ (sorted)
    return list(entry.obj.Params.model_fields)


@pytest.mark.parametrize("registry", [SPLITTERS, RULES, FEATURES, CLASSIFIERS, METHODS], ids=lambda r: r.kind)
def test_every_entry_documents_exactly_its_declared_parameters(registry):
    entries = list(registry.entries())
    assert entries
    for e in entries:
        names = documented(e.obj.__doc__ or "")
        assert len(names) == len(set(names)), e.name
        assert sorted(names) == sorted(declared(registry, e)), e.name
        assert e.obj.__doc__.count("\nParameters\n") + e.obj.__doc__.startswith("Parameters\n") == 1, e.name


def test_a_rules_section_is_its_model_with_the_descriptions():
    """``majority``: hand-written from MajorityParams' fields (an int >= 1 and a fraction)."""
    doc = RULES.get("majority").__doc__
    expected = ("Parameters\n"
                "----------\n"
                "n : int in [1, inf), default 5\n"
                "    how many of the latest decisions vote (1: ``max`` itself).\n"
                "threshold : float in [0, 1], default 0.5\n"
                "    ``max``'s threshold.\n")
    assert expected in doc
    assert doc.index("Parameters\n") < doc.index("Examples\n")  # numpydoc's order


def test_a_feature_sets_section_is_its_constraints_in_words():
    """``lbptop``: radius array-like, n_points an Integral in [4, 16], mapping one of u2/none."""
    expected = ("Parameters\n"
                "----------\n"
                "radius : a list or array, default (1, 1, 1)\n"
                "    the radii (r_x, r_y, r_t), three positive integers.\n"
                "n_points : an integer in [4, 16], default 8\n"
                "    P, the neighbours per plane.\n"
                "mapping : one of 'none', 'u2', default 'u2'\n"
                "    ``u2``: the uniform patterns' bins; ``none``: all 2**P codes.\n"
                "sensor : any value, default None\n"
                "    unused.\n")
    assert FEATURES.get("lbptop").__doc__.endswith(expected)


def test_constraints_in_words():
    assert constraint_words([Interval(Integral, 1, None, closed="left")]) == "an integer in [1, inf)"
    assert constraint_words([Interval(Real, 0, 1, closed="neither"), None]) == "a number in (0, 1) or None"
    assert constraint_words([StrOptions({"b", "a"})]) == "one of 'a', 'b'"
    assert constraint_words(["boolean"]) == "a boolean"


def test_a_models_bounds_choices_and_required_fields():
    from typing import Literal, Optional

    class P(BaseModel):
        name: str = Field(min_length=1, description="a name.")
        k: Optional[int] = Field(default=None, ge=2, le=9)
        side: Literal["left", "right"] = "left"
        rate: float = Field(default=0.5, gt=0, lt=1)

    assert render(model_params(P)) == ("Parameters\n----------\n"
                                       "name : str, not empty, required\n    a name.\n"
                                       "k : int in [2, 9] or None, default None\n"
                                       "side : one of 'left', 'right', default 'left'\n"
                                       "rate : float in (0, 1), default 0.5\n")


def test_a_hand_written_section_is_replaced_in_place():
    doc = """Summary.

    Parameters
    ----------
    old : what it was.

    Examples
    --------
    >>> 1
    1
    """
    out = with_parameters(doc, "Parameters\n----------\nnew : int, default 1\n")
    assert out == "Summary.\n\nParameters\n----------\nnew : int, default 1\n\nExamples\n--------\n>>> 1\n1\n"
    assert with_parameters("Summary.", "Parameters\n----------\nNone.\n") == \
        "Summary.\n\nParameters\n----------\nNone.\n"


def test_a_methods_section_shows_the_values_it_sets():
    # touch-et-adapt gives session-centred params={} (its classifier's default is None); touch-et sets
    # nothing, so touch-extra-trees' own defaults show (500 trees)
    adapt = METHODS.get("touch-et-adapt").__doc__
    assert "params : any value, default {}\n    (this method's value; session-centred's is None)" in adapt
    assert "n_estimators : int, default 500" in METHODS.get("touch-et").__doc__
