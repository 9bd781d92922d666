"""The registry index (touchbench.core.listing): the listings' rows kept in the cache under a
fingerprint of what they depend on; a changed fingerprint or a damaged file rebuilds them.

The whole commands, read from the index and built from the registries, are compared in
tests/test_cli_conventions.py; a plugin installed or broken after the index was written, in
tests/test_plugins.py.
"""

from __future__ import annotations

import json
import os

import pytest

from touchbench.core import listing
from touchbench.core.plugins import PluginInfo

NOT_IMPORTED = ("a_package_nobody_imports",)


class Builder:
    """A listing's build function that counts its calls."""

    def __init__(self, rows):
        self.rows, self.calls = rows, 0

    def __call__(self):
        self.calls += 1
        return self.rows


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("TOUCHBENCH_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(listing, "plugin_status", lambda: [])
    return tmp_path / "cache"


def test_rows_are_built_once_then_read_from_the_index(cache, monkeypatch):
    monkeypatch.setattr(listing, "fingerprint", lambda: "one")
    build = Builder([{"name": "b", "tags": ("x", 1)}, {"name": "a", "n": {2: None}}])
    want = [{"name": "b", "tags": ["x", 1]}, {"name": "a", "n": {"2": None}}]  # as JSON gives them back
    assert listing.cached_rows("things", build, NOT_IMPORTED) == want and build.calls == 1
    assert listing.index_path().parent == cache / "registry-index"
    assert listing.cached_rows("things", build, NOT_IMPORTED) == want and build.calls == 1
    # another listing joins the same file; the first stays
    other = Builder([{"name": "c"}])
    assert listing.cached_rows("others", other, NOT_IMPORTED) == [{"name": "c"}] and other.calls == 1
    assert listing.cached_rows("things", build, NOT_IMPORTED) == want and build.calls == 1
    assert sorted(json.loads(listing.index_path().read_text())["listings"]) == ["others", "things"]


def test_a_changed_fingerprint_rebuilds_the_index(cache, monkeypatch):
    monkeypatch.setattr(listing, "fingerprint", lambda: "before")
    listing.cached_rows("things", Builder([{"name": "old"}]), NOT_IMPORTED)
    monkeypatch.setattr(listing, "fingerprint", lambda: "after")  # a registry module touched, say
    build = Builder([{"name": "new"}])
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "new"}] and build.calls == 1
    assert json.loads(listing.index_path().read_text())["fingerprint"] == "after"
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "new"}] and build.calls == 1


@pytest.mark.parametrize("damage", [
    lambda text: text[: len(text) // 2],  # cut short
    lambda text: "\x00\xff not json",
    lambda text: json.dumps([1, 2]),  # JSON, not an index
    lambda text: text.replace('"old"', '"edited"'),  # edited: no longer what was written
], ids=["truncated", "garbage", "not-an-index", "edited"])
def test_a_damaged_index_is_ignored_and_rewritten(cache, monkeypatch, damage):
    monkeypatch.setattr(listing, "fingerprint", lambda: "one")
    listing.cached_rows("things", Builder([{"name": "old"}]), NOT_IMPORTED)
    path = listing.index_path()
    path.write_text(damage(path.read_text()))
    build = Builder([{"name": "rebuilt"}])
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "rebuilt"}] and build.calls == 1
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "rebuilt"}] and build.calls == 1


def test_nothing_is_written_when_a_plugin_failed_or_the_registries_are_imported(cache, monkeypatch):
    monkeypatch.setattr(listing, "fingerprint", lambda: "one")
    info = PluginInfo("broken", "1.0", "main", "broken_mod")
    monkeypatch.setattr(listing, "plugin_status", lambda: [(info, "ImportError: no")])
    build = Builder([{"name": "a"}])
    listing.cached_rows("things", build, NOT_IMPORTED)
    listing.cached_rows("things", build, NOT_IMPORTED)
    assert build.calls == 2 and not listing.index_path().exists()
    monkeypatch.setattr(listing, "plugin_status", lambda: [(info, None)])
    listing.cached_rows("things", build, ("json",))  # imported already: its entries are the answer
    assert build.calls == 3 and not listing.index_path().exists()
    monkeypatch.setattr(listing, "fingerprint", lambda: None)  # cannot be taken
    listing.cached_rows("things", build, NOT_IMPORTED)
    assert build.calls == 4 and not listing.index_path().exists()


def test_an_index_that_cannot_be_written_leaves_the_listing_answered(cache, monkeypatch):
    monkeypatch.setattr(listing, "fingerprint", lambda: "one")
    cache.mkdir()
    (cache / "registry-index").write_text("a file where the folder goes")
    build = Builder([{"name": "a"}])
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "a"}]
    assert listing.cached_rows("things", build, NOT_IMPORTED) == [{"name": "a"}] and build.calls == 2


def _touch(path, seconds):
    os.utime(path, ns=(seconds * 10**9, seconds * 10**9))


def test_the_fingerprint_follows_the_package_files_and_the_plugins(tmp_path, monkeypatch):
    package, site = tmp_path / "pkg", tmp_path / "site"
    (package / "sub").mkdir(parents=True)
    site.mkdir()
    for f in (package / "__init__.py", package / "sub" / "mod.py"):
        f.write_text("x = 1\n")
        _touch(f, 1_000)
    monkeypatch.setattr(listing, "PACKAGE_DIR", package)
    monkeypatch.setattr(listing, "installed_plugins", lambda: [])
    monkeypatch.setattr(listing.sys, "path", [str(site)])
    _touch(site, 1_000)
    first = listing.fingerprint()
    assert listing.fingerprint() == first
    _touch(package / "sub" / "mod.py", 2_000)  # a registry module saved again
    touched = listing.fingerprint()
    assert touched != first
    (package / "sub" / "mod.py").write_text("x = 22\n")
    _touch(package / "sub" / "mod.py", 2_000)  # same time, another size
    assert listing.fingerprint() not in (first, touched)
    (package / "sub" / "mod.py").write_text("x = 1\n")
    _touch(package / "sub" / "mod.py", 1_000)
    assert listing.fingerprint() == first
    _touch(site, 2_000)  # a package installed or removed beside the plugins
    assert listing.fingerprint() != first
    _touch(site, 1_000)
    assert listing.fingerprint() == first

    # a plugin: its entry point, its version and its module's files count; one not found on
    # sys.path gives no fingerprint (the index is not used)
    (site / "plug.py").write_text("y = 1\n")
    _touch(site / "plug.py", 1_000)
    _touch(site, 1_000)
    plugin = PluginInfo("plug", "1.0", "main", "plug")
    monkeypatch.setattr(listing, "installed_plugins", lambda: [(plugin, None)])
    with_plugin = listing.fingerprint()
    assert with_plugin not in (None, first)
    _touch(site / "plug.py", 3_000)
    assert listing.fingerprint() not in (None, with_plugin)
    _touch(site / "plug.py", 1_000)
    newer = PluginInfo("plug", "1.1", "main", "plug")
    monkeypatch.setattr(listing, "installed_plugins", lambda: [(newer, None)])
    assert listing.fingerprint() not in (None, with_plugin)
    missing = PluginInfo("plug", "1.0", "main", "elsewhere.mod")
    monkeypatch.setattr(listing, "installed_plugins", lambda: [(missing, None)])
    assert listing.fingerprint() is None
