"""The documents point at what exists: every source file a page of docs/ names is in the repository,
the registered names a page places in a module are registered by that module, no page sends the
reader outside the repository, and docs/README.md lists every page."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = sorted(DOCS.glob("*.md")) + sorted((DOCS / "research").glob("*.md"))

# `path/to/file.py` in backquotes: a source file (a placeholder such as NAME.py or a glob is no path)
SOURCE = re.compile(r"`([\w./-]+/[\w.-]+\.py)`")
# `touchbench/x/y.py` (`name-a`, `name-b` ...): the names a page says that module registers
PLACED = re.compile(r"`(touchbench/[\w/]+\.py)`\s*\(([^)]*)\)")


def _ids(pages):
    return [str(p.relative_to(ROOT)) for p in pages]


def _resolves(path: str, page: Path) -> bool:
    """A path in a page is read from the repository root, from touchbench/ (the package's map names
    its modules from there) or from the page's own folder."""
    return any((base / path).is_file() for base in (ROOT, ROOT / "touchbench", page.parent))


@pytest.mark.parametrize("page", PAGES, ids=_ids(PAGES))
def test_every_source_file_a_page_names_exists(page):
    named = {m.group(1) for m in SOURCE.finditer(page.read_text(encoding="utf-8"))}
    missing = sorted(p for p in named if "NAME" not in p and not _resolves(p, page))
    assert not missing, f"{page.relative_to(ROOT)} names files that do not exist: {missing}"


def _registered_names() -> set[str]:
    from touchbench.classifiers import CLASSIFIERS
    from touchbench.datasets.registry import DATASETS
    from touchbench.features import FEATURES
    from touchbench.methods import METHODS

    return {n for reg in (CLASSIFIERS, DATASETS, FEATURES, METHODS) for n in reg.names()}


@pytest.mark.parametrize("page", PAGES, ids=_ids(PAGES))
def test_names_a_page_places_in_a_module_are_registered_there(page):
    registered = _registered_names()
    wrong = []
    for m in PLACED.finditer(page.read_text(encoding="utf-8")):
        path = ROOT / m.group(1)
        if not path.is_file():
            continue  # the test above reports it
        source = path.read_text(encoding="utf-8")
        for name in re.findall(r"`([a-z0-9][a-z0-9-]*)`", m.group(2)):
            if name in registered and f'"{name}"' not in source:
                wrong.append(f"{name} is not registered in {m.group(1)}")
    assert not wrong, f"{page.relative_to(ROOT)}: {wrong}"


def test_the_placing_check_catches_a_name_put_in_the_wrong_module():
    text = "- `touchbench/classifiers/touch.py` (`touch-extra-trees`, `touch-et`) and more"
    (m,) = PLACED.finditer(text)
    source = (ROOT / m.group(1)).read_text(encoding="utf-8")
    names = re.findall(r"`([a-z0-9][a-z0-9-]*)`", m.group(2))
    assert names == ["touch-extra-trees", "touch-et"]
    # touch-et is a method (touchbench/methods/touch.py), not a classifier of classifiers/touch.py
    assert [n for n in names if f'"{n}"' not in source] == ["touch-et"]
    assert '"touch-et"' in (ROOT / "touchbench" / "methods" / "touch.py").read_text(encoding="utf-8")


@pytest.mark.parametrize("page", PAGES + [ROOT / "README.md"], ids=_ids(PAGES + [ROOT / "README.md"]))
def test_no_page_sends_the_reader_outside_the_repository(page):
    text = page.read_text(encoding="utf-8")
    outside = sorted(set(re.findall(r"\.\./shared/(?!data\b)[\w./-]+", text)))
    assert not outside, f"{page.relative_to(ROOT)} points outside the repository: {outside}"


def test_the_docs_index_lists_every_page_with_a_line():
    index = (DOCS / "README.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"\[[^\]]+\]\(([\w./-]+\.md)\)", index))
    pages = {str(p.relative_to(DOCS)) for p in PAGES if p.name != "README.md"}
    assert pages <= listed, f"docs/README.md does not list {sorted(pages - listed)}"
    assert listed <= pages | {"../CONTRIBUTING.md", "../README.md"}, f"docs/README.md lists missing pages: {sorted(listed - pages)}"


def test_contributing_guide_points_to_the_map_of_the_code():
    text = (ROOT / "CONTRIBUTING.md").read_text(encoding="utf-8")
    assert "docs/internals.md" in text and "make test" in text and "make lint" in text
