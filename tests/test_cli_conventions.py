"""The command line's conventions: exit statuses, ``--json`` output, ``-v`` / ``-q``, one ``--jobs``
default, an example in every ``--help``, and a start-up that imports no command it does not run."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest
from helpers import SUBPROCESS_HANG_S
from click.testing import CliRunner

from touchbench.cli import exitcodes
from touchbench.cli.common import JOBS_DEFAULT
from touchbench.cli.main import _COMMANDS, cli

OK_PROTOCOL = "name: ok\ndataset: scene:tiny\nscheme: loso\nfeatures: [sd]\nclassifiers: [zhou-lda]\n"
# test-fail (touchbench.engine.testing) raises in fit: every task of it fails
FAILING = "name: failing\ndataset: scene:tiny\nscheme: loso\nfeatures: [sd]\nclassifiers:\n  - name: test-fail\n"


def invoke(*args, **kw):
    return CliRunner().invoke(cli, list(args), **kw)


@pytest.fixture
def env(engine_env):
    yield


def _all_commands():
    """(path, command) of every command and group."""
    out = []

    def walk(cmd, path):
        out.append((path, cmd))
        for name in getattr(cmd, "list_commands", lambda ctx: [])(None):
            walk(cmd.get_command(None, name), [*path, name])

    walk(cli, [])
    return out


# ----------------------------------------------------------------- exit statuses
def test_exit_status_of_a_run_whose_tasks_all_fail(env, tmp_path):
    (tmp_path / "p.yaml").write_text(FAILING)
    r = invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o"))
    assert r.exit_code == exitcodes.TASKS_FAILED == 1, r.output
    assert "task(s) failed, e.g." in r.output


def test_exit_status_of_a_run_where_some_tasks_fail_and_fail_fast(env, tmp_path):
    (tmp_path / "p.yaml").write_text(OK_PROTOCOL.replace("[zhou-lda]", "[zhou-lda, test-fail]"))
    r = invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o"), "--json")
    assert r.exit_code == 1, r.output
    doc = json.loads(r.stdout)
    assert doc["tasks"]["failed"] == doc["tasks"]["total"] // 2 > 0
    assert {f["classifier"] for f in doc["failures"]} == {"test-fail"}
    r = invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "ff"), "--fail-fast", "--json")
    doc = json.loads(r.stdout)
    assert r.exit_code == 1 and doc["stopped_early"] and doc["tasks"]["failed"] == 1
    assert doc["tasks"]["ran"] < doc["tasks"]["total"]


def test_exit_status_of_usage_and_data_errors(env, tmp_path):
    r = invoke("run", "--no-such-option")
    assert r.exit_code == exitcodes.USAGE == 2 and "No such option" in r.output
    (tmp_path / "bad.yaml").write_text("dataset: scene:tiny\nscheme: loso\nfeatures: [nope]\nclassifiers: [zhou-lda]\n")
    r = invoke("run", str(tmp_path / "bad.yaml"))
    assert r.exit_code == exitcodes.DATA == 3
    assert r.output.startswith("error: ") and "bad.yaml:3" in r.output and "nope" in r.output
    r = invoke("data", "info", str(tmp_path / "missing.parquet"))
    assert r.exit_code == 3 and "missing.parquet" in r.output


def test_exit_statuses_are_listed_in_help():
    r = invoke("--help")
    assert r.exit_code == 0
    text = " ".join(r.output.split())
    assert ("Exit status: 0 done; 1 some task failed; 2 usage error; 3 data, protocol or file error" in text
            and "130 interrupted" in text)


def test_a_successful_run_exits_0_and_its_json_is_the_only_stdout(env, tmp_path):
    (tmp_path / "p.yaml").write_text(OK_PROTOCOL)
    r = invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o"), "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["tasks"]["failed"] == 0 and doc["tasks"]["ran"] == doc["tasks"]["total"] > 0
    [m] = doc["methods"]
    assert (m["features"], m["classifier"]) == ("sd", "zhou-lda") and 0 <= m["accuracy_mean"] <= 1


# ----------------------------------------------------------------- --json on every command that lists or reports
@pytest.mark.parametrize("args, check", [
    (["data", "list", "--json"], lambda d: "haart" in {x["name"] for x in d}),
    (["data", "formats", "--json"], lambda d: "challenge-csv" in {x["name"] for x in d}),
    (["features", "list", "--json"], lambda d: "msd" in {x["name"] for x in d}),
    (["classifiers", "list", "--json"], lambda d: "gaus-rf" in {x["name"] for x in d}),
    (["protocols", "list", "--json"], lambda d: "demo-haart" in {x["name"] for x in d}),
    (["scenes", "list", "--json"], lambda d: "tiny" in {x["name"] for x in d}),
    (["plugins", "list", "--json"], lambda d: isinstance(d, list)),
    (["papers", "list", "--json"], lambda d: d["profile"] == "quick" and len(d["protocols"]) > 3),
    (["data", "info", "scene:tiny", "--json"], lambda d: d["captures"] > 0 and "by_gesture" in d),
])
def test_json_output_parses(args, check):
    r = invoke(*args)
    assert r.exit_code == 0, r.output
    assert check(json.loads(r.stdout))


def test_json_of_validate_leaderboard_and_compare(env, tmp_path):
    (tmp_path / "p.yaml").write_text(OK_PROTOCOL.replace("[zhou-lda]", "[zhou-lda, zhou-knn]"))
    r = invoke("protocols", "validate", str(tmp_path / "p.yaml"), "--json")
    doc = json.loads(r.stdout)
    assert r.exit_code == 0 and doc["valid"] and doc["classifiers"] == 2 and doc["tasks"] == 2 * doc["folds"]
    assert invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o")).exit_code == 0
    r = invoke("leaderboard", str(tmp_path / "o"), "--json")
    [table] = json.loads(r.stdout)["tables"]
    assert {row["classifier"] for row in table["rows"]} == {"zhou-lda", "zhou-knn"}
    r = invoke("compare", str(tmp_path / "o"), "--a", "sd/zhou-lda", "--b", "sd/zhou-knn", "--json")
    assert r.exit_code == 0, r.output
    assert isinstance(json.loads(r.stdout), (dict, list))


# ----------------------------------------------------------------- logging, --jobs, help
def test_quiet_silences_the_progress_messages(env, tmp_path):
    (tmp_path / "p.yaml").write_text(OK_PROTOCOL)
    loud = invoke("run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o"))
    assert "tasks ->" in loud.stderr and "reports: " in loud.stderr
    quiet = invoke("-q", "run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o2"))
    assert quiet.exit_code == 0 and quiet.stderr == "" and "zhou-lda" in quiet.stdout
    debug = invoke("-v", "run", str(tmp_path / "p.yaml"), "--out", str(tmp_path / "o2"))
    assert "nothing to do" in debug.stderr


def test_one_jobs_default():
    defaults = {}
    for path, cmd in _all_commands():
        for p in getattr(cmd, "params", []):
            if p.name == "jobs":
                defaults[" ".join(path)] = p.default
    assert set(defaults) == {"run", "demo", "papers reproduce", "audit"} and set(defaults.values()) == {JOBS_DEFAULT}


def test_every_help_shows_an_example():
    missing = []
    for path, cmd in _all_commands():
        r = invoke(*path, "--help")
        assert r.exit_code == 0, (path, r.output)
        if not re.search(r"Example:\n\s+touchbench ", r.output):
            missing.append(" ".join(path) or "touchbench")
    assert not missing


def test_help_and_version_import_no_command_module():
    code = ("import sys\nfrom touchbench.cli.main import cli\n"
            "try:\n    cli(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.startswith(('touchbench.cli.', 'sklearn', 'numpy', 'pandas'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    loaded = eval(out.strip().splitlines()[-1])
    assert loaded == ["touchbench.cli.common", "touchbench.cli.exitcodes", "touchbench.cli.main"]
    assert set(_COMMANDS) == set(cli.list_commands(None))


_OPTIONAL = ("torch", "aeon", "dask", "distributed", "ray", "xgboost")
_NUMERIC = ("numpy", "pandas", "pyarrow", "scipy", "sklearn", "pydantic")


def _imported_by(args: list[str], cache) -> set[str]:
    """The top-level packages a fresh process has imported once ``touchbench ARGS`` ran (its cache in
    folder ``cache``)."""
    code = ("import json, sys\nfrom touchbench.cli.main import cli\n"
            f"try:\n    cli({args!r})\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})), file=sys.stderr)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=SUBPROCESS_HANG_S,
                       env={**os.environ, "TOUCHBENCH_CACHE_DIR": str(cache)})
    assert r.returncode == 0, r.stderr
    return set(json.loads(r.stderr.strip().splitlines()[-1]))


def test_listing_protocols_imports_no_numeric_package(tmp_path):
    # the names and descriptions are read from the files: no schema, no scheme, no registry (nor an
    # optional extra: the other listings are checked for those by the test below, in the same process)
    assert not _imported_by(["protocols", "list"], tmp_path) & set(_OPTIONAL + _NUMERIC)


def _listings(commands: list[list[str]], cache) -> dict:
    """The exit status and output of each of ``commands`` run one after the other in one fresh process
    (its cache in folder ``cache``), and the top-level packages that process had imported at the end."""
    code = ("import json, sys\nfrom click.testing import CliRunner\nfrom touchbench.cli.main import cli\n"
            f"runs = [CliRunner().invoke(cli, args, env={{'COLUMNS': '200'}}) for args in {commands!r}]\n"
            "print(json.dumps({'outputs': [[r.exit_code, r.stdout] for r in runs], "
            "'modules': sorted({m.split('.')[0] for m in sys.modules})}))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=SUBPROCESS_HANG_S,
                       env={**os.environ, "TOUCHBENCH_CACHE_DIR": str(cache)})
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("command", ["data", "features", "classifiers", "plugins"])
def test_a_listing_from_the_registry_index_is_the_same_and_imports_no_numeric_package(command, tmp_path):
    commands = [[command, "list"], [command, "list", "--json"]]
    built = _listings(commands, tmp_path)  # no index yet: the registries imported, the index written
    assert all(code == 0 and out.strip() for code, out in built["outputs"]), built["outputs"]
    assert sorted(set(built["modules"]) & set(_OPTIONAL)) == []  # the registries import no optional extra
    read = _listings(commands, tmp_path)  # the same commands in a new process: from the index
    assert read["outputs"] == built["outputs"]
    assert sorted(set(read["modules"]) & set(_OPTIONAL + _NUMERIC)) == []
    assert "sklearn" in built["modules"] and list((tmp_path / "registry-index").glob("*.json"))


def test_a_sigterm_inside_an_import_waits_for_the_import_to_end(tmp_path):
    # the module's body sends the process SIGTERM and then goes on for 0.3 s: the interruption must
    # come once the import is whole (DONE set), not in the middle of it
    (tmp_path / "slowmod.py").write_text(
        "import os, signal, time\nos.kill(os.getpid(), signal.SIGTERM)\ntime.sleep(0.3)\nDONE = True\n")
    code = (
        "import signal, sys, time\n"
        "from touchbench.cli.main import _terminate\n"
        "signal.signal(signal.SIGTERM, _terminate)\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        "try:\n"
        "    import slowmod\n"
        "    deadline = time.monotonic() + 30\n"
        "    while time.monotonic() < deadline:\n"
        "        time.sleep(0.01)\n"
        "    print('not interrupted')\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted; the import was whole:', getattr(sys.modules.get('slowmod'), 'DONE', False))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=SUBPROCESS_HANG_S)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "interrupted; the import was whole: True"
