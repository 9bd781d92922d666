"""What the repository says about itself agrees: licence, citation, version, changelog, install
ranges and the pins of the development environment."""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

import pytest
import yaml
from packaging.requirements import Requirement

import touchbench
from touchbench.core import versions

REPO = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
PROJECT = PYPROJECT["project"]
SEEDS = REPO.parent / "shared" / "seeds"


def test_license_file_is_the_mit_license_pyproject_names():
    assert PROJECT["license"] == "MIT" and PROJECT["license-files"] == ["LICENSE"]
    text = (REPO / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License\n") and "Permission is hereby granted, free of charge" in text


def test_one_version_everywhere():
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text(encoding="utf-8"))
    assert PROJECT["version"] == touchbench.__version__ == cff["version"]


def test_citation_file_is_cff_1_2_0_and_cites_the_four_papers():
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software" and cff["license"] == "MIT"
    assert {"authors", "message", "title"} <= set(cff)
    for ref in cff["references"]:
        assert {"type", "title", "authors", "year"} <= set(ref), ref["title"]
    firsts = {(r["authors"][0]["family-names"], r["year"]) for r in cff["references"]}
    assert firsts == {("Gaus", 2015), ("Al-mashhadani", 2021), ("Flagg", 2012), ("Zhou", 2017)}
    for who in ("Gaus et al. 2015", "Al-mashhadani et al. 2021", "Flagg 2012", "Zhou et al. 2017"):
        assert who in cff["message"]


def test_cited_titles_are_the_papers_titles():
    """Each reference's title is the title of one of the papers' texts (../shared/seeds)."""
    if not SEEDS.is_dir():
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"the papers' texts not found at {SEEDS}")
        pytest.skip(f"the papers' texts not found at {SEEDS}")
    def squash(s: str) -> str:
        return re.sub(r"[\W_]+", " ", s).lower()

    texts = [squash(p.read_text(encoding="utf-8")[:3000]) for p in sorted(SEEDS.glob("00*.txt"))]
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text(encoding="utf-8"))
    found = [[i for i, t in enumerate(texts) if squash(r["title"]) in t] for r in cff["references"]]
    assert sorted(f for hits in found for f in hits) == [0, 1, 2, 3]


def test_changelog_follows_keep_a_changelog():
    text = (REPO / "CHANGELOG.md").read_text(encoding="utf-8")
    assert text.startswith("# Changelog\n") and "keepachangelog.com" in text
    assert "## [Unreleased]" in text and "### Added" in text


def _requirements() -> list[Requirement]:
    reqs = [Requirement(r) for r in PROJECT["dependencies"]]
    return reqs + [Requirement(r) for extra in PROJECT["optional-dependencies"].values() for r in extra]


def test_no_exact_pins_for_users():
    pinned = [str(r) for r in _requirements() if any(s.operator in ("==", "===") for s in r.specifier)]
    assert pinned == []


def test_the_development_pins_lie_within_the_ranges_users_get():
    pins = [Requirement(line) for line in (REPO / "constraints.txt").read_text(encoding="utf-8").splitlines()
            if line.strip() and not line.startswith("#")]
    ranges = {r.name: r.specifier for r in _requirements()}
    assert [p.name for p in pins] == ["torch", "flake8", "flake8-functions", "Flake8-pyproject", "pytest-xdist", "pytest", "skops"]
    for pin in pins:
        (version,) = [s.version for s in pin.specifier]
        assert version in ranges[pin.name], (pin, ranges[pin.name])
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    installs = [line for line in makefile.splitlines() if "pip install" in line and "--upgrade pip" not in line]
    assert installs and all("-c $(CONSTRAINTS)" in line for line in installs)


def test_xgboost_is_an_extra_of_either_build():
    assert not [r for r in PROJECT["dependencies"] if Requirement(r).name.startswith("xgboost")]
    extras = PROJECT["optional-dependencies"]
    assert [Requirement(r).name for r in extras["xgboost"]] == ["xgboost"]
    assert [Requirement(r).name for r in extras["xgboost-cpu"]] == ["xgboost-cpu"]


@pytest.mark.parametrize("installed, missing", [
    ({"xgboost": "3.2.0"}, []),                     # the full build (a GPU build included)
    ({"xgboost-cpu": "3.2.0"}, []),                 # the CPU build installs the same package
    ({}, ["xgboost"]),
])
def test_either_xgboost_build_satisfies_the_extra(monkeypatch, installed, missing):
    monkeypatch.setattr(versions.metadata, "requires", lambda dist: ['xgboost>=2.0; extra == "xgboost"'])
    monkeypatch.setattr(versions, "_version", lambda dist: installed.get(dist))
    assert versions.missing_extra("xgboost") == missing
