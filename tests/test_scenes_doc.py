"""docs/scenes.md lists every value the paper-like scene files set, with its source.

For each scene the page has a section (``## <scene>``) with a table
``property | value | source``. Every leaf of the scene YAML (dotted path;
``effects`` item by item) must have a row, every row must name a property
the file sets, and every row must give its source. The value column must
hold the file's current value (in backticks, as YAML), so a changed value
shows up as a stale row.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "scenes.md"
SPECS = REPO / "touchbench" / "scenes" / "specs"
SCENES = ["cost-like", "fur-like", "tpm-like"]
SKIPPED = {"name", "description", "seed", "calibrated"}  # calibrated: where values come from


def leaf_properties(raw: dict) -> dict[str, object]:
    """Every property a scene file sets: dotted path -> value.

    Nested mappings give ``a.b.c``; a list (``grid``, ``split.train``) or an
    empty mapping (a gesture with the library's parameters) is one
    property; ``effects`` gives one property per item, ``effects: <item>``.
    Top-level ``name``, ``description``, ``seed`` and ``calibrated`` (the
    sources of calibrated values, not a property) are left out."""
    out: dict[str, object] = {}

    def walk(prefix: str, value: object) -> None:
        if isinstance(value, dict) and value:
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else str(k), v)
        else:
            out[prefix] = value

    for key, value in raw.items():
        if key in SKIPPED:
            continue
        if key == "effects":
            for item in value:
                out[f"effects: {item}"] = item
            continue
        walk(str(key), value)
    return out


def section(text: str, scene: str) -> str:
    """The text between ``## <scene>`` and the next ``## `` heading."""
    m = re.search(rf"^## {re.escape(scene)}[ \t]*$(.*?)(?=^## |\Z)", text, flags=re.M | re.S)
    assert m, f"docs/scenes.md has no section '## {scene}'"
    return m.group(1)


def table_rows(sec: str) -> list[tuple[str, str, str]]:
    """(property, value, source) of each table row whose first cell is a backticked property."""
    rows = []
    for line in sec.splitlines():
        line = line.strip()
        if not line.startswith("|"):
            continue
        cells = [c.strip() for c in line.strip("|").split("|")]
        m = re.fullmatch(r"`([^`]+)`", cells[0]) if cells else None
        if not m:
            continue  # the header and the separator
        assert len(cells) == 3, f"row for {m.group(1)!r} has {len(cells)} cells, not 3 (property | value | source)"
        rows.append((m.group(1), cells[1], cells[2]))
    return rows


def doc_text() -> str:
    return DOC.read_text(encoding="utf-8")


def scene_raw(scene: str) -> dict:
    return yaml.safe_load((SPECS / f"{scene}.yaml").read_text(encoding="utf-8"))


def test_leaf_properties_of_a_hand_written_scene():
    raw = {
        "name": "x",
        "description": "d",
        "seed": 3,
        "effects": ["style", "noise"],
        "sensor": {"grid": [8, 8], "noise_sd": 2.0, "baseline": {"level": 40, "structure": "lines"}},
        "gestures": {"tap": {}, "rub": {"osc_hz": 2.0}},
        "protocol": {"groups": {"A": {"instructions": {"stroke": {"cycles": 3}}}}},
    }
    assert leaf_properties(raw) == {
        "effects: style": "style",
        "effects: noise": "noise",
        "sensor.grid": [8, 8],
        "sensor.noise_sd": 2.0,
        "sensor.baseline.level": 40,
        "sensor.baseline.structure": "lines",
        "gestures.tap": {},
        "gestures.rub.osc_hz": 2.0,
        "protocol.groups.A.instructions.stroke.cycles": 3,
    }


def test_section_ends_at_the_next_heading():
    text = "intro\n## a\n| `p` | `1` | s |\n## ab\n| `q` | `2` | t |\n"
    assert table_rows(section(text, "a")) == [("p", "`1`", "s")]
    assert table_rows(section(text, "ab")) == [("q", "`2`", "t")]


@pytest.mark.parametrize("scene", SCENES)
def test_every_property_of_the_scene_is_documented(scene):
    documented = {p for p, _, _ in table_rows(section(doc_text(), scene))}
    missing = [p for p in leaf_properties(scene_raw(scene)) if p not in documented]
    assert not missing, f"docs/scenes.md, section {scene}: no row for {', '.join(missing)}"


@pytest.mark.parametrize("scene", SCENES)
def test_every_documented_property_is_in_the_scene(scene):
    props = leaf_properties(scene_raw(scene))
    rows = table_rows(section(doc_text(), scene))
    assert rows, f"docs/scenes.md, section {scene}: no table rows"
    stale = [p for p, _, _ in rows if p not in props]
    assert not stale, f"docs/scenes.md, section {scene}: {', '.join(stale)} not set in {scene}.yaml (stale row)"
    names = [p for p, _, _ in rows]
    twice = sorted({p for p in names if names.count(p) > 1})
    assert not twice, f"docs/scenes.md, section {scene}: listed twice: {', '.join(twice)}"


@pytest.mark.parametrize("scene", SCENES)
def test_every_row_has_a_source(scene):
    rows = table_rows(section(doc_text(), scene))
    empty = [p for p, _, source in rows if not source]
    assert not empty, f"docs/scenes.md, section {scene}: no source for {', '.join(empty)}"


@pytest.mark.parametrize("scene", SCENES)
def test_documented_values_match_the_scene(scene):
    props = leaf_properties(scene_raw(scene))
    wrong = []
    for prop, value, _ in table_rows(section(doc_text(), scene)):
        if prop.startswith("effects: ") or prop not in props:
            continue  # an effect row has no value; a stale row fails its own test
        m = re.match(r"`([^`]*)`", value)
        if not m:
            wrong.append(f"{prop} (no value in backticks)")
            continue
        if yaml.safe_load(m.group(1)) != props[prop]:
            wrong.append(f"{prop} (page {m.group(1)}, file {props[prop]!r})")
    assert not wrong, f"docs/scenes.md, section {scene}: stale value for {'; '.join(wrong)}"


@pytest.mark.parametrize("scene", SCENES)
def test_a_calibrated_value_is_documented_with_its_table(scene):
    calibrated = scene_raw(scene).get("calibrated") or {}
    rows = {p: source for p, _, source in table_rows(section(doc_text(), scene))}

    def under(prop: str) -> list[str]:  # a calibrated block (population.repetition) is all its rows
        return [p for p in rows if p == prop or p.startswith(prop + ".")]

    for prop, cal in calibrated.items():
        assert under(prop), f"docs/scenes.md, section {scene}: no row for the calibrated {prop}"
        where = cal["table"].split(",")[1].split("(")[0].strip()  # "Table 3", "Fig. 4.9"
        for p in under(prop):
            assert f"calibrated on {where}" in rows[p], f"docs/scenes.md, section {scene}: {p} does not say it was " \
                                                      f"calibrated on {cal['table']}"
    said = [p for p, source in rows.items() if "calibrated on" in source]
    extra = [p for p in said if not any(p == c or p.startswith(c + ".") for c in calibrated)]
    assert not extra, f"docs/scenes.md, section {scene}: says calibrated but the scene does not: {extra}"
