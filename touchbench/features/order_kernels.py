"""Order statistics in compiled loops, shared by the kernels modules of the feature sets (used when
numba is installed): :func:`select` (the value of a rank, by selection) and :func:`counted` (the values
of ascending ranks, read off counts of whole numbers). Both give exactly the value a sort would put
at the rank."""

from __future__ import annotations

import numba

jit = numba.njit(cache=True, nogil=True)


@jit
def select(x, m):
    """The ``m``-th smallest value of ``x`` (0-based), the value at ``m`` once sorted, reordering
    ``x`` in place so that nothing before ``m`` is larger (Hoare's selection)."""
    lo, hi = 0, x.size - 1
    while lo < hi:
        pivot = x[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while x[i] < pivot:
                i += 1
            while x[j] > pivot:
                j -= 1
            if i <= j:
                x[i], x[j] = x[j], x[i]
                i += 1
                j -= 1
        if m <= j:
            hi = j
        elif m >= i:
            lo = i
        else:
            break
    return x[m]


@jit
def counted(hist, s0, nb, lo, ranks, stats):
    """The order statistics ``ranks`` (ascending, 0-based) of a series held as counts
    ``hist[s0:s0 + nb]`` of the values ``lo + b`` into ``stats``."""
    cum = 0
    r = 0
    for b in range(nb):
        cum += hist[s0 + b]
        while r < ranks.size and ranks[r] < cum:
            stats[r] = lo + b
            r += 1
        if r == ranks.size:
            break
