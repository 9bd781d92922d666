"""Seeds derived from a protocol seed and an identity.

Every random choice in a run (fold assignment, a classifier's
``random_state``) is seeded by :func:`derive_seed` from the protocol's
``seed`` and a string naming what is being seeded (repetition, fold, feature
combination, classifier). The derivation is a hash, not a running random
generator, so a seed does not depend on the order tasks run in or on how many
run in parallel: a rerun gives bit-identical results.
"""

from __future__ import annotations

import hashlib


def derive_seed(seed: int, *identity: object) -> int:
    """A seed in ``[0, 2**31 - 1)`` from ``seed`` and the parts of an identity.

    >>> derive_seed(0, "rep0", "fold f1") == derive_seed(0, "rep0", "fold f1")
    True
    >>> derive_seed(0, "a") != derive_seed(1, "a")
    True
    """
    text = "\x1f".join([str(int(seed))] + [str(p) for p in identity])
    digest = hashlib.sha256(text.encode()).digest()
    return int.from_bytes(digest[:8], "big") % (2**31 - 1)
