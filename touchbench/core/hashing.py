"""Canonical JSON for hashing and for parameter columns, and the state of a file that a kept digest
is trusted for."""

from __future__ import annotations

import json
import os
import time
from typing import Any

__all__ = ["RECENT_SECONDS", "canonical_json", "file_state", "settled"]

#: a file changed less than this many seconds ago may change again within the same timestamp tick:
#: what was read from it then is not kept
RECENT_SECONDS = 2.0


def canonical_json(obj: Any) -> str:
    """JSON with sorted keys and no spaces, for hashing and for the ``params`` columns.

    >>> canonical_json({"b": 1, "a": [1, 2.5, None]})
    '{"a":[1,2.5,null],"b":1}'
    """
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def file_state(path: str | os.PathLike) -> list[int]:
    """What changes whenever a file is written: device, inode, size, modification and change times
    (the change time is the system's: setting the modification time back changes it)."""
    st = os.stat(path)
    return [st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns]


def settled(changed_ns: int) -> bool:
    """Whether something last changed at ``changed_ns`` (a time in ns) changed over
    :data:`RECENT_SECONDS` ago, so that what was read from it may be kept."""
    return time.time_ns() - changed_ns > RECENT_SECONDS * 1e9
