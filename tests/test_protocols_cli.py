"""`touchbench protocols validate / list`, and the protocols shipped in protocols/."""

from __future__ import annotations

import pandas as pd
import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.core.paths import REPO_ROOT
from touchbench.protocols.library import PAPERS_DIR, SHIPPED_DIR
from touchbench.protocols.schema import load_protocol

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
    assert [r.value for r in cnn.expected.results] == [83.2]  # Al-mashhadani et al. 2021, Table 2
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
