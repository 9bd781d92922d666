"""The one list of package versions: run manifests, model files and task identities use it.

Versions are read from the installed distributions' metadata, without
importing the packages (cheap, and safe for optional extras).

Two questions, one function:

- ``package_versions()``: the packages whose version can change a number
  touchbench reports (:data:`PACKAGES`), for manifests and model files;
- ``package_versions(modules=[...])``: the distributions that provide the
  given top-level import names (``sklearn`` -> ``scikit-learn``, mapped with
  :func:`importlib.metadata.packages_distributions`) and, transitively, the
  installed distributions they require (scikit-learn's results depend on
  SciPy's version too), for task identities.
"""

from __future__ import annotations

import platform
import re
from functools import lru_cache
from importlib import metadata
from typing import Iterable

from .version import __version__

__all__ = ["PACKAGES", "SAME_PACKAGE", "missing_extra", "package_versions"]

# Every package whose version can change a number touchbench reports.
PACKAGES = (
    "numpy", "scipy", "scikit-learn", "pandas", "pyarrow", "joblib", "pydantic", "PyYAML",
    "PyWavelets", "xgboost", "xgboost-cpu", "torch", "threadpoolctl", "aeon", "numba",
)

_REQUIREMENT_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)")

# Distributions that install the same import package: either one installed satisfies the other.
SAME_PACKAGE: dict[str, tuple[str, ...]] = {"xgboost": ("xgboost-cpu",), "xgboost-cpu": ("xgboost",)}


@lru_cache(maxsize=None)
def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


@lru_cache(maxsize=None)
def _distributions_of_modules() -> dict[str, tuple[str, ...]]:
    return {k: tuple(v) for k, v in metadata.packages_distributions().items()}


@lru_cache(maxsize=None)
def _requirements(dist: str) -> tuple[str, ...]:
    """The distributions ``dist`` requires unconditionally (no extras), as installed names."""
    try:
        reqs = metadata.requires(dist) or []
    except metadata.PackageNotFoundError:
        return ()
    out = []
    for r in reqs:
        name, _, marker = r.partition(";")
        if "extra" in marker:
            continue  # an optional extra: not installed because of this distribution
        m = _REQUIREMENT_NAME.match(name)
        if m and _version(m.group(1)) is not None:
            out.append(metadata.metadata(m.group(1))["Name"])
    return tuple(out)


def _with_requirements(dists: Iterable[str]) -> dict[str, str | None]:
    out: dict[str, str | None] = {}
    todo = list(dists)
    while todo:
        d = todo.pop()
        if d in out:
            continue
        out[d] = _version(d)
        todo.extend(_requirements(d))
    return out


def package_versions(installed_only: bool = False, *, modules: Iterable[str] | None = None) -> dict[str, str | None]:
    """``{"touchbench": ..., "python": ..., package: version or None}``.

    Without ``modules``: the packages of :data:`PACKAGES`
    (``installed_only=True`` leaves out those that are not installed).
    With ``modules`` (top-level import names such as ``"sklearn"``): the
    distributions providing them and those they require, each installed;
    a name no installed distribution provides is left out.
    """
    out: dict[str, str | None] = {"touchbench": __version__, "python": platform.python_version()}
    if modules is not None:
        mapping = _distributions_of_modules()
        dists = sorted({d for m in modules for d in mapping.get(m, ())})
        found = _with_requirements(dists)
        out.update({d: v for d, v in sorted(found.items()) if v is not None})
        return out
    for name in PACKAGES:
        version = _version(name)
        if version is not None or not installed_only:
            out[name] = version
    return out


def missing_extra(extra: str, dist: str = "touchbench") -> list[str]:
    """The distributions of ``dist``'s optional ``extra`` (``pip install 'touchbench[EXTRA]'``) that
    are not installed, read from the installed metadata (nothing imported); ``[]`` when ``dist``'s
    metadata cannot be found (nothing to check against). A distribution counts as installed when
    one installing the same package is (:data:`SAME_PACKAGE`: ``xgboost-cpu`` for ``xgboost``).
    Several extras joined by commas (``"peers,deep"``) give the missing ones of all of them."""
    if "," in extra:
        return [m for part in extra.split(",") for m in missing_extra(part.strip(), dist)]
    try:
        reqs = metadata.requires(dist) or []
    except metadata.PackageNotFoundError:
        return []
    wanted = re.compile(r"""extra\s*==\s*["']""" + re.escape(extra) + r"""["']""")
    out = []
    for r in reqs:
        spec, _, marker = r.partition(";")
        m = _REQUIREMENT_NAME.match(spec)
        if m and wanted.search(marker):
            name = m.group(1)
            if all(_version(d) is None for d in (name, *SAME_PACKAGE.get(name.lower(), ()))):
                out.append(name)
    return out
