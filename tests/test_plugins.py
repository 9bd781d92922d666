"""Plugins: installed packages that register entries through the entry-point
group ``touchbench.plugins``.

The example plugin (examples/touchbench-plugin-example, installed by ``make
setup``) must be installed: its tests fail under CI=true when it is not (the
``example_plugin`` fixture). The broken plugins are fake distributions
written into a temporary folder (a ``*.dist-info`` with ``entry_points.txt``
is all importlib.metadata needs) and run in a fresh process, since plugins
are loaded once per process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from helpers import SUBPROCESS_HANG_S

from touchbench.classifiers import CLASSIFIERS
from touchbench.cli.main import cli
from touchbench.core.errors import RegistrationError
from touchbench.core.plugins import PluginInfo, importing
from touchbench.core.registry import Registry
from touchbench.datasets.model import SensorSpec
from touchbench.engine import run_protocol
from touchbench.engine.testing import SENSOR, random_dataset
from touchbench.features import FEATURES
from touchbench.protocols.loading import parse_protocol

REPO = Path(__file__).resolve().parent.parent
FEATURE, CLASSIFIER = "example-pressure-stats", "example-nearest-centroid"

PROTOCOL = """\
name: plugin-small
dataset: {data}
scheme: loso
features:
  - [{feature}]
classifiers:
  - {classifier}
seed: 5
"""


# ------------------------------------------------------------- the example plugin
def test_the_example_plugin_registers_its_entries_with_its_package(example_plugin):
    package, version = example_plugin
    want = PluginInfo(package, version, "example", "touchbench_plugin_example")
    assert FEATURES.entry(FEATURE).plugin == want
    assert CLASSIFIERS.entry(CLASSIFIER).plugin == want
    assert FEATURES.entry("sd").plugin is None and CLASSIFIERS.entry("zhou-knn").plugin is None


def test_pressure_stats_worked_out_by_hand(example_plugin):
    # per-frame means: [[0, 2], [4, 6]] -> 3, all 5 -> 5, all 1 -> 1
    cap = np.array([[[0, 2], [4, 6]], [[5, 5], [5, 5]], [[1, 1], [1, 1]]], dtype=np.uint16)
    sd = np.sqrt(((3 - 3) ** 2 + (5 - 3) ** 2 + (1 - 3) ** 2) / 3)
    out = FEATURES.create(FEATURE).fit_transform([cap])
    np.testing.assert_allclose(out, [[3.0, sd, 1.0, 5.0]])
    # a sensor rescales by its value range 0..10; one whose higher values mean less pressure is flipped
    sensor = SensorSpec(name="s", grid=(2, 2), frame_rate=10.0, value_range=(0.0, 10.0))
    np.testing.assert_allclose(FEATURES.create(FEATURE, sensor=sensor).fit_transform([cap]),
                               [[0.3, sd / 10, 0.1, 0.5]])
    inverse = SensorSpec(name="s", grid=(2, 2), frame_rate=10.0, value_range=(0.0, 10.0),
                         higher_is_more_pressure=False)
    np.testing.assert_allclose(FEATURES.create(FEATURE, sensor=inverse).fit_transform([cap]),
                               [[0.7, sd / 10, 0.5, 0.9]])
    assert FEATURES.create(FEATURE).feature_names((2, 2)) == [
        "frame_mean_pressure_mean", "frame_mean_pressure_sd", "frame_mean_pressure_min", "frame_mean_pressure_max"]


def test_listings_show_the_plugin_package(example_plugin):
    package, version = example_plugin
    label = f"{package} {version}"
    r = CliRunner().invoke(cli, ["plugins", "list"])
    assert r.exit_code == 0, r.output
    assert f"{label}  (entry point example = touchbench_plugin_example)" in r.output
    assert any(ln.split()[:3] == ["feature", "set", FEATURE] for ln in r.output.splitlines())
    assert any(ln.split()[:2] == ["classifier", CLASSIFIER] for ln in r.output.splitlines())
    r = CliRunner().invoke(cli, ["features", "list"], env={"COLUMNS": "250"})
    assert r.exit_code == 0, r.output
    line = next(ln for ln in r.output.splitlines() if f" {FEATURE} " in ln)
    assert package in line and "touchbench " in next(ln for ln in r.output.splitlines() if " msd " in ln)
    r = CliRunner().invoke(cli, ["classifiers", "list"])
    assert f"{CLASSIFIER}  " in r.output and f"[plugin {label}]" in r.output
    assert "zhou-knn  " in r.output and r.output.count("[plugin ") == 1
    r = CliRunner().invoke(cli, ["classifiers", "list", "--json"])
    rows = {row["name"]: row for row in json.loads(r.output)}
    assert rows[CLASSIFIER]["plugin"] == {"package": package, "version": version, "entry_point": "example"}
    assert rows["zhou-knn"]["plugin"] is None


def _nearest_centroid_by_hand(X_tr, y_tr, X_te):
    """The label of the nearest class mean (Euclidean)."""
    classes = sorted(set(y_tr))
    centroids = np.array([X_tr[np.asarray(y_tr) == c].mean(axis=0) for c in classes])
    d = ((X_te[:, None, :] - centroids[None]) ** 2).sum(axis=2)
    return [classes[i] for i in d.argmin(axis=1)]


def test_a_protocol_runs_the_plugin_by_name_in_parallel_workers(example_plugin, tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    ds = random_dataset(subjects=("s1", "s2", "s3"), per_cell=4, frames=(10, 14), seed=3)
    ds.to_parquet(tmp_path / "data.parquet")
    (tmp_path / "p.yaml").write_text(PROTOCOL.format(data=tmp_path / "data.parquet", feature=FEATURE,
                                                     classifier=CLASSIFIER))
    r = CliRunner().invoke(cli, ["protocols", "validate", str(tmp_path / "p.yaml")])
    assert r.exit_code == 0 and "valid protocol 'plugin-small'" in r.output, r.output

    res = run_protocol(tmp_path / "p.yaml", tmp_path / "out", jobs=2, progress=False)  # loky worker processes
    assert res.n_tasks == res.n_ran == 3 and (res.scores["status"] == "ok").all()
    preds = pd.read_parquet(tmp_path / "out" / "predictions.parquet")

    # the same by hand: per-frame means rescaled by the sensor's range 0..255, four statistics, LOSO
    lo, hi = SENSOR.value_range
    m = [(c.astype(np.float64).mean(axis=(1, 2)) - lo) / (hi - lo) for c in ds.captures]
    X = np.array([[v.mean(), v.std(), v.min(), v.max()] for v in m])
    y = ds.meta["gesture"].to_numpy()
    ids = ds.meta["capture_id"].to_numpy()
    for s in ("s1", "s2", "s3"):
        test = (ds.meta["subject"] == s).to_numpy()
        want = dict(zip(ids[test], _nearest_centroid_by_hand(X[~test], y[~test], X[test])))
        got = preds[preds["fold"] == f"subject={s}"].set_index("capture_id")["predicted_label"].to_dict()
        assert got == want, s


def test_protocol_validation_accepts_the_names(example_plugin, tmp_path):
    p = parse_protocol(PROTOCOL.format(data="haart-sample", feature=FEATURE, classifier=CLASSIFIER), tmp_path / "p.yaml")
    assert [c.name for c in p.classifier_entries()] == [CLASSIFIER]
    with pytest.raises(Exception, match="did you mean 'example-nearest-centroid'"):
        parse_protocol(PROTOCOL.format(data="haart-sample", feature=FEATURE, classifier="example-nearest-centroi"),
                       tmp_path / "p.yaml")


# ------------------------------------------------------------- the registry's side
def test_entries_registered_while_a_plugin_is_imported_carry_it():
    info = PluginInfo("touchbench-plugin-test", "2.0", "t", "tp")
    reg: Registry = Registry("thing", plugins=True)
    reg.register("own", description="touchbench's")(int)
    with importing(info):
        reg.register("theirs", description="a plugin's")(float)
        with pytest.raises(RegistrationError, match=r"thing 'own' is registered twice: by module builtins \(kept\) and by "
                                                    r"plugin touchbench-plugin-test 2.0 \(entry point 't' = 'tp'.*"
                                                    r"\(left out, with everything touchbench-plugin-test 2.0 registers\)"):
            reg.register("own", description="again")(str)
        with pytest.raises(RegistrationError, match="the scene registry does not take plugins"):
            Registry("scene").register("x", description="x")(str)
        with pytest.raises(RegistrationError, match="the tag 'plugin' is touchbench's"):
            reg.register("tagged", description="x", plugin="mine")(str)
    assert reg.entry("theirs").plugin == info and reg.entry("own").plugin is None
    assert "plugin touchbench-plugin-test 2.0" in reg.entry("theirs").origin


def test_a_plugin_registers_a_scheme_beside_the_package_s_own():
    from touchbench.protocols.schemes import SPLITTERS, Fold, Splitter, make_splitter

    info = PluginInfo("touchbench-plugin-test", "2.0", "t", "tp")
    own = SPLITTERS.names()  # the package's modules, found by the registry
    try:
        with importing(info):
            @SPLITTERS.register("every-other", description="even rows trained on, odd rows tested")
            class EveryOther(Splitter):
                name = "every-other"

                def _split(self, meta):
                    idx = np.arange(len(meta))
                    return [Fold("odd", idx[idx % 2 == 0], idx[idx % 2 == 1])]

        assert SPLITTERS.entry("every-other").plugin == info and "loso" in own
        train, test = next(make_splitter("every-other").split(pd.DataFrame({"gesture": list("abcd")})))
        assert train.tolist() == [0, 2] and test.tolist() == [1, 3]
    finally:
        SPLITTERS._entries.pop("every-other", None)


# ------------------------------------------------------------- broken plugins
def _fake_plugin(root: Path, package: str, module: str, source: str) -> None:
    """An installed distribution ``package`` 1.0 whose entry point ``main`` names ``module``."""
    (root / f"{module}.py").write_text(source)
    info = root / f"{package.replace('-', '_')}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {package}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[touchbench.plugins]\nmain = {module}\n")


def _touchbench(site: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(site), str(REPO), os.environ.get("PYTHONPATH", "")]),
               TOUCHBENCH_CACHE_DIR=str(tmp_path / "cache"))
    return subprocess.run([sys.executable, "-c", "from touchbench.cli.main import cli; cli()", *args],
                          env=env, cwd=tmp_path, capture_output=True, text=True, timeout=SUBPROCESS_HANG_S)


def _where(package: str, module: str) -> str:
    return f"plugin {package} 1.0 (entry point 'main' = '{module}' in group 'touchbench.plugins')"


#: the listings that load the plugins, each of its own registry (the first also gives the names listed)
LISTINGS = (["features", "list", "--json"], ["classifiers", "list"], ["data", "list"], ["data", "formats"])


@pytest.mark.slow
@pytest.mark.parametrize("source, why, listings", [
    ("import a_module_nobody_has\n", "ModuleNotFoundError: No module named 'a_module_nobody_has'", LISTINGS),
    # how a plugin fails is told apart where it is loaded, whichever listing loads it: one listing here
    ("from touchbench.features.base import FEATURES, FeatureSet\n"
     "@FEATURES.register('half-way', description='registered before the exit')\n"
     "class Mine(FeatureSet):\n    pass\n"
     "import sys\nsys.exit(3)\n", "it called sys.exit(3) while being imported", LISTINGS[:1]),
], ids=["import-error", "sys-exit"])
def test_a_plugin_that_fails_to_load_is_reported_and_left_out(tmp_path, source, why, listings):
    site = tmp_path / "site"
    site.mkdir()
    _fake_plugin(site, "broken-plugin", "broken_plugin_mod", source)
    where = _where("broken-plugin", "broken_plugin_mod")
    said = {}
    for args in listings:
        r = said[tuple(args)] = _touchbench(site, tmp_path, *args)
        assert r.returncode == 0, (args, r.stdout, r.stderr)  # the command goes on without the plugin
        assert f"{where} failed to load and is left out: {why}" in r.stderr, args
        assert "Traceback" not in r.stderr
    names = [row["name"] for row in json.loads(said[tuple(LISTINGS[0])].stdout)]
    assert "sd" in names and "half-way" not in names  # what it registered before it failed is removed
    # help, and the command that says what is installed, still work
    r = _touchbench(site, tmp_path, "--help")
    assert r.returncode == 0 and "plugins" in r.stdout, r.stderr
    r = _touchbench(site, tmp_path, "plugins", "list")
    assert r.returncode == 3
    assert "broken-plugin 1.0  (entry point main = broken_plugin_mod)" in r.stdout
    assert f"failed to load: {why}" in r.stdout and where in r.stderr


@pytest.mark.slow
def test_a_plugin_that_registers_an_existing_name_is_left_out(tmp_path):
    site = tmp_path / "site"
    site.mkdir()
    _fake_plugin(site, "clashing-plugin", "clashing_plugin_mod",
                 "from touchbench.features.base import FEATURES, FeatureSet\n"
                 "@FEATURES.register('sd', description='not the paper one')\n"
                 "class Mine(FeatureSet):\n    pass\n")
    # the data registry loads the plugins here: touchbench's own feature sets still come first
    r = _touchbench(site, tmp_path, "data", "list")
    assert r.returncode == 0, r.stdout + r.stderr
    assert (f"{_where('clashing-plugin', 'clashing_plugin_mod')} failed to load and is left out: feature set 'sd' "
            "is registered twice: by module touchbench.features.gaus_sd (kept) and by "
            f"{_where('clashing-plugin', 'clashing_plugin_mod')} (left out, with everything clashing-plugin 1.0 "
            "registers)") in r.stderr


@pytest.mark.slow
def test_a_name_two_plugins_register_names_both_and_keeps_the_first(tmp_path):
    site = tmp_path / "site"
    site.mkdir()
    for package, module in (("alpha-plugin", "alpha_mod"), ("beta-plugin", "beta_mod")):
        _fake_plugin(site, package, module,
                     "from touchbench.features.base import FEATURES, FeatureSet\n"
                     f"@FEATURES.register('shared-name', description='by {package}')\n"
                     "class Mine(FeatureSet):\n    pass\n"
                     f"@FEATURES.register('only-{package}', description='by {package}')\n"
                     "class Other(FeatureSet):\n    pass\n")
    r = _touchbench(site, tmp_path, "features", "list", "--json")
    assert r.returncode == 0, r.stdout + r.stderr
    alpha, beta = _where("alpha-plugin", "alpha_mod"), _where("beta-plugin", "beta_mod")
    assert (f"{beta} failed to load and is left out: feature set 'shared-name' is registered twice: by {alpha} (kept) "
            f"and by {beta} (left out, with everything beta-plugin 1.0 registers)") in r.stderr
    listed = {row["name"]: row for row in json.loads(r.stdout)}
    assert listed["shared-name"]["description"] == "by alpha-plugin" and "only-alpha-plugin" in listed
    assert "only-beta-plugin" not in listed  # left out whole


def test_a_plugins_source_enters_the_identity_of_its_components(example_plugin, tmp_path, monkeypatch):
    """A plugin is installed like any package (under site-packages), but its source
    is followed like touchbench's own: editing it without a new version changes the
    identity of the components it registers, so their tasks are recomputed."""
    import importlib

    from touchbench.engine import identity as ident

    module = importlib.import_module(FEATURES.get("example-pressure-stats").__module__)
    assert ident._top_kind(module.__name__.split(".")[0]) == "own"
    before = ident.feature_set_identity("example-pressure-stats")
    assert module.__name__ in before.modules
    # the same file with one more line: the identity follows the content
    copy = tmp_path / Path(module.__file__).name
    copy.write_text(Path(module.__file__).read_text() + "\n# edited\n")
    real = ident._file_info

    def edited(path, *a, **k):
        return real(str(copy) if os.path.samefile(path, module.__file__) else path, *a, **k)

    monkeypatch.setattr(ident, "_file_info", edited)
    after = ident.feature_set_identity("example-pressure-stats")
    assert after.digest != before.digest


@pytest.mark.slow
def test_a_plugin_installed_or_broken_after_the_listings_were_indexed_is_listed(tmp_path):
    # the listings are kept in the registry index (touchbench.core.listing); installing a plugin, or
    # editing it into one that fails, changes what they show at once
    site = tmp_path / "site"
    site.mkdir()
    indexed = [_touchbench(site, tmp_path, *args) for args in (["features", "list", "--json"], ["plugins", "list", "--json"])]
    assert all(r.returncode == 0 for r in indexed) and "late-set" not in indexed[0].stdout
    folder_time = site.stat().st_mtime_ns
    _fake_plugin(site, "late-plugin", "late_mod",
                 "from touchbench.features.base import FEATURES, FeatureSet\n"
                 "@FEATURES.register('late-set', description='installed after the index')\n"
                 "class Late(FeatureSet):\n    pass\n")
    os.utime(site, ns=(folder_time, folder_time))  # only the entry point and its module tell
    r = _touchbench(site, tmp_path, "features", "list", "--json")
    assert {"name": "late-set", "package": "late-plugin 1.0"}.items() <= next(
        row for row in json.loads(r.stdout) if row["name"] == "late-set").items()
    r = _touchbench(site, tmp_path, "plugins", "list")
    assert r.returncode == 0 and "late-plugin 1.0  (entry point main = late_mod)" in r.stdout
    assert any(ln.split()[:3] == ["feature", "set", "late-set"] for ln in r.stdout.splitlines())

    (site / "late_mod.py").write_text("import a_module_nobody_has\n")
    why = "ModuleNotFoundError: No module named 'a_module_nobody_has'"
    for _ in range(2):  # a failure is never kept in the index: reported, and tried again, every time
        r = _touchbench(site, tmp_path, "plugins", "list")
        assert r.returncode == 3 and f"failed to load: {why}" in r.stdout, r.stdout + r.stderr
    r = _touchbench(site, tmp_path, "features", "list", "--json")
    assert r.returncode == 0 and "late-set" not in r.stdout
    assert f"{_where('late-plugin', 'late_mod')} failed to load and is left out: {why}" in r.stderr
