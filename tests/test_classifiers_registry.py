"""The classifier registry: names, tags, parameter handling, the command
line listing, and life without PyTorch."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from helpers import SUBPROCESS_HANG_S
from click.testing import CliRunner

from snapshots.registries import builtin_names, snapshot

from touchbench.classifiers import CLASSIFIERS, make_classifier
from touchbench.core.errors import TouchbenchError, UnknownNameError
from touchbench.datasets.haart import HAART_SENSOR

EXPECTED = snapshot()["classifiers"]  # tests/snapshots/registry-names.json (make snapshots)
EXTRAS = {"cnn": "deep", "inception-time": "deep", "fusion": "peers", "minirocket": "peers", "multirocket": "peers", "multirocket-hydra": "peers,deep", "quant": "peers,deep",
          "rdst": "peers", "xgboost": "xgboost"}


def test_registry_holds_exactly_the_documented_names():
    assert builtin_names(CLASSIFIERS) == sorted(EXPECTED)


@pytest.mark.parametrize("name", EXPECTED)
def test_entry_tags_and_defaults(name):
    e = CLASSIFIERS.entry(name)
    assert e.description and e.tags["source"]
    assert e.tags["extra"] == EXTRAS.get(name)
    est = make_classifier(name, random_state=7)
    params = est.get_params()
    for k, v in e.tags["defaults"].items():  # the defaults listed are the ones built
        assert params[k] == v, (name, k)
    if "random_state" in params:
        assert params["random_state"] == 7
    if "n_jobs" in params:
        assert params["n_jobs"] == 1


def test_paper_settings_are_the_defaults():
    # Gaus et al. section 4; Flagg Appendix A; Zhou et al. section 4.2; Al-mashhadani Table 1 / Fig. 5
    assert make_classifier("gaus-rf").n_estimators == 1000
    b = make_classifier("gaus-boost")
    assert (b.n_estimators, b.n_trees) == (500, 1000)
    lr = make_classifier("flagg-logistic")
    assert lr.ridge == 1e-8
    mlp = make_classifier("flagg-mlp")
    assert (mlp.hidden_layers, mlp.learning_rate, mlp.momentum, mlp.max_epochs) == ("a", 0.3, 0.2, 500)
    rf = make_classifier("flagg-rf")
    assert (rf.n_estimators, rf.max_features) == (10, 5)
    assert make_classifier("zhou-tree").max_leaf_nodes == 21  # 20 splits
    assert make_classifier("zhou-knn").n_neighbors == 10
    assert make_classifier("zhou-weighted-knn").distance_weight == "squaredinverse"
    assert make_classifier("zhou-quadratic-svm").polynomial_order == 2
    assert make_classifier("zhou-bagged-trees").n_estimators == 30
    cnn = make_classifier("cnn", sensor=HAART_SENSOR)  # the grid is the sensor's (the engine passes it)
    assert (cnn.L, tuple(cnn.sensor.grid), cnn.train_windows, cnn.test_windows) == (30, (8, 8), "first", "first")


def test_params_override_defaults_and_unknown_params_are_refused():
    assert make_classifier("gaus-rf", n_estimators=7).n_estimators == 7
    with pytest.raises(TouchbenchError, match="unknown parameter.*n_trees.*known:"):
        make_classifier("gaus-rf", n_trees=7)
    with pytest.raises(UnknownNameError, match="gaus-rf"):
        make_classifier("gaus_rf")


@pytest.mark.parametrize("name", ["xgboost", "zhou-weighted-knn", "flagg-bayesnet", "gaus-boost"])
def test_string_labels_in_string_labels_out(name):
    rng = np.random.default_rng(0)
    y = np.repeat(np.array(["pat", "rub", "stroke"]), 20)
    X = rng.normal(size=(60, 4)) + np.repeat(np.eye(3, 4) * 4, 20, axis=0)
    est = make_classifier(name, random_state=0, **({"n_trees": 5, "n_estimators": 3} if name == "gaus-boost" else {}))
    pred = est.fit(X, y).predict(X)
    assert set(pred) <= {"pat", "rub", "stroke"}
    assert np.mean(pred == y) > 0.9


def test_refit_with_the_same_seed_is_bit_identical():
    rng = np.random.default_rng(1)
    X, y = rng.normal(size=(80, 6)), rng.integers(0, 3, 80).astype(str)
    for name, kw in [("gaus-rf", {"n_estimators": 20}), ("xgboost", {"n_estimators": 20}),
                     ("flagg-mlp", {"max_epochs": 5}), ("zhou-quadratic-svm", {})]:
        a = make_classifier(name, random_state=5, **kw).fit(X, y)
        b = make_classifier(name, random_state=5, **kw).fit(X, y)
        f = "predict_proba" if hasattr(a, "predict_proba") else "decision_function"
        assert np.array_equal(getattr(a, f)(X), getattr(b, f)(X)), name


def test_cli_list_shows_every_classifier_with_source_and_defaults():
    from touchbench.cli.classifiers import classifiers

    res = CliRunner().invoke(classifiers, ["list"])
    assert res.exit_code == 0, res.output
    for name in EXPECTED:
        assert f"\n{name}  " in "\n" + res.output
    n = len(CLASSIFIERS.names())  # touchbench's own and any installed plugin's (tests/test_plugins.py)
    assert res.output.count("    source:   ") == n and res.output.count("    defaults: ") == n
    assert "n_estimators=1000" in res.output
    rows = json.loads(CliRunner().invoke(classifiers, ["list", "--json"]).output)
    assert [r["name"] for r in rows if r["plugin"] is None] == sorted(EXPECTED)
    assert all(r["available"] for r in rows)  # torch and aeon are in the development venv


def test_cli_is_registered_in_the_main_group():
    from touchbench.cli.main import cli

    assert "classifiers" in cli.list_commands(None) and cli.get_command(None, "classifiers").name == "classifiers"


_NO_TORCH = textwrap.dedent("""
    import sys, json

    class _NoTorch:  # a finder that makes torch and xgboost unimportable, as if they were not installed
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("torch", "xgboost"):
                raise ModuleNotFoundError(f"No module named {name!r}")
            return None

    sys.meta_path.insert(0, _NoTorch())
    import numpy as np
    from click.testing import CliRunner
    from touchbench.classifiers import CLASSIFIERS, make_classifier
    from touchbench.cli.classifiers import classifiers
    from touchbench.core.errors import TouchbenchError
    out = {"names": CLASSIFIERS.names()}
    res = CliRunner().invoke(classifiers, ["list"])
    out["list_exit"] = res.exit_code
    out["cnn_line"] = [l for l in res.output.splitlines() if l.startswith("cnn ")][0]
    out["xgb_line"] = [l for l in res.output.splitlines() if l.startswith("xgboost ")][0]
    try:
        make_classifier("xgboost").fit(np.zeros((4, 2)), ["a", "b", "a", "b"])
    except TouchbenchError as e:
        out["xgb_error"] = str(e)
    try:
        make_classifier("cnn")
        out["cnn_error"] = None
    except TouchbenchError as e:
        out["cnn_error"] = str(e)
    from touchbench.classifiers.cnn import HaartCNNClassifier
    try:
        HaartCNNClassifier().fit(np.zeros((4, 64)), ["a", "b", "a", "b"])
    except TouchbenchError as e:
        out["fit_error"] = str(e)
    X = np.random.default_rng(0).normal(size=(30, 3)); y = np.array(["a", "b", "c"] * 10)
    make_classifier("zhou-knn").fit(X, y).predict(X)
    make_classifier("flagg-bayesnet").fit(X, y).predict(X)
    out["torch_imported"] = "torch" in sys.modules
    print(json.dumps(out))
""")


def test_without_torch_everything_else_works_and_cnn_says_how_to_install():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", _NO_TORCH], capture_output=True, text=True, env=env, timeout=SUBPROCESS_HANG_S)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert "cnn" in out["names"] and out["list_exit"] == 0
    assert "not installed" in out["cnn_line"] and "pip install 'touchbench[deep]'" in out["cnn_line"]
    for key in ("cnn_error", "fit_error"):
        assert "pip install 'touchbench[deep]'" in out[key] and "pip install torch)" in out[key]
    assert not out["torch_imported"]
    # XGBoost likewise: listed as not installed, refused when fitted, with both of its extras named
    for key in ("xgb_line", "xgb_error"):
        assert "pip install 'touchbench[xgboost]'" in out[key] and "'touchbench[xgboost-cpu]'" in out[key]
    assert "not installed" in out["xgb_line"]


def test_listing_does_not_import_torch():
    code = ("import sys; from touchbench.cli.classifiers import classifiers; from click.testing import CliRunner; "
            "CliRunner().invoke(classifiers, ['list']); print('torch' in sys.modules)")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=SUBPROCESS_HANG_S)
    assert proc.stdout.strip() == "False", proc.stderr


def test_a_renamed_classifier_says_what_it_became():
    # the extra-trees entries were called sota-et, sota-et-fast and sota-et-tuned before they got their names
    for old, new in (("sota-et", "touch-extra-trees"), ("sota-et-fast", "touch-extra-trees-fast"),
                     ("sota-et-tuned", "touch-extra-trees-tuned")):
        assert old not in CLASSIFIERS and new in CLASSIFIERS
        with pytest.raises(UnknownNameError, match=f"classifier '{old}' was renamed '{new}'"):
            make_classifier(old)
        assert f"renamed '{new}'" in CLASSIFIERS.suggest(old)


def test_the_former_names_table_maps_only_to_registered_names():
    from touchbench.core.registry import RENAMED
    from touchbench.datasets.formats import FORMATS

    registries = {"classifier": CLASSIFIERS, "file format": FORMATS}
    assert set(RENAMED) <= set(registries)
    for kind, table in RENAMED.items():
        for old, new in table.items():
            assert old not in registries[kind] and new in registries[kind], (kind, old, new)
    # the file format that became `table`, on the command line (a protocol or a reader gets the same words)
    from touchbench.cli.main import cli

    res = CliRunner().invoke(cli, ["predict", "m.joblib", "x.csv", "--format", "long"])
    assert res.exit_code == 2 and "file format 'long' was renamed 'table'" in res.output
