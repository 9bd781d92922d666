"""Every registry holds exactly the names of tests/snapshots/registry-names.json.

An intended change (a new feature set, classifier, reader...) is recorded by
regenerating the snapshot with ``make snapshots``; an unintended one (an
entry lost in a rename, a module that failed to register) fails here.
"""

from __future__ import annotations

import pytest
from snapshots.registries import current, snapshot


@pytest.mark.parametrize("kind", sorted(snapshot()))
def test_registry_matches_its_snapshot(kind):
    have, want = current()[kind], snapshot()[kind]
    added, lost = sorted(set(have) - set(want)), sorted(set(want) - set(have))
    assert have == want, (f"{kind}: registered but not in the snapshot: {added}; in the snapshot but not "
                          f"registered: {lost}. If this is intended, run `make snapshots` and commit the file.")


def test_snapshot_names_every_registry():
    assert sorted(snapshot()) == sorted(current())
