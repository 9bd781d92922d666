"""Classifier parameter values that could only fail when a method runs are refused by
`touchbench protocols validate`, with the file, the line and the field (each classifier's declared
domains, ``_parameter_constraints``, and its own checks, the registry tag ``check_params``, asked
of every entry and every nested candidate)."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from touchbench.classifiers import ParamError, check_classifier_params, make_classifier
from touchbench.cli.main import cli
from touchbench.core.versions import missing_extra

HEAD = "name: t\ndataset: scene:tiny\nscheme: loso\nmethods:\n"  # lines 1-4; the entry starts on line 5

needs_peers = pytest.mark.skipif(bool(missing_extra("peers")), reason="fusion needs the peers extra")


def validate(tmp_path, entry: str) -> str:
    """The one error line of `protocols validate --schema-only` on HEAD + ``entry``."""
    path = tmp_path / "p.yaml"
    path.write_text(HEAD + entry)
    r = CliRunner().invoke(cli, ["protocols", "validate", "--schema-only", str(path)])
    assert r.exit_code == 3, r.output
    assert "Traceback" not in r.output and len(r.output.strip().splitlines()) == 1, r.output
    return r.output.strip().removeprefix("error: ").replace(str(path), "p.yaml")


#: sd_floor's declared domain in scikit-learn's words: a positive finite number
FLOOR = "The 'sd_floor' parameter of SessionCentred must be a float in the range (0.0, inf)"
FUSION = "  - name: fusion\n    params:\n      parts: [touch-et-contact, touch-et]\n"  # lines 5-7


@needs_peers
@pytest.mark.parametrize("weights,shown", [("[[-1, 2]]", "[-1, 2]"), ("[[1, 1], [.nan, 1]]", "[nan, 1]")])
def test_fusion_weights_that_are_not_a_distribution_are_refused(tmp_path, weights, shown):
    out = validate(tmp_path, FUSION + f"      weights: {weights}\n")  # line 8
    vector = 0 if weights.startswith("[[-1") else 1
    assert out.startswith(f"p.yaml:8: methods[0].params.weights[{vector}]: fusion: weight vector {shown} is not 2 "
                          "non-negative weights with a positive sum")


@pytest.mark.parametrize("entry,line,field,shown", [
    ("  - name: touch-et-adapt\n    params:\n      sd_floor: 0\n", 7, "methods[0].params.sd_floor", "0"),
    ("  - name: touch-et-adapt\n    params:\n      sd_floor: -1.0e-6\n", 7, "methods[0].params.sd_floor", "-1e-06"),
    ("  - name: touch-et-adapt\n    params: {scale: true, sd_floor: .nan}\n", 6, "methods[0].params.sd_floor", "nan"),
])
def test_a_session_floor_that_is_not_positive_is_refused(tmp_path, entry, line, field, shown):
    out = validate(tmp_path, entry)
    assert out.startswith(f"p.yaml:{line}: {field}: method 'touch-et-adapt' rejects ")
    assert out.endswith(f"{FLOOR}. Got {shown} instead.")


def test_a_classifier_entry_is_checked_as_a_method_entry_is(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("name: t\ndataset: scene:tiny\nscheme: loso\nfeatures: [[flagg-stats]]\nclassifiers:\n"
                    "  - name: session-centred\n    params:\n      sd_floor: 0\n")
    r = CliRunner().invoke(cli, ["protocols", "validate", "--schema-only", str(path)])
    assert r.exit_code == 3 and (f"{path}:8: classifiers[0].params.sd_floor: classifier 'session-centred' rejects "
                                 f"{{'sd_floor': 0}}: {FLOOR}. Got 0 instead.") in r.output


@pytest.mark.parametrize("entry,start", [
    ("  - name: shift-augmented\n    params:\n      features: [contact-evidence]\n      crop: 0\n",
     "p.yaml:8: methods[0].params.crop: method 'shift-augmented' rejects {'features': ['contact-evidence'], "
     "'crop': 0}: The 'crop' parameter of ShiftAugmented must be a float in the range (0.0, 1.0]. Got 0 instead."),
    # at most 100 copies of each capture
    ("  - name: touch-et-shift\n    params:\n      copies: 1000000000000\n",
     "p.yaml:7: methods[0].params.copies: method 'touch-et-shift' rejects {'copies': 1000000000000}: The 'copies' "
     "parameter of ShiftAugmented must be an int in the range [0, 100]. Got 1000000000000 instead."),
    # inside a fusion part: the part's line (9)
    pytest.param("  - name: fusion\n    params:\n      parts:\n        - touch-et\n"
                 "        - {name: touch-et-shift, params: {crop: 0}}\n",
                 "p.yaml:9: methods[0].params.parts[1].params.crop: The 'crop' parameter of ShiftAugmented must be",
                 marks=needs_peers),
    # inside a written-out candidate: the value's line (12)
    ("  - name: nested-select\n    params:\n      candidates:\n        - touch-et\n"
     "        - features: [flagg-stats]\n          estimator: session-centred\n"
     "          params:\n            sd_floor: 0\n",
     f"p.yaml:12: methods[0].params.candidates[1].params.sd_floor: {FLOOR}. Got 0 instead."),
    # every point of a grid
    ("  - name: touch-et-adapt\n    params:\n      sd_floor: {grid: [0.001, 0]}\n",
     f"p.yaml:7: methods[0].params.sd_floor: method 'touch-et-adapt' rejects {{'sd_floor': 0}}: {FLOOR}. "
     "Got 0 instead."),
])
def test_shift_values_and_nested_values_are_refused_naming_their_line(tmp_path, entry, start):
    assert validate(tmp_path, entry).startswith(start)


@pytest.mark.parametrize("value", ["1e-09", "{grid: [0.001, 1e-09]}"])
def test_a_number_yaml_read_as_a_string_says_so(tmp_path, value):
    out = validate(tmp_path, f"  - name: touch-et-adapt\n    params:\n      sd_floor: {value}\n")
    assert out == (f"p.yaml:7: methods[0].params.sd_floor: method 'touch-et-adapt' rejects {{'sd_floor': '1e-09'}}: "
                   f"{FLOOR}. Got '1e-09' instead. (YAML read '1e-09' as a string, not a number: YAML 1.1 reads an "
                   "exponent as a number only after a dot and with a sign; write 1.0e-09)")


def test_a_quoted_number_is_not_said_to_be_read_as_a_string(tmp_path):
    out = validate(tmp_path, "  - name: touch-et-adapt\n    params:\n      sd_floor: '1e-09'\n")
    assert out.endswith("Got '1e-09' instead.")


@pytest.mark.parametrize("entry,start", [
    ("  - name: fusion\n    params:\n      parts: [touch-et]\n",
     "p.yaml:7: methods[0].params.parts: fusion needs at least 2 parts (the methods whose probabilities it sums), "
     "got 1"),
    ("  - name: touch-et-adapt\n    params:\n      params: {n_estimators: 1000000000000}\n",
     "p.yaml:7: methods[0].params.params.n_estimators: The 'n_estimators' parameter of SelectedExtraTrees must be "
     "an int in the range [1, 100000]. Got 1000000000000 instead."),
    ("  - name: touch-et\n    params:\n      n_estimators: 0\n",
     "p.yaml:7: methods[0].params.n_estimators: method 'touch-et' rejects {'n_estimators': 0}: The 'n_estimators' "
     "parameter of SelectedExtraTrees must be an int in the range [1, 100000]. Got 0 instead."),
    pytest.param("  - name: touch-rocket-fusion\n    params:\n      inner_folds: 1000000000000000000\n",
                 "p.yaml:7: methods[0].params.inner_folds: method 'touch-rocket-fusion' rejects {'inner_folds': "
                 "1000000000000000000}: The 'inner_folds' parameter of Fusion must be None or an int in the range "
                 "[2, 1000].", marks=needs_peers),
    ("  - name: touch-select\n    params:\n      inner_folds: 1\n",
     "p.yaml:7: methods[0].params.inner_folds: method 'touch-select' rejects {'inner_folds': 1}: The 'inner_folds' "
     "parameter of NestedSelection must be None or an int in the range [2, 1000]. Got 1 instead."),
])
def test_absurd_counts_and_a_one_part_fusion_are_refused_at_their_line(tmp_path, entry, start):
    assert validate(tmp_path, entry).startswith(start)


def test_counts_at_their_bounds_pass(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(HEAD + "  - {name: touch-et, params: {n_estimators: 100000}}\n"
                    "  - {name: touch-select, params: {inner_folds: 1000}}\n  - {name: touch-select, params: "
                    "{inner_folds: 2}}\n  - {name: touch-et-fast, params: {n_estimators: 1}}\n")
    r = CliRunner().invoke(cli, ["protocols", "validate", "--schema-only", str(path)])
    assert r.exit_code == 0, r.output


@needs_peers
def test_good_values_pass(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(HEAD + FUSION + "      weights: [[1, 3], [0, 1]]\n"
                    "  - {name: touch-et-adapt, params: {scale: true, sd_floor: 0.001}}\n"
                    "  - {name: touch-et-shift, params: {crop: 0.5, copies: 1}}\n")
    r = CliRunner().invoke(cli, ["protocols", "validate", "--schema-only", str(path)])
    assert r.exit_code == 0, r.output


def test_the_check_runs_when_the_classifier_is_fitted_too():
    # the same function the protocol's validation calls, from Python
    with pytest.raises(ParamError) as e:
        check_classifier_params("session-centred", {"sd_floor": 0.0})
    assert e.value.field == ("sd_floor",)
    est = make_classifier("session-centred", random_state=0, sd_floor=-1)
    with pytest.raises(ParamError, match=r"The 'sd_floor' parameter of SessionCentred must be a float in the range \(0\.0, inf\)\. Got -1 instead\."):
        est.fit(np.arange(8.0).reshape(4, 2), ["a", "b", "a", "b"])
