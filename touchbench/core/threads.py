"""Thread limits for deterministic, non-oversubscribed work."""

from __future__ import annotations

import contextlib
import sys
from typing import Iterator

from threadpoolctl import threadpool_limits

__all__ = ["single_thread"]


@contextlib.contextmanager
def single_thread() -> Iterator[None]:
    """BLAS/OpenMP and torch (when already imported) limited to one thread."""
    torch = sys.modules.get("torch")
    prev = torch.get_num_threads() if torch is not None else None
    with threadpool_limits(limits=1):
        if torch is not None:
            torch.set_num_threads(1)
        try:
            yield
        finally:
            if torch is not None and prev is not None:
                torch.set_num_threads(prev)
