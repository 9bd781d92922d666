"""The one switch between the feature sets' compiled loops and their numpy path.

Where numba is installed (an optional dependency: the ``peers`` extra brings it), the feature sets
that have compiled loops (the touch sets, ``contact-evidence``, the five Gaus sets) and the live forest
walk run them, from a kernels module imported on first use and compiled once per machine into
numba's on-disk cache. Without numba every one runs its vectorised numpy code, which stays the
reference the loops are tested against (within 1e-9 for the feature sets; the forest walk gives
scikit-learn's probabilities bit for bit). :func:`kernels` is the only way code asks for its loops.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
from types import ModuleType

#: whether the compiled loops run where numba is installed; the tests set it False to compare them
#: with the numpy path. Not a user setting: a run's identity (its feature cache keys and task ids)
#: holds numba's version, not this switch, so both paths of one environment must not share a cache.
COMPILED = True


@functools.lru_cache(maxsize=1)
def _numba_installed() -> bool:
    return importlib.util.find_spec("numba") is not None


#: the kernels modules imported so far, by the name :func:`kernels` was given (a live decision asks
#: several times per window: a dictionary read, not the import machinery)
_LOADED: dict[str, ModuleType] = {}


def kernels(module: str) -> ModuleType | None:
    """The kernels module ``module`` of touchbench (e.g. ``"features.gaus_kernels"``), compiled on
    first use, or None without numba (the numpy path) or when :data:`COMPILED` is False."""
    if not COMPILED or not _numba_installed():
        return None
    found = _LOADED.get(module)
    if found is None:
        found = _LOADED[module] = importlib.import_module(f"touchbench.{module}")
    return found
