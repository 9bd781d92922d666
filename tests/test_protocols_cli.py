"""`touchbench protocols validate / list`, and the protocols shipped in protocols/."""

from __future__ import annotations

import click
import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.paths import REPO_ROOT
from touchbench.protocols.library import PAPERS_DIR, SHIPPED_DIR
from touchbench.protocols.loading import load_protocol

SHIPPED = sorted(SHIPPED_DIR.glob("*.yaml")) + sorted(PAPERS_DIR.glob("*.yaml"))
MINE = ["haart-loso-msd-rf", "gaus-table5-haart", "cnn-table2-loso-haart", "cnn-fig5-frame-sweep-haart", "tiny"]


def invoke(*args):
    return CliRunner().invoke(cli, list(args))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_protocol_is_valid(path):
    p = load_protocol(path)  # builds every classifier entry with its parameters
    assert p.description, f"{path.name} needs a one-line description for `protocols list`"
    assert p.name == path.stem


def test_expected_numbers_of_the_paper_protocols():
    t5 = load_protocol(PAPERS_DIR / "gaus-table5-haart.yaml")
    values = {"+".join(r.features): r.value for r in t5.expected.results if r.classifier == "gaus-rf"}
    assert values == {"sd": 36.17, "bmh": 22.67, "msd": 54.82, "smmhh": 65.66, "lbptop": 53.01,
                      "sd+bmh+msd+smmhh+lbptop": 76.65}  # Gaus et al. 2015, Table 5, RF
    cnn = load_protocol(PAPERS_DIR / "cnn-table2-loso-haart.yaml")
    # Al-mashhadani et al. 2021, Table 2, beside the first window (the paper's) and all 30 windows, soft vote
    assert [(r.classifier, r.value) for r in cnn.expected.results] == [("cnn", 83.2), ("cnn-all-windows", 83.2)]
    assert [(c.label, c.params) for c in cnn.classifier_entries()] == [
        ("cnn", {"L": 30}), ("cnn-all-windows", {"L": 30, "test_windows": "all", "vote": "soft"})]
    assert "stopped-on-test" in cnn.audit.variants  # early stopping on the held-out subject, audited as a leak
    sweep = load_protocol(PAPERS_DIR / "cnn-fig5-frame-sweep-haart.yaml")
    assert [c.params["L"] for c in sweep.classifier_entries()] == list(range(5, 55, 5))
    assert sweep.scheme.params == {"subjects": ["s01", "s03", "s05", "s07"]}


def test_list_shows_the_shipped_protocols_with_descriptions(monkeypatch):
    monkeypatch.chdir(REPO_ROOT)
    r = invoke("protocols", "list")
    assert r.exit_code == 0
    for name in MINE:
        line = next(l for l in r.output.splitlines() if f"/{name}.yaml" in l)
        assert len(line.split(maxsplit=1)) == 2  # path, then the description


def test_validate_valid_and_invalid(tmp_path):
    r = invoke("protocols", "validate", "--schema-only", str(SHIPPED_DIR / "haart-loso-msd-rf.yaml"))
    assert r.exit_code == 0 and "valid protocol 'haart-loso-msd-rf'" in r.output
    bad = tmp_path / "bad.yaml"
    bad.write_text((SHIPPED_DIR / "haart-loso-msd-rf.yaml").read_text().replace("name: gaus-rf", "name: gaus-fr"))
    r = invoke("protocols", "validate", str(bad))
    assert r.exit_code == 3
    lines = [l for l in r.output.splitlines() if l.strip()]
    assert len(lines) == 1
    assert lines[0].startswith(f"error: {bad}:17: classifiers[0].name: unknown classifier 'gaus-fr'; did you mean 'gaus-rf'")


def test_validate_by_name_and_missing_file():
    r = invoke("protocols", "validate", "--schema-only", "tiny")
    assert r.exit_code == 0 and "valid protocol 'tiny'" in r.output
    r = invoke("protocols", "validate", "no-such-protocol")
    assert r.exit_code == 3 and "no such protocol file" in r.output


def test_tiny_protocol_runs_and_reruns_as_noop(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    r = invoke("protocols", "validate", "tiny")
    assert r.exit_code == 0, r.output
    assert "4 fold(s) x 3 x 2 = 24 task(s)" in r.output
    r = invoke("run", "tiny", "--out", str(tmp_path / "out"))
    assert r.exit_code == 0, r.output
    scores = pd.read_parquet(tmp_path / "out" / "scores.parquet")
    assert len(scores) == 24 and (scores["status"] == "ok").all()
    r = invoke("run", "tiny", "--out", str(tmp_path / "out"))
    assert r.exit_code == 0 and "nothing to do" in r.output


# -- the commands a shipped protocol's comment gives work from the repository root --------------------------

_COMMENT_PATH_ROOTS = ("touchbench/", "docs/", "protocols/", "examples/", "benchmarks/", "../shared/")


def _comment_text(path):
    """A protocol file's comment lines, as they read (the ``#`` and its indent removed)."""
    return [line[1:].strip() for line in path.read_text().splitlines() if line.startswith("#")]


def _comment_commands(path):
    """Every ``touchbench ...`` command a protocol's comment gives: the indented command lines (each
    ``&&`` part, a trailing ``# ...`` or ``(or: ...)`` left out) and the ones quoted in backticks."""
    import re
    import shlex

    lines = _comment_text(path)
    found = []
    for line in lines:
        if line.startswith("touchbench "):
            line = re.split(r"\s#\s|\(or:", line)[0]
            found += [part.strip() for part in line.split("&&")]
    found += re.findall(r"`(touchbench [^`]+)`", " ".join(lines))
    return [shlex.split(c)[1:] for c in found]


def _parse(args):
    """The click context of ``touchbench ARGS`` (parsed, not run): a wrong option or a missing argument raises."""
    ctx = cli.make_context("touchbench", list(args), resilient_parsing=False)
    while isinstance(ctx.command, click.Group):
        name, cmd, rest = ctx.command.resolve_command(ctx, [*ctx._protected_args, *ctx.args])
        ctx = cmd.make_context(name, rest, parent=ctx)
    return ctx


@pytest.mark.parametrize("path", [p for p in SHIPPED if _comment_commands(p)], ids=lambda p: p.name)
def test_comment_commands_of_shipped_protocols_work_from_the_repository_root(path, tmp_path, monkeypatch):
    from touchbench.protocols.library import find_protocol

    monkeypatch.chdir(REPO_ROOT)
    written = set()  # the results folders the comment's run commands write
    for args in _comment_commands(path):
        if args[0] == "leaderboard":  # reads what a run of the same comment writes
            folders = [a for a in args[1:] if not a.startswith("-")]
            assert folders and set(folders) <= written, f"{path.name}: {args} reads no folder its run writes"
            monkeypatch.chdir(tmp_path)
            for f in folders:
                (tmp_path / f).mkdir(parents=True, exist_ok=True)
            _parse(args)
            monkeypatch.chdir(REPO_ROOT)
            continue
        ctx = _parse(args)
        protocol = ctx.params.get("protocol")
        if protocol is not None:
            assert find_protocol(protocol).resolve().parent in (SHIPPED_DIR, PAPERS_DIR), f"{path.name}: {args}"
            written.add(ctx.params.get("out") or f"results/{load_protocol(find_protocol(protocol)).name}")


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_paths_named_in_shipped_protocol_comments_exist_from_the_repository_root(path):
    import re

    text = " ".join(_comment_text(path))
    named = [m for m in re.findall(r"[\w./-]+", text) if m.startswith(_COMMENT_PATH_ROOTS)]
    missing = [m.rstrip(".,;:)") for m in named if not (REPO_ROOT / m.rstrip(".,;:)")).exists()]
    assert not missing, f"{path.name} names paths that do not exist from the repository root: {missing}"


def test_run_audit_and_train_refuse_an_unknown_evaluation_with_one_message(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    proto = load_protocol(SHIPPED_DIR / "touch-all.yaml")
    assert [p.evaluation for p in proto.evaluations_named(["to-fur", "loso"])] == ["loso", "to-fur"]
    text = "'los' is not an evaluation of protocol 'touch-all'; did you mean 'loso'?"
    for args, code in ((["run", "touch-all", "--evaluation", "los"], 2),
                       (["audit", "touch-all", "--evaluation", "los"], 2),
                       (["train", "touch-all", "--method", "touch-et", "--evaluation", "los", "--out", "m.tbm"], 3)):
        r = invoke(*args)
        assert r.exit_code == code and text in " ".join(r.output.split()), (args, r.output)
    r = invoke("run", "tiny", "--evaluation", "loso")
    assert r.exit_code == 2 and "it has none: leave out --evaluation" in " ".join(r.output.split())
