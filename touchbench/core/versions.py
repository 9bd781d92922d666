"""The one list of package versions: run manifests, model files and task identities use it.

Versions are read from the installed distributions' metadata, without
importing the packages (cheap, and safe for optional extras).
"""

from __future__ import annotations

import platform
from functools import lru_cache
from importlib import metadata

from .. import __version__

__all__ = ["PACKAGES", "package_versions"]

# Every package whose version can change a number touchbench reports.
PACKAGES = (
    "numpy", "scipy", "scikit-learn", "pandas", "pyarrow", "joblib", "pydantic", "PyYAML",
    "PyWavelets", "xgboost", "xgboost-cpu", "torch", "threadpoolctl", "aeon", "numba",
)


@lru_cache(maxsize=None)
def _installed() -> tuple[tuple[str, str | None], ...]:
    out = []
    for name in PACKAGES:
        try:
            out.append((name, metadata.version(name)))
        except metadata.PackageNotFoundError:
            out.append((name, None))
    return tuple(out)


def package_versions(installed_only: bool = False) -> dict[str, str | None]:
    """``{"touchbench": ..., "python": ..., package: version or None}``.

    ``installed_only=True`` leaves out packages that are not installed.
    """
    out: dict[str, str | None] = {"touchbench": __version__, "python": platform.python_version()}
    for name, version in _installed():
        if version is not None or not installed_only:
            out[name] = version
    return out
