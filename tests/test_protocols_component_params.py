"""Each classifier's and method's parameters are checked when a protocol is read: a value the
estimator's constraints refuse (scikit-learn's own ``_parameter_constraints``, or those declared in
the same style on touchbench's estimators) is one ProtocolError with the file, line and field; a
boolean is never read as a number. Bounds below are taken from the documented constraints
(scikit-learn's, XGBoost's, Weka's, MATLAB's), not from the checks' output."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from touchbench.classifiers import CLASSIFIERS
from touchbench.cli.main import cli
from touchbench.core.errors import TouchbenchError
from touchbench.protocols.loading import parse_protocol

HEAD = "name: t\ndataset: scene:tiny\ntarget: gesture\nscheme: {name: kfold, k: 2, stratified: true}\n"  # 1-4
FEATURES = "features: [[sd]]\n"  # line 5


def classifier_entry(name: str, param: str, value: str) -> str:
    """A protocol whose one classifier entry sets ``param: value`` on line 8."""
    return HEAD + FEATURES + f"classifiers:\n  - name: {name}\n    params:\n      {param}: {value}\n"


def refusal(text: str) -> str:
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(text, "p.yaml")
    return str(e.value)


# ------------------------------------------------------------ the values that used to pass
@pytest.mark.parametrize("text,start", [
    (classifier_entry("gaus-boost-oob", "n_estimators", "0"), "p.yaml:9: classifiers[0].params.n_estimators: "),
    (classifier_entry("zhou-knn", "n_neighbors", "0"), "p.yaml:9: classifiers[0].params.n_neighbors: "),
    (classifier_entry("gaus-rf", "n_estimators", "true"), "p.yaml:9: classifiers[0].params.n_estimators: "),
    (classifier_entry("touch-extra-trees", "keep", "true"), "p.yaml:9: classifiers[0].params.keep: "),
    (classifier_entry("zhou-linear-svm", "box_constraint", "false"),
     "p.yaml:9: classifiers[0].params.box_constraint: "),
    (HEAD + "methods:\n  - name: touch-et-adapt\n    params:\n      params: {n_estimators: 1000000000000}\n",
     "p.yaml:8: methods[0].params.params.n_estimators: "),
    (HEAD + "methods:\n  - name: touch-rocket-fusion\n    params:\n      inner_folds: 1000000000000000000\n",
     "p.yaml:8: methods[0].params.inner_folds: "),
    (HEAD + "methods:\n  - name: touch-et\n    params:\n      n_estimators: true\n",
     "p.yaml:8: methods[0].params.n_estimators: "),
    (HEAD + "methods:\n  - name: fusion\n    params:\n      parts: [touch-et]\n",
     "p.yaml:8: methods[0].params.parts: fusion needs at least 2 parts"),
])
def test_a_value_no_task_could_run_is_refused_at_its_line(text, start):
    out = refusal(text)
    assert out.startswith(start), out
    assert len(out.splitlines()) == 1, out


def test_a_boolean_says_it_was_read_as_a_boolean():
    out = refusal(classifier_entry("zhou-knn", "n_neighbors", "true"))
    assert out.startswith("p.yaml:9: classifiers[0].params.n_neighbors: "), out
    assert "boolean" in out and "'true' was read as a YAML boolean" in out


def test_a_design_block_naming_an_unknown_method_is_refused_with_the_known_ones():
    text = (HEAD + FEATURES + "classifiers: [zhou-lda, gaus-rf]\n"  # line 6
            "design:\n  subjects: [s1]\n  methods: [gaus-fr]\n")  # methods on line 9
    out = refusal(text)
    assert out.startswith("p.yaml:9: design.methods[0]: design names method 'gaus-fr'"), out
    assert "did you mean 'gaus-rf'" in out


def test_a_boolean_stays_a_boolean_where_the_estimator_takes_one():
    # RandomForestClassifier: bootstrap is ["boolean"], verbose is ["verbose"] (an int or a bool)
    parse_protocol(HEAD + FEATURES + "classifiers:\n  - name: gaus-rf\n    params: {bootstrap: false, "
                   "verbose: true, n_estimators: 5}\n", "p.yaml")


# ------------------------------------------------------------ every classifier, at and beyond its bounds
#: classifier -> [(parameter, a value at its bound, a value beyond it)], from the documentation:
#: scikit-learn's parameter constraints of the estimator (or of the one a wrapper builds), XGBoost's
#: parameter ranges, Weka's (momentum in [0, 1]), MATLAB's (a positive polynomial order); the shared
#: counts (n_estimators 1..100000, inner_folds 2..1000) and the epochs' 100000 are touchbench's
BOUNDS: dict[str, list[tuple[str, str, str]]] = {
    "example-nearest-centroid": [("shrink_threshold", "0.001", "0")],  # (0, inf)
    "flagg-bayesnet": [("max_parents", "0", "-1"), ("alpha", "0.001", "0")],
    "flagg-logistic": [("ridge", "1.0e-12", "0"), ("max_iter", "0", "-1")],  # LogisticRegression max_iter >= 0
    "flagg-mlp": [("momentum", "1", "1.01"), ("max_epochs", "100000", "100001"), ("learning_rate", "0.001", "0")],
    "flagg-rf": [("min_samples_split", "2", "1"), ("n_estimators", "1", "0")],
    "gaus-boost": [("n_trees", "100000", "100001"), ("learning_rate", "0.001", "0")],
    "gaus-boost-oob": [("n_estimators", "100000", "100001"), ("n_trees", "1", "0")],
    "gaus-rf": [("n_estimators", "1", "0"), ("min_samples_leaf", "1", "0")],
    "jung-naive-bayes": [("var_smoothing", "0", "-1.0e-9")],  # [0, inf)
    "jung-svm": [("C", "0.001", "0")],  # SVC: C in (0, inf)
    "xgboost": [("subsample", "1", "1.5"), ("learning_rate", "1", "1.5"), ("max_depth", "0", "-1")],
    "touch-extra-trees": [("keep", "1", "0"), ("max_features", "1.0", "1.5")],  # ExtraTrees: (0, 1] as a fraction
    "touch-extra-trees-fast": [("n_estimators", "1", "0")],
    "touch-extra-trees-tuned": [("max_groups_loo", "0", "-1"), ("inner_folds", "2", "1")],
    "zhou-bagged-trees": [("n_estimators", "100000", "100001"), ("max_features", "1.0", "0.0")],
    "zhou-knn": [("n_neighbors", "1", "0")],  # KNeighborsClassifier: n_neighbors >= 1
    "zhou-weighted-knn": [("n_neighbors", "1", "0")],
    "zhou-lda": [("tol", "0", "-1")],  # LinearDiscriminantAnalysis: tol in [0, inf)
    "zhou-linear-svm": [("box_constraint", "0.001", "0")],  # the binary SVCs' C in (0, inf)
    "zhou-quadratic-svm": [("polynomial_order", "1", "0")],
    "zhou-tree": [("max_leaf_nodes", "2", "1"), ("min_samples_split", "2", "1")],
}
#: classifiers whose bounds are worked out in tests/test_classifier_constraints.py instead: the deep
#: networks, the peers' time-series classifiers and the wrappers (every declared bound of every
#: classifier is also walked by tests/test_registry_params_walk.py)
LEFT = {"cnn", "inception-time", "minirocket", "multirocket", "multirocket-hydra", "quant", "rdst",
        "fusion", "two-stage", "nested-select", "session-centred", "shift-augmented", "quiet-gated"}


def test_every_registered_classifier_is_placed():
    assert set(CLASSIFIERS.names()) == set(BOUNDS) | LEFT


@pytest.mark.parametrize("name,param,at,beyond", [(n, *b) for n, bs in BOUNDS.items() for b in bs])
def test_a_value_at_the_bound_passes_and_one_beyond_is_refused(name, param, at, beyond):
    parse_protocol(classifier_entry(name, param, at), "p.yaml")
    out = refusal(classifier_entry(name, param, beyond))
    assert out.startswith(f"p.yaml:9: classifiers[0].params.{param}: "), out


def test_values_at_their_bounds_run(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text(HEAD + FEATURES + "classifiers:\n"
                    "  - {name: zhou-knn, params: {n_neighbors: 1}}\n"
                    "  - {name: zhou-quadratic-svm, params: {polynomial_order: 1}}\n"
                    "  - {name: touch-extra-trees, params: {keep: 1, n_estimators: 1, max_features: 1.0}}\n"
                    "seed: 0\n")
    r = CliRunner().invoke(cli, ["run", str(path), "--out", str(tmp_path / "res")])
    assert r.exit_code == 0, r.output


def test_a_refused_choice_lists_the_choices_in_the_same_order_in_every_process(tmp_path):
    # a set of strings iterates in an order that depends on the hash seed: two interpreters with
    # different seeds must still print the choices alike, sorted
    import os
    import subprocess
    import sys

    from helpers import SUBPROCESS_HANG_S

    code = ("from sklearn.utils._param_validation import StrOptions\n"
            "from touchbench.core.constraints import declared_failures\n"
            "print(declared_failures({'p': [StrOptions({'delta', 'alpha', 'charlie', 'bravo'})]}, {'p': 'x'}, 'o')['p'])")
    outs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                           timeout=SUBPROCESS_HANG_S, env={**os.environ, "PYTHONHASHSEED": str(seed)}).stdout
            for seed in (1, 2, 3, 4)}
    assert outs == {"The 'p' parameter of o must be a str among {'alpha', 'bravo', 'charlie', 'delta'}. "
                    "Got 'x' instead.\n"}
