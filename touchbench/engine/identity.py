"""What a component's results depend on: its source and the packages it imports.

The feature cache keys and the task ids hash a component's identity, so
that editing its code (or a helper it imports) or upgrading a package it
uses makes the next run recompute what it affects, and only that.

The identity of a feature set or classifier is

- the source of every module it comes from: the modules defining the
  registered object (for a class, its bases too), for a classifier also the
  classes of the estimator its factory builds (nested estimators included),
  wherever they live (touchbench or a user's own module);
- followed through every ``import`` statement of those modules (at module
  level and inside functions) to the modules that are neither the standard
  library nor an installed third-party package, transitively, at most
  :data:`MAX_MODULES` modules (beyond that the identity says it is
  incomplete and the run gets a note); touchbench's own modules count as
  source wherever touchbench is installed;
- the components a parameter names: a string (or a list of strings) that is
  a registered feature set or classifier adds that component's identity
  (the ``touch-*`` classifiers build their feature sets by name);
- the versions of the third-party distributions those modules import and of
  the distributions these require (:func:`touchbench.core.versions.package_versions`),
  plus touchbench's and Python's versions.

A module's source is hashed by content, under its module name (moving a
checkout does not change it). A class or function whose module has no
source file (defined in a notebook) is hashed by its compiled code and the
simple module-level values it refers to. Files are read and parsed once per process
and read again when their size or modification time changes.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import inspect
import json
import os
import site
import sys
import sysconfig
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Iterable

from ..classifiers import CLASSIFIERS
from ..core.atomic import atomic_write_bytes
from ..core.errors import WriteError
from ..core.hashing import canonical_json, file_state, settled
from ..core.paths import cache_dir
from ..core.plugins import installed_plugins
from ..core.versions import package_versions
from ..features import FEATURES

__all__ = ["MAX_MODULES", "Identity", "classifier_identity", "feature_set_identity", "source_identity"]

MAX_MODULES = 400  # own modules followed per component before the walk stops


@dataclass(frozen=True)
class Identity:
    """A component's identity: ``digest`` hashes ``modules`` (name -> content hash) and ``packages``."""

    digest: str
    modules: dict[str, str] = field(default_factory=dict)
    packages: dict[str, str | None] = field(default_factory=dict)
    incomplete: bool = False  # the walk stopped at MAX_MODULES


# ----------------------------------------------------------------- modules
@functools.lru_cache(maxsize=None)
def _library_roots() -> tuple[str, ...]:
    """Folders of the standard library and of installed packages."""
    keys = ("stdlib", "platstdlib", "purelib", "platlib")
    roots: set[str] = set()
    for paths in (sysconfig.get_paths(), sysconfig.get_paths(vars={"base": sys.base_prefix, "platbase": sys.base_prefix})):
        roots.update(paths[k] for k in keys if k in paths)
    try:
        roots.update(site.getsitepackages())
        roots.add(site.getusersitepackages())
    except AttributeError:  # an old virtualenv's site module without these
        pass
    return tuple(sorted(os.path.realpath(r) for r in roots if r))


def _under(path: str, roots: Iterable[str]) -> bool:
    real = os.path.realpath(path)
    return any(real == r or real.startswith(r + os.sep) for r in roots)


_KINDS: dict[str, str] = {}


@functools.lru_cache(maxsize=1)
def _plugin_tops() -> frozenset[str]:
    """Top-level modules of the installed touchbench plugins: their source counts like
    touchbench's own, so editing a plugin recomputes its tasks even without a new version."""
    return frozenset(ep.value.split(":")[0].split(".")[0] for _, ep in installed_plugins())


def _top_kind(top: str) -> str:
    """``"stdlib"``, ``"package"`` (installed third party), ``"own"`` (source to follow) or ``"missing"``."""
    if top in _KINDS:
        return _KINDS[top]
    if top == "touchbench" or top in _plugin_tops():
        kind = "own"  # touchbench's and its plugins' source is followed, wherever they are installed
    elif top in sys.stdlib_module_names or top in sys.builtin_module_names or top == "__future__":
        kind = "stdlib"
    else:
        mod = sys.modules.get(top)
        if mod is not None:
            where = [getattr(mod, "__file__", None), *(getattr(mod, "__path__", None) or [])]
        else:
            try:
                spec = importlib.util.find_spec(top)
            except (ImportError, ValueError):
                spec = None
            if spec is None:
                return "missing"  # not remembered: the module may appear later
            where = [spec.origin if spec.has_location else None, *(spec.submodule_search_locations or [])]
        where = [str(p) for p in where if p]
        if not where:  # a module made in memory (a notebook's), or one built into the interpreter
            kind = "own" if mod is not None else "stdlib"
        elif any(_under(p, _library_roots()) for p in where):
            kind = "package"
        else:
            kind = "own"
    _KINDS[top] = kind
    return kind


def _module_file(name: str) -> tuple[str | None, bool]:
    """``(source file or None, is a package)`` of an importable module, without importing it when possible."""
    mod = sys.modules.get(name)
    if mod is not None:
        f = getattr(mod, "__file__", None)
        return (f if f and f.endswith(".py") else None), hasattr(mod, "__path__")
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None, False
    if spec is None:
        return None, False
    f = spec.origin if spec.has_location else None
    return (f if f and f.endswith(".py") else None), spec.submodule_search_locations is not None


def _is_module(name: str) -> bool:
    if name in sys.modules:
        return isinstance(sys.modules[name], ModuleType)
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


@functools.lru_cache(maxsize=4096)
def _parse(path: str, signature: tuple[int, ...]) -> tuple[str, tuple[tuple[str, tuple[str, ...], int], ...]]:
    """``(content hash, imports)`` of a source file; imports as ``(module, names, level)``."""
    data = Path(path).read_bytes()
    digest = hashlib.sha256(data).hexdigest()[:16]
    imports: list[tuple[str, tuple[str, ...], int]] = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # invalid escape sequences and the like
            tree = ast.parse(data, filename=path)
    except (SyntaxError, ValueError):
        return digest, ()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imports += [(a.name, (), 0) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            imports.append((node.module or "", tuple(a.name for a in node.names), node.level))
        elif (loops := _kernels_module(node)) is not None:
            imports.append((loops, (), 0))
    return digest, tuple(imports)


def _kernels_module(node: ast.AST) -> str | None:
    """The module a call ``kernels("features.gaus_kernels")`` imports
    (:func:`touchbench.core.compiled.kernels`: compiled loops imported by name on first use), so the
    walk follows it, and numba, as it follows an import statement; None for any other node."""
    if not isinstance(node, ast.Call) or len(node.args) != 1:
        return None
    func, arg = node.func, node.args[0]
    name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else None
    if name != "kernels" or not (isinstance(arg, ast.Constant) and isinstance(arg.value, str)):
        return None
    return f"touchbench.{arg.value}"


#: the versions of the distributions behind sets of import names, kept in the cache folder with the
#: state of the environment they were read in (``identity/packages.json``)
PACKAGES_RECORD = "packages.json"


#: each source file's content hash and imports with the file's state when it was parsed
#: (``identity/sources-2.json`` in the cache folder), so a new process parses only files written since;
#: the name changes with what a parse reads (2: the modules ``kernels("...")`` calls import)
SOURCES_RECORD = "sources-2.json"
_parsed: dict[str, Any] = {"path": None, "files": {}, "changed": False}


def _kept_parses() -> dict[str, Any]:
    """The parses kept in the cache folder (read once per process and cache folder)."""
    path = cache_dir() / "identity" / SOURCES_RECORD
    if _parsed["path"] != path:
        try:
            files = json.loads(path.read_text())
        except (OSError, ValueError):
            files = {}
        _parsed.update(path=path, files=files if isinstance(files, dict) else {}, changed=False)
    return _parsed["files"]


def _save_parses() -> None:
    """Write the kept parses when this process added some (a folder that cannot take them: parsed
    again next time)."""
    if _parsed["changed"] and _parsed["path"] is not None:
        try:
            atomic_write_bytes(_parsed["path"], json.dumps(_parsed["files"]).encode())
        except WriteError:
            pass
        _parsed["changed"] = False


def _file_info(path: str) -> tuple[str, tuple[tuple[str, tuple[str, ...], int], ...]]:
    """:func:`_parse` of ``path``, kept across processes while the file's state (modification and
    change times, size, inode) is the one it was parsed in; a file changed in the last
    ``RECENT_SECONDS`` (:mod:`touchbench.core.hashing`) is not kept (it could change again within the same timestamp tick)."""
    signature = file_state(path)
    kept = _kept_parses()
    entry = kept.get(path)
    if isinstance(entry, list) and len(entry) == 3 and entry[0] == signature:
        return entry[1], tuple((m, tuple(n), lvl) for m, n, lvl in entry[2])
    digest, imports = _parse(path, tuple(signature))
    if settled(signature[4]):
        kept[path] = [signature, digest, [[m, list(n), lvl] for m, n, lvl in imports]]
        _parsed["changed"] = True
    return digest, imports


def _imported_modules(name: str, is_package: bool, imports) -> list[tuple[str, bool]]:
    """``(absolute name, is a name imported from a module)`` of every import
    (``from m import x`` gives ``m`` and ``m.x``: ``x`` may be a submodule)."""
    package = name if is_package else name.rpartition(".")[0]
    out: list[tuple[str, bool]] = []
    for module, names, level in imports:
        if level:
            parts = package.split(".") if package else []
            if level - 1 > len(parts):
                continue
            base = parts[: len(parts) - (level - 1)]
            module = ".".join(base + ([module] if module else []))
        if not module:
            continue
        out.append((module, False))
        out += [(f"{module}.{n}", True) for n in names if n != "*"]
    return out


def _walk(roots: Iterable[str]) -> tuple[dict[str, str], set[str], bool]:
    """Follow the imports from the modules ``roots``: ``(own module -> content hash, package tops, incomplete)``."""
    own: dict[str, str] = {}
    tops: set[str] = set()
    seen: set[str] = set()
    todo = [(r, False) for r in roots]
    incomplete = False
    while todo:
        name, from_name = todo.pop()
        if name in seen:
            continue
        top = name.partition(".")[0]
        kind = _top_kind(top)
        if kind == "package":
            tops.add(top)
        if kind != "own":
            seen.add(name)
            continue
        seen.add(name)
        if from_name and not (_module_file(name.rpartition(".")[0])[1] and _is_module(name)):
            continue  # ``from m import name``: a name defined in m, not a submodule
        path, is_package = _module_file(name)
        if path is None:
            continue
        if len(own) >= MAX_MODULES:
            incomplete = True
            break
        digest, imports = _file_info(path)
        own[name] = digest
        todo.extend(m for m in _imported_modules(name, is_package, imports) if m[0] not in seen)
    return own, tops, incomplete


# ----------------------------------------------------------------- components
def _module_of(obj: Any) -> str | None:
    if inspect.ismodule(obj):
        return obj.__name__
    return getattr(obj, "__module__", None) or getattr(type(obj), "__module__", None)


def _defining_modules(obj: Any) -> list[str]:
    """The modules defining ``obj`` (a module, class, function or instance) and, for a class, its bases."""
    if inspect.ismodule(obj):
        return [obj.__name__]
    if isinstance(obj, functools.partial):
        return _defining_modules(obj.func)
    klass = obj if inspect.isclass(obj) else None
    if klass is None and not (inspect.isfunction(obj) or inspect.ismethod(obj) or inspect.isbuiltin(obj)):
        klass = type(obj)
    if klass is None:
        m = _module_of(obj)
        return [m] if m else []
    return [k.__module__ for k in klass.__mro__ if getattr(k, "__module__", None) not in (None, "builtins")]


def _named_components(value: Any, depth: int = 0) -> list[tuple[str, str]]:
    """Registered feature sets / classifiers named by a parameter value (strings, nested lists, dicts)."""
    if depth > 4:
        return []
    if isinstance(value, str):
        out = []
        if value in FEATURES:
            out.append(("feature set", value))
        if value in CLASSIFIERS:
            out.append(("classifier", value))
        return out
    if isinstance(value, dict):
        return [c for v in value.values() for c in _named_components(v, depth + 1)]
    if isinstance(value, (list, tuple, set, frozenset)):
        return [c for v in value for c in _named_components(v, depth + 1)]
    return []


def _estimator_parts(obj: Any, depth: int = 0) -> tuple[list[Any], list[Any]]:
    """``(objects whose classes count, parameter values)`` of an estimator, nested estimators included."""
    if depth > 6:
        return [], []
    objs, values = [obj], []
    get_params = getattr(obj, "get_params", None)
    if get_params is None or inspect.isclass(obj):
        return objs, values
    try:
        params = get_params(deep=False)
    except Exception:  # not a scikit-learn style estimator after all
        return objs, values
    for v in params.values():
        for item in (v if isinstance(v, (list, tuple)) else [v]):
            for sub in (item if isinstance(item, tuple) else [item]):
                if hasattr(sub, "get_params") and not inspect.isclass(sub):
                    o, vals = _estimator_parts(sub, depth + 1)
                    objs += o
                    values += vals
                else:
                    values.append(sub)
    return objs, values


_SIMPLE = (int, float, complex, str, bytes, bool, type(None))


def _code_digest(obj: Any) -> str:
    """A hash of the compiled code of a function or class defined without a source file (a notebook, say):
    its bytecode, constants and names, and the simple module-level values those names refer to."""
    h = hashlib.sha256()

    def code(c: Any, glob: dict[str, Any]) -> None:
        h.update(c.co_code + repr((c.co_names, c.co_varnames)).encode())
        for k in c.co_consts:
            if hasattr(k, "co_code"):
                code(k, glob)
            else:
                h.update(repr(k).encode())
        for n in c.co_names:
            v = glob.get(n)
            if isinstance(v, _SIMPLE) or (isinstance(v, tuple) and all(isinstance(x, _SIMPLE) for x in v)):
                h.update(f"{n}={v!r}".encode())

    def function(f: Any) -> None:
        f = getattr(f, "__func__", f)
        if isinstance(f, property):
            f = f.fget
        if hasattr(f, "__code__"):
            code(f.__code__, getattr(f, "__globals__", {}))

    if inspect.isclass(obj):
        for klass in obj.__mro__:
            if klass.__module__ != obj.__module__:
                continue
            for name, v in sorted(vars(klass).items()):
                if isinstance(v, _SIMPLE):
                    h.update(f"{name}={v!r}".encode())
                else:
                    function(v)
    else:
        function(obj)
    return hashlib.sha256(h.digest()).hexdigest()[:16]


def _fileless(objects: Iterable[Any]) -> dict[str, str]:
    """``"module:qualname" -> code hash`` of the objects whose own module has no source file."""
    out: dict[str, str] = {}
    for o in objects:
        o = o.func if isinstance(o, functools.partial) else o
        target = o if (inspect.isclass(o) or inspect.isfunction(o)) else type(o)
        module = getattr(target, "__module__", None)
        if not module or _top_kind(module.partition(".")[0]) not in ("own", "missing") or _module_file(module)[0]:
            continue
        out[f"{module}:{target.__qualname__}"] = _code_digest(target)
    return out


def _environment_state() -> list[list[Any]]:
    """What changes when a distribution is installed, upgraded or removed: the metadata folders
    (``*.dist-info``, ``*.egg-info``) in each folder of the import path, with their modification times."""
    out = []
    for entry in sys.path:
        folder = os.path.abspath(entry or ".")
        try:
            names = sorted(n for n in os.listdir(folder) if n.endswith((".dist-info", ".egg-info")))
        except OSError:
            continue
        for name in names:
            try:
                out.append([os.path.join(folder, name), os.stat(os.path.join(folder, name)).st_mtime_ns])
            except OSError:
                continue
    return out


@functools.lru_cache(maxsize=None)
def _versions_of(tops: tuple[str, ...]) -> dict[str, str | None]:
    """:func:`touchbench.core.versions.package_versions` of the import names ``tops``, kept on disk
    while the environment is as it was when they were read (:func:`_environment_state`); reading
    every installed distribution's file list to map import names to distributions costs a new
    process a third of a second."""
    state = _environment_state()
    path = cache_dir() / "identity" / PACKAGES_RECORD
    key = canonical_json({"state": state, "tops": list(tops), "python": sys.version})
    try:
        kept = json.loads(path.read_text())
    except (OSError, ValueError):
        kept = {}
    if isinstance(kept, dict) and isinstance(kept.get(key), dict):
        return dict(kept[key])
    versions = dict(package_versions(modules=list(tops)))
    if all(settled(mtime) for _, mtime in state):
        kept = {k: v for k, v in kept.items() if json.loads(k).get("state") == state} if isinstance(kept, dict) else {}
        kept[key] = versions
        try:
            atomic_write_bytes(path, json.dumps(kept).encode())
        except WriteError:  # a cache folder that cannot take it: read again next time
            pass
    return versions


def _identity(objects: Iterable[Any], params: Any, seen: frozenset[tuple[str, str]]) -> Identity:
    objects = list(objects)
    roots = [m for o in objects for m in _defining_modules(o)]
    own, tops, incomplete = _walk(roots)
    _save_parses()
    modules = {**own, **_fileless(objects)}
    packages = dict(_versions_of(tuple(sorted(tops))))
    for kind, name in _named_components(params):
        if (kind, name) in seen:
            continue
        sub = _component(kind, name, {}, seen | {(kind, name)})
        modules.update(sub.modules)
        packages.update(sub.packages)
        incomplete = incomplete or sub.incomplete
    packages = dict(sorted(packages.items()))
    digest = hashlib.sha256(canonical_json({"modules": sorted(modules.items()), "packages": packages}).encode()).hexdigest()[:20]
    return Identity(digest=digest, modules=dict(sorted(modules.items())), packages=packages, incomplete=incomplete)


def _component(kind: str, name: str, params: dict[str, Any], seen: frozenset[tuple[str, str]]) -> Identity:
    if kind == "feature set":
        return _identity([FEATURES.get(name)], params, seen)
    factory = CLASSIFIERS.get(name)
    objects: list[Any] = [factory]
    values: list[Any] = [params]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est = factory(random_state=0, **params)
    except Exception:  # the task will fail with this error; the factory's source still counts
        est = None
    if est is not None:
        objs, vals = _estimator_parts(est)
        objects += objs
        values += vals
    return _identity(objects, values, seen)


def source_identity(*objects: Any, params: Any = None) -> Identity:
    """The identity of arbitrary objects (modules, classes, functions, instances)."""
    return _identity(objects, params, frozenset())


def feature_set_identity(name: str, params: dict[str, Any] | None = None) -> Identity:
    """The identity of the registered feature set ``name`` with ``params``."""
    return _component("feature set", name, dict(params or {}), frozenset({("feature set", name)}))


def classifier_identity(name: str, params: dict[str, Any] | None = None) -> Identity:
    """The identity of the registered classifier ``name`` built with ``params`` (its estimator classes included)."""
    return _component("classifier", name, dict(params or {}), frozenset({("classifier", name)}))
