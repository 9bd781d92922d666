"""single_thread: every native thread pool of the process limited to one thread inside, as before after."""

from __future__ import annotations

import numpy  # noqa: F401 - loads BLAS, whose thread pool the test reads
from threadpoolctl import threadpool_info

from touchbench.core.threads import single_thread


def _threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info()]


def test_every_pool_has_one_thread_inside_and_its_own_count_after():
    before = _threads()
    assert before  # numpy's BLAS at least
    for _ in range(2):  # the second time reuses the pools found the first time
        with single_thread():
            assert _threads() == [1] * len(before)
        assert _threads() == before
