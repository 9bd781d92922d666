"""Protocol files: the schema, its shorthands and grids, and one clear error per mistake.

Every invalid protocol must fail at parse time, naming the file, the line
and the field (the lines below are counted by hand in the YAML texts).
"""

from __future__ import annotations

import pytest

from touchbench.engine.testing import random_dataset, components_for_tests
from touchbench.protocols.entries import expand_grid
from touchbench.protocols.errors import ProtocolError
from touchbench.protocols.loading import load_protocol, parse_protocol

BASE = """\
name: t
dataset: data.parquet
scheme: loso
features:
  - [test-mean]
classifiers:
  - test-logreg
"""

# an expected block with one 2 x 2 confusion matrix (lines 8-17 after BASE)
CONFUSION = ("expected:\n  confusions:\n    - classifier: test-logreg\n      source: T1\n      tolerance: 10\n      rows: predicted\n      classes: [a, b]\n      matrix:\n        - [1, 2]\n        - [3, 4]\n")


@pytest.fixture(autouse=True)
def components(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with components_for_tests():
        random_dataset().to_parquet(tmp_path / "data.parquet")
        yield


def error(text: str) -> str:
    with pytest.raises(ProtocolError) as e:
        parse_protocol(text, "protocols/x.yaml")
    return str(e.value)


def test_valid_protocol_and_shorthands():
    p = parse_protocol(BASE, "protocols/x.yaml")
    assert p.name == "t" and p.dataset.name == "data.parquet" and p.scheme.name == "loso"
    assert p.target == "gesture" and p.seed == 0 and p.repetitions == 1
    assert [c.label for c in p.combinations()] == ["test-mean"]
    assert [c.label for c in p.classifier_entries()] == ["test-logreg"]


def test_name_defaults_to_file_stem(tmp_path):
    f = tmp_path / "my-proto.yaml"
    f.write_text(BASE.replace("name: t\n", ""))
    assert load_protocol(f).name == "my-proto"


def test_combinations_each_alone_then_combined():
    text = BASE.replace("  - [test-mean]\n", "  - test-mean\n  - [test-centered]\n  - [test-mean, test-centered]\n")
    p = parse_protocol(text, "x.yaml")
    assert [c.label for c in p.combinations()] == ["test-mean", "test-centered", "test-mean+test-centered"]
    assert p.combinations()[2].names == ["test-mean", "test-centered"]


def test_grid_expands_to_labelled_entries():
    assert expand_grid({"a": 1, "b": {"grid": [2, 3]}, "c": {"grid": ["x", "y"]}}) == [
        {"a": 1, "b": 2, "c": "x"}, {"a": 1, "b": 2, "c": "y"}, {"a": 1, "b": 3, "c": "x"}, {"a": 1, "b": 3, "c": "y"}]
    assert expand_grid({"layers": [10, 20]}) == [{"layers": [10, 20]}]  # a plain list is a value, not a grid
    text = BASE.replace("  - test-logreg\n", "  - {name: test-forest, params: {n_estimators: {grid: [3, 5]}, max_features: 0.5}}\n")
    entries = parse_protocol(text, "x.yaml").classifier_entries()
    assert [e.label for e in entries] == ["test-forest(n_estimators=3)", "test-forest(n_estimators=5)"]
    assert entries[1].params == {"n_estimators": 5, "max_features": 0.5}
    text = BASE.replace("[test-mean]", "[{name: test-mean, params: {scale: {grid: [1, 2]}}}]")
    assert [c.label for c in parse_protocol(text, "x.yaml").combinations()] == ["test-mean(scale=1)", "test-mean(scale=2)"]


def test_content_hash_ignores_comments_and_description():
    a = parse_protocol(BASE, "x.yaml")
    b = parse_protocol("# a comment\n" + BASE + "description: words\n", "x.yaml")
    c = parse_protocol(BASE + "seed: 3\n", "x.yaml")
    assert a.content_hash == b.content_hash != c.content_hash
    assert a.text_hash != b.text_hash


@pytest.mark.parametrize("text,expected", [
    (BASE.replace("[test-mean]", "[test-maen]"),
     "protocols/x.yaml:5: features[0][0].name: unknown feature set 'test-maen'; did you mean 'test-mean'"),
    (BASE + "  - name: test-logerg\n",
     "protocols/x.yaml:8: classifiers[1].name: unknown classifier 'test-logerg'; did you mean 'test-logreg'"),
    (BASE.replace("scheme: loso\n", ""), "protocols/x.yaml:1: scheme: missing required field"),
    (BASE + "seed: ten\n", "protocols/x.yaml:8: seed: Input should be a valid integer"),
    (BASE + "repetitions: 0\n", "protocols/x.yaml:8: repetitions: Input should be greater than or equal to 1, got 0"),
    (BASE.replace("scheme: loso", "scheme: loos"),
     "protocols/x.yaml:3: scheme.name: unknown evaluation scheme 'loos'; did you mean 'loso'?"),
    (BASE.replace("dataset: data.parquet", "dataset:\n  name: data.parquet\n  filters:\n    gesture: []"),
     "protocols/x.yaml:5: dataset.filters.gesture: the gesture filter is empty"),
    (BASE + "clasifiers: []\n", "protocols/x.yaml:8: clasifiers: unknown field; did you mean 'classifiers'?"),
    (BASE.replace("scheme: loso", "scheme:\n  name: kfold\n  k: 1"),
     "protocols/x.yaml:5: scheme.k: Input should be greater than or equal to 2, got 1"),
    (BASE.replace("scheme: loso", "scheme:\n  name: kfold\n  kk: 3"),
     "protocols/x.yaml:5: scheme.kk: unknown field; did you mean 'k'?"),
    (BASE.replace("scheme: loso", "scheme:\n  name: early\n  base: {name: kfold, k: x}\n  frames: [3]"),
     "protocols/x.yaml:5: scheme.base.k: Input should be a valid integer"),
    (BASE.replace("scheme: loso", "scheme:\n  name: early\n  base: loso"),
     "protocols/x.yaml:3: scheme: give exactly one of 'frames'"),
    (BASE.replace("  - test-logreg", "  - {name: test-forest, params: {n_estimator: 3}}"),
     "protocols/x.yaml:7: classifiers[0].params.n_estimator: unknown parameter 'n_estimator' for classifier "
     "'test-forest'; did you mean 'n_estimators'?"),
    (BASE.replace("  - test-logreg", "  - {name: test-logreg, params: {random_state: 3}}"),
     "protocols/x.yaml:7: classifiers[0].params.random_state: random_state is derived from the protocol's seed"),
    (BASE.replace("[test-mean]", "[{name: test-mean, params: {scal: 2}}]"),
     "protocols/x.yaml:5: features[0][0].params.scal: unknown parameter 'scal' for feature set 'test-mean'; did you mean 'scale'?"),
    (BASE + "expected:\n  results:\n    - {features: [test-centered], classifier: test-logreg, value: 50}\n",
     "protocols/x.yaml:10: expected.results[0].features: no feature combination ['test-centered'] in this protocol"),
    (BASE + "  - [oops\n", "protocols/x.yaml:9: invalid YAML"),
    (BASE + "target: subject\n", "protocols/x.yaml:8: target: target 'subject' (person identification) needs each test"),
    (BASE + "target: ''\n", "protocols/x.yaml:8: target: String should have at least 1 character"),
    (BASE.replace("data.parquet", "haartt"), "protocols/x.yaml:2: dataset.name: unknown dataset 'haartt'; did you mean 'haart'"),
    (BASE.replace("data.parquet", "missing/file.parquet"), "protocols/x.yaml:2: dataset.name: no dataset file 'missing/file.parquet'"),
    (BASE.replace("  - test-logreg", "  - {name: test-forest, params: {n_estimators: {grid: []}}}"),
     "protocols/x.yaml:7: classifiers[0].params.n_estimators.grid: a grid must be a non-empty list"),
    (BASE.replace("  - [test-mean]", "  - []"), "protocols/x.yaml:5: features[0]: this feature combination is empty"),
    (BASE.replace("  - [test-mean]", "  - 3"), "protocols/x.yaml:5: features[0]: Input should be a valid list"),
    (BASE.replace("classifiers:\n  - test-logreg\n", "classifiers: []\n"), "protocols/x.yaml:6: classifiers: List should have at least 1 item"),
    (BASE.replace("name: t", "name: a/b"), "protocols/x.yaml:1: name: name 'a/b' must be letters, digits"),
    # the expected numbers that are not one accuracy (lines 8-17: expected, confusions, classifier, source,
    # tolerance, rows, classes, matrix, its two rows)
    (BASE + CONFUSION.replace("[3, 4]", "[3]"),
     "protocols/x.yaml:17: expected.confusions[0].matrix[1]: row 2 (b) has 1 count for 2 classes: the matrix is square"),
    (BASE + CONFUSION.replace("        - [3, 4]\n", ""),
     "protocols/x.yaml:15: expected.confusions[0].matrix: 1 row for 2 classes: one row per class"),
    (BASE + CONFUSION.replace("[1, 2]", "[1, -2]"),
     "protocols/x.yaml:16: expected.confusions[0].matrix[0][1]: Input should be greater than or equal to 0, got -2"),
    (BASE + CONFUSION.replace("[a, b]", "[a, a]"),
     "protocols/x.yaml:14: expected.confusions[0].classes: each class once: a repeated"),
    (BASE + CONFUSION.replace("rows: predicted", "rows: columns"),
     "protocols/x.yaml:13: expected.confusions[0].rows: Input should be 'predicted' or 'true', got 'columns'"),
    (BASE + CONFUSION.replace("      source: T1\n", ""),
     "protocols/x.yaml:10: expected.confusions[0].source: missing required field"),
    (BASE + CONFUSION.replace("classifier: test-logreg", "classifier: test-logerg"),
     "protocols/x.yaml:10: expected.confusions[0].classifier: no classifier entry labelled 'test-logerg' in this "
     "protocol; did you mean 'test-logreg'"),
    (BASE + "expected:\n  standard_deviations:\n    - {classifier: test-logreg, value: -1, tolerance: 5, source: T2}\n",
     "protocols/x.yaml:10: expected.standard_deviations[0].value: Input should be greater than or equal to 0, got -1"),
    (BASE.replace("  - test-logreg", "  - {name: test-forest, params: {n_estimators: {grid: [3, 5]}}}")
     + "expected:\n  best_parameters:\n    - {classifier: test-forest, parameter: n_estimators, value: 4, source: F5}\n",
     "protocols/x.yaml:10: expected.best_parameters[0].value: 4 is not in the grid of n_estimators: 3, 5"),
    (BASE + "expected:\n  best_parameters:\n    - {classifier: test-logreg, parameter: C, value: 1, source: F5}\n",
     "protocols/x.yaml:10: expected.best_parameters[0].parameter: test-logreg has no grid of 'C' to take the best of"),
    (BASE + "expected:\n  source: Table 1\n",
     "protocols/x.yaml:8: expected: no paper numbers: give results, standard_deviations, confusions or best_parameters"),
    ("", "protocols/x.yaml: the protocol is empty"),
    ("- a\n- b\n", "protocols/x.yaml:1: a protocol is a mapping"),
])
def test_invalid_protocol_one_clear_message(text, expected):
    msg = error(text)
    assert msg.startswith(expected), msg
    assert "\n" not in msg  # one mistake, one line


def test_unknown_gaus_classifier_suggests_the_real_name():
    from touchbench.classifiers import CLASSIFIERS

    if "gaus-rf" not in CLASSIFIERS:
        pytest.fail("gaus-rf is not registered")
    msg = error(BASE + "  - name: gaus-fr\n")
    assert msg.startswith("protocols/x.yaml:8: classifiers[1].name: unknown classifier 'gaus-fr'; did you mean 'gaus-rf'")


def test_several_mistakes_are_all_listed():
    msg = error(BASE.replace("[test-mean]", "[test-maen]").replace("scheme: loso", "scheme: loos"))
    lines = msg.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("protocols/x.yaml:3: scheme.name") or lines[1].startswith("protocols/x.yaml:3: scheme.name")


# ------------------------------------------------------------- repeated sets, YAML booleans
def test_a_feature_set_listed_twice_in_a_combination_is_refused_at_its_second_place():
    msg = error(BASE.replace("  - [test-mean]", "  - [test-mean, test-mean]"))
    assert msg == ("protocols/x.yaml:5: features[0][1]: feature set 'test-mean' is listed twice in this combination "
                   "(also at features[0][0]): list each feature set once")
    msg = error("name: t\ndataset: data.parquet\nscheme: loso\nmethods:\n"
                "  - {features: [test-mean, {name: test-mean}], estimator: test-logreg}\n")
    assert msg.startswith("protocols/x.yaml:5: methods[0].features[1]: feature set 'test-mean' is listed twice")


@pytest.mark.parametrize("written, where, line, value", [
    ("no", "classifiers:\n  - no\n", "7: classifiers[0]", "False"),
    ("off", "classifiers:\n  - {name: off}\n", "7: classifiers[0].name", "False"),
    ("yes", "classifiers:\n  - test-logreg\ntarget: yes\n", "8: target", "True"),
])
def test_a_yaml_boolean_where_a_name_is_expected_is_shown_as_written(written, where, line, value):
    msg = error(BASE.replace("classifiers:\n  - test-logreg\n", where))
    assert msg.startswith(f"protocols/x.yaml:{line}: ")
    assert msg.endswith(f"({written!r} was read as a YAML boolean, {value}: quote it, \"{written}\", "
                        "where a name or text is meant)")


def test_a_yaml_boolean_in_a_filter_is_shown_as_written(tmp_path):
    from touchbench.engine.planning import prepare_evaluation

    p = parse_protocol(BASE.replace("dataset: data.parquet", "dataset: {name: data.parquet, filters: {gesture: [no]}}"),
                       "protocols/x.yaml")
    with pytest.raises(ProtocolError, match=r"^protocols/x.yaml:2: dataset.filters.gesture\[0\]: gesture 'False' is "
                                            r"not in the dataset .*\('no' was read as a YAML boolean, False"):
        prepare_evaluation(p)


# ------------------------------------------------- a paper number's cause and its kind
# lines 8-12 after BASE: expected, results, features, classifier, value; 13 on the lines under test
RESULT = "expected:\n  results:\n    - features: [test-mean]\n      classifier: test-logreg\n      value: 50\n"


@pytest.mark.parametrize("extra,expected", [
    # the former form: a cause as text, with measured_by beside it
    ("      cause: folds share subjects\n      measured_by: touchbench run p.yaml\n",
     "protocols/x.yaml:13: expected.results[0].cause: a cause is a mapping with its kind: {kind: measured"),
    ("      measured_by: touchbench run p.yaml\n",
     "protocols/x.yaml:13: expected.results[0].measured_by: measured_by is now a measured cause's command"),
    ("      cause: {text: folds share subjects}\n",
     "protocols/x.yaml:13: expected.results[0].cause.kind: a cause needs its kind: one of measured, ruled_out, "
     "unexplained"),
    ("      cause: {kind: guessed}\n",
     "protocols/x.yaml:13: expected.results[0].cause.kind: Input should be 'measured', 'ruled_out' or 'unexplained'"),
    ("      cause: {kind: measured, text: folds share subjects, command: touchbench run p.yaml}\n",
     "protocols/x.yaml:13: expected.results[0].cause.output: a measured cause needs output: what that command "
     "printed or gave"),
    ("      cause: {kind: measured, text: folds, output: '60.0'}\n",
     "protocols/x.yaml:13: expected.results[0].cause.command: a measured cause needs command"),
    ("      cause: {kind: measured, text: folds, command: python x.py, output: '60.0'}\n",
     "protocols/x.yaml:13: expected.results[0].cause.command: a command is a touchbench command (starting "
     "'touchbench '), got 'python x.py'"),
    ("      cause: {kind: ruled_out, text: the features}\n",
     "protocols/x.yaml:13: expected.results[0].cause.ruled_out: a ruled_out cause lists what was excluded"),
    ("      cause: {kind: unexplained, command: touchbench run p.yaml}\n",
     "protocols/x.yaml:13: expected.results[0].cause.command: command belongs to a measured cause; this cause is "
     "unexplained"),
    ("      cause: {kind: ruled_out, ruled_out: [{tried: grouped folds, gave: '60.0'}]}\n",
     "protocols/x.yaml:13: expected.results[0].cause.ruled_out[0].command: give one of command"),
    ("      cause:\n        kind: ruled_out\n        ruled_out:\n          - {tried: a, command: run x, gave: b}\n",
     "protocols/x.yaml:16: expected.results[0].cause.ruled_out[0].command: a command is a touchbench command"),
    ("      cause: {kind: measured, text: folds, command: 'touchbench run p.yaml; rm -rf x', output: '60.0'}\n",
     "protocols/x.yaml:13: expected.results[0].cause.command: a command is one touchbench command, without shell "
     "operators: 'touchbench run p.yaml; rm -rf x' has ';'"),
    ("      cause: {kind: measured, text: f, command: 'touchbench run p.yaml && echo $(id)', output: '6'}\n",
     "protocols/x.yaml:13: expected.results[0].cause.command: a command is one touchbench command, without shell "
     "operators: 'touchbench run p.yaml && echo $(id)' has '&&' '$('"),
    ("      cause:\n        kind: ruled_out\n        ruled_out:\n"
     "          - {tried: a, command: 'touchbench run x | tee `y` > z < w || q', gave: b}\n",
     "protocols/x.yaml:16: expected.results[0].cause.ruled_out[0].command: a command is one touchbench command, "
     "without shell operators: 'touchbench run x | tee `y` > z < w || q' has '||' '|' '`' '>' '<'"),
])
def test_a_cause_says_its_kind_and_what_backs_it(extra, expected):
    msg = error(BASE + RESULT + extra)
    assert msg.startswith(expected), msg
    assert "\n" not in msg


def test_a_cause_of_each_kind_is_kept():
    measured = "      cause: {kind: measured, text: folds, command: touchbench run p.yaml, output: '60.0'}\n"
    r = parse_protocol(BASE + RESULT + measured, "protocols/x.yaml").expected.results[0]
    assert (r.cause.kind, r.cause.text, r.cause.command, r.cause.output) == (
        "measured", "folds", "touchbench run p.yaml", "60.0")
    # ruled out: the grouped folds' run of this row gave 44.3, 5.7 from the paper's 50 (tolerance 3)
    ruled = ("      cause: {kind: ruled_out, text: the features, ruled_out: [{tried: grouped folds, "
             "command: touchbench run g.yaml, row: 44.3, gave: '44.3'}, {tried: Weka, source: docs/research/w.md, "
             "gave: '49.0'}]}\n")
    r = parse_protocol(BASE + RESULT + ruled, "protocols/x.yaml").expected.results[0]
    assert [(t.tried, t.command, t.source, t.row, t.gave) for t in r.cause.ruled_out] == [
        ("grouped folds", "touchbench run g.yaml", None, 44.3, "44.3"), ("Weka", None, "docs/research/w.md", None, "49.0")]
    r = parse_protocol(BASE + RESULT + "      cause: {kind: unexplained}\n", "protocols/x.yaml").expected.results[0]
    assert (r.cause.kind, r.cause.text, r.cause.ruled_out) == ("unexplained", None, [])
    assert parse_protocol(BASE + RESULT, "protocols/x.yaml").expected.results[0].cause is None


# ------------------------------------------------- the same method twice: at the second entry's line
@pytest.mark.parametrize("text,expected", [
    ("name: t\ndataset: data.parquet\nscheme: loso\nmethods:\n  - touch-et\n  - touch-xgb\n  - touch-et\n",
     "protocols/x.yaml:7: methods[2]: this entry describes the same method as methods[0] ('touch-et')"),
    (BASE + "  - test-logreg\n",
     "protocols/x.yaml:8: classifiers[1]: this entry describes the same method as classifiers[0] ('test-logreg')"),
    (BASE.replace("  - [test-mean]\n", "  - [test-mean]\n  - [test-mean]\n"),
     "protocols/x.yaml:6: features[1]: this entry describes the same method as features[0] ('test-logreg')"),
    # the same method under another label is still the same tasks
    ("name: t\ndataset: data.parquet\nscheme: loso\nmethods:\n  - touch-et\n  - {name: touch-et, label: again}\n",
     "protocols/x.yaml:6: methods[1]: this entry describes the same method as methods[0] ('again')"),
])
def test_the_same_method_twice_is_refused_at_the_second_entry(text, expected):
    msg = error(text)
    assert msg.startswith(expected) and msg.endswith("so the same tasks: list each method once"), msg


def test_methods_that_differ_in_a_parameter_are_kept():
    p = parse_protocol("name: t\ndataset: data.parquet\nscheme: loso\nmethods:\n  - touch-xgb\n"
                       "  - {name: touch-et, params: {n_estimators: {grid: [10, 20]}}}\n", "protocols/x.yaml")
    assert len(p.evaluated_methods()) == 3


# ------------------------------------------------- a design block names methods the protocol evaluates
@pytest.mark.parametrize("design,expected", [
    ("design:\n  subjects: [s1]\n  methods: [test-logreg, test-lgoreg]\n",
     "protocols/x.yaml:10: design.methods[1]: design names method 'test-lgoreg', which this protocol does not "
     "evaluate; did you mean 'test-logreg'"),
    ("design:\n  - {subjects: [s1], methods: [test-logreg]}\n  - {subjects: [s2], methods: [forest]}\n",
     "protocols/x.yaml:10: design[1].methods[0]: design names method 'forest', which this protocol does not evaluate"),
])
def test_a_design_naming_a_method_not_evaluated_is_refused(design, expected):
    msg = error(BASE + design)
    assert msg.startswith(expected), msg


def test_a_design_names_a_method_by_its_label_or_its_full_name():
    for name in ("test-logreg", "test-mean / test-logreg"):
        p = parse_protocol(BASE + f"design:\n  subjects: [s1]\n  methods: ['{name}']\n", "protocols/x.yaml")
        assert p.design.methods == [name]
