"""The validation passes after the shape (see :mod:`touchbench.protocols.schema`): the number
of entries the grids expand to, the scheme's parameters, feature and classifier parameters (names
and values: a classifier's own checks, :func:`touchbench.classifiers.check_classifier_params`,
for every entry and every candidate nested in one), the ``expected`` references, each
evaluation's dataset and target. Each pass gives ``(field location, message)`` issues."""

from __future__ import annotations

import inspect
import itertools
import math
import re
from typing import Any, Collection

from pydantic import ValidationError

from ..catalog import dataset_ref_problem, format_ref_problem
from ..classifiers import CLASSIFIERS, ParamError, check_classifier_params
from ..core.constraints import declared_failures
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.suggest import did_you_mean
from ..core.versions import missing_extra
from ..datasets.formats import FORMATS
from ..datasets.registry import DATASETS, LOADER_PLACES, WRITE_LOCATIONS
from ..features import FEATURES
from ..features.base import FeatureInputError, SensorNeededError, make_feature_set
from ..methods import METHODS, expand_candidates
from .entries import FeatureRef, _fmt_value, _is_grid, expand_grid
from .errors import _loc_str, _make_error, _pydantic_issues
from .expected import ExpectedBest
from .schema import MAX_ENTRIES, Protocol, protocol_dataset_ref
from .schemes import SPLITTERS, SplitError
from .schemes.base import WrappingParams
from .specs import EVALUATION_FIELDS


def _scheme_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """The scheme's parameters, validated once (:meth:`Protocol.scheme_params`: the scheme is built
    from that model), and the scheme each wraps."""
    cls = SPLITTERS.get(protocol.scheme.name)  # a known name: the shape checked it
    try:
        validated = protocol.scheme_params()
    except ValidationError as e:
        return _pydantic_issues(e, cls.Params, ("scheme",))
    return _base_issues(validated, ("scheme",))


def _base_issues(validated: Any, prefix: tuple) -> list[tuple[tuple, str]]:
    """The scheme that the scheme of parameters ``validated`` wraps (its ``base``), validated once by
    its own model (:attr:`WrappingParams.base_params`, from which it is built), and the one that wraps."""
    if not isinstance(validated, WrappingParams):
        return []
    at = prefix + ("base",)
    name = validated.base.get("name")
    if not isinstance(name, str):
        return [(at, "base must name a scheme: base: {name: loso}")]
    if name not in SPLITTERS:
        return [(at + ("name",), SPLITTERS.suggest(name))]
    try:
        base = validated.base_params
    except ValidationError as e:
        return _pydantic_issues(e, SPLITTERS.get(name).Params, at)
    return _base_issues(base, at)


def _accepted_params(obj: Any) -> tuple[list[str], bool]:
    """Parameter names a constructor / factory accepts, and whether it takes **kwargs."""
    names: list[str] = []
    var_kw = False
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return names, True
    for p in sig.parameters.values():
        if p.kind is inspect.Parameter.VAR_KEYWORD:
            var_kw = True
        elif p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY):
            names.append(p.name)
    return names, var_kw


def _grid_size(params: dict[str, Any]) -> int:
    """How many entries ``params`` expands to (a grid that is not a list counts once: refused elsewhere)."""
    return math.prod(len(v["grid"]) if isinstance(v["grid"], list) else 1 for v in params.values() if _is_grid(v))


def _size_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """The number of entries the protocol expands to, counted without expanding anything.

    Feature combinations x classifier entries + method entries, every grid
    expanded; more than :data:`MAX_ENTRIES` is refused at the largest grid.
    """
    sizes: list[tuple[int, tuple]] = []
    n_combos = 0
    for i, combo in enumerate(protocol.features):
        n = 1
        for j, ref in enumerate(combo):
            sizes.append((_grid_size(ref.params), ("features", i, j, "params")))
            n *= sizes[-1][0]
        n_combos += n
    n_clf = 0
    for i, spec in enumerate(protocol.classifiers):
        sizes.append((_grid_size(spec.params), ("classifiers", i, "params")))
        n_clf += sizes[-1][0]
    n_methods = 0
    for i, m in enumerate(protocol.methods):
        sizes.append((_grid_size(m.params), ("methods", i, "params")))
        n_methods += sizes[-1][0]
    total = n_combos * n_clf + n_methods
    if total <= MAX_ENTRIES:
        return []
    largest, loc = max(sizes, key=lambda x: x[0])
    shape = f"{n_combos} feature combination(s) x {n_clf} classifier entries" + (
        f" + {n_methods} method entries" if protocol.methods else "")
    return [(loc if largest > 1 else ("features",),
             f"the protocol expands to {total} entries ({shape}, grids expanded): at most {MAX_ENTRIES}"
             + (f"; this grid gives {largest}" if largest > 1 else "") + ": make the grids smaller or split the protocol")]


def _shape_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """Empty filters and empty feature combinations (named by their key / index)."""
    issues = []
    for col, values in protocol.dataset.filters.items():
        if not values:
            issues.append((("dataset", "filters", col),
                           f"the {col} filter is empty: it would leave no captures; "
                           "list the values to keep, or remove the filter"))
    for i, combo in enumerate(protocol.features):
        if not combo:
            issues.append((("features", i), "this feature combination is empty: list at least one feature set"))
    combos = [(("features", i), combo) for i, combo in enumerate(protocol.features)]
    combos += [(("methods", i, "features"), m.features) for i, m in enumerate(protocol.methods) if m.features]
    for at, refs in combos:
        issues += _repeated_set_issues(at, refs)
    return issues


def _repeated_set_issues(at: tuple, refs: list[FeatureRef]) -> list[tuple[tuple, str]]:
    """A feature set listed twice with the same parameters in one combination, at its second place."""
    issues = []
    seen: dict[str, int] = {}
    for j, ref in enumerate(refs):
        key = canonical_json([ref.name, ref.params])
        if key in seen:
            issues.append((at + (j,), f"feature set {ref.name!r} is listed twice in this combination (also at "
                                      f"{_loc_str(at + (seen[key],))}): list each feature set once"))
        seen.setdefault(key, j)
    return issues


def _feature_value_issue(name: str, params: dict[str, Any]) -> str | None:
    """The feature set's declared domains (``check_declared``) and own parameter checks
    (``_check_params``) for every grid value, without a sensor.

    A set that leaves a value to the sensor (``SensorNeededError``) is
    asked again by the plan, with the dataset's sensor."""
    for p in expand_grid(params):
        try:
            fs = make_feature_set(name, p, None)
            fs.check_declared()
            fs._check_params()
        except SensorNeededError:
            continue
        except FeatureInputError as e:
            return str(e)
        except Exception as e:  # a value of the wrong type that the check did not foresee
            return f"feature set {name!r} rejects {p}: {type(e).__name__}: {e}"
    return None


def _feature_issues(protocol: Protocol) -> list[tuple[tuple, str]]:

    issues = []
    refs = [(("features", i, j), ref) for i, combo in enumerate(protocol.features) for j, ref in enumerate(combo)]
    refs += [(("methods", i, "features", j), ref) for i, m in enumerate(protocol.methods)
             for j, ref in enumerate(m.features or [])]
    for at, ref in refs:
        cls = FEATURES.get(ref.name)
        names, var_kw = _accepted_params(cls)
        names = [n for n in names if n not in ("self",)]
        n_before = len(issues)
        for k, v in ref.params.items():
            loc = at + ("params", k)
            if k == "sensor":
                issues.append((loc, "the engine passes the dataset's sensor; do not set 'sensor'"))
            elif not var_kw and k not in names:
                issues.append((loc, f"unknown parameter {k!r} for feature set {ref.name!r}"
                                    f"{did_you_mean(k, names)} (accepted: {', '.join(n for n in names if n != 'sensor') or 'none'})"))
            elif _is_grid(v) and not (isinstance(v["grid"], list) and v["grid"]):
                issues.append((loc + ("grid",), "a grid must be a non-empty list of values"))
        if len(issues) == n_before:
            problem = _feature_value_issue(ref.name, ref.params)
            if problem:
                issues.append((_param_loc(at + ("params",), ref.params, problem), problem))
    return issues


def _estimator_issues(name: str, params: dict[str, Any], loc: tuple, what: str) -> list[tuple[tuple, str]]:
    """Parameters of the classifier or named method ``name`` (a method's go to its estimator), at ``loc``;
    none when its optional extra is missing (it cannot be built here; the run of it is refused:
    :func:`require_extras`)."""
    est_name, base = _estimator_and_defaults(name)
    factory = CLASSIFIERS.get(est_name)
    extra = CLASSIFIERS.entry(est_name).tags.get("extra")
    if extra and missing_extra(extra):
        return []
    issues = _reserved_param_issues(params, loc)
    issues += _unknown_param_issues(name, params, _estimator_param_names(factory), loc, what)
    if issues:
        return issues
    return _construction_issues(factory, base, name, params, loc, what) or _own_check_issues(est_name, base, params, loc)


def _own_check_issues(est_name: str, base: dict[str, Any], params: dict[str, Any], loc: tuple) -> list[tuple[tuple, str]]:
    """The first point of the grid ``params`` whose values the classifier's own checks refuse
    (``check_classifier_params``: its registry entry's ``check_params`` and those of the classifiers
    nested in it, candidates written out), at the field the refusal names; the declared domains of
    the estimator itself were checked when it was built (:func:`_construction_issues`)."""
    for p in expand_grid(params):
        try:
            check_classifier_params(est_name, expand_candidates(est_name, {**base, **p}), declared=False)
        except ParamError as e:
            return [(loc + ("params",) + e.field, str(e))]
        except TouchbenchError as e:  # a candidate that cannot be written out
            return [(loc + ("params",), str(e))]
        except Exception as e:  # a value of a type the check did not foresee
            return [(loc + ("params",), f"{est_name!r} rejects {p}: {type(e).__name__}: {e}")]
    return []


def _estimator_and_defaults(name: str) -> tuple[str, dict[str, Any]]:
    """The classifier ``name`` builds and the parameters it sets: a named method's estimator and
    defaults, else ``name`` itself and none."""
    if name in METHODS:  # a named method's parameters go to its estimator
        tags = METHODS.entry(name).tags
        return tags["estimator"], dict(tags.get("defaults") or {})
    return name, {}


def _reserved_param_issues(params: dict[str, Any], loc: tuple) -> list[tuple[tuple, str]]:
    """The parameters a protocol may not set (``random_state``, ``sensor``) and empty grids."""
    issues: list[tuple[tuple, str]] = []
    for k, v in params.items():
        at = loc + ("params", k)
        if k == "random_state":
            issues.append((at, "random_state is derived from the protocol's seed; set 'seed' instead"))
        elif k == "sensor":
            issues.append((at, "the engine passes the dataset's sensor; do not set 'sensor'"))
        elif _is_grid(v) and not (isinstance(v["grid"], list) and v["grid"]):
            issues.append((at + ("grid",), "a grid must be a non-empty list of values"))
    return issues


def _estimator_param_names(factory: Any) -> list[str]:
    """The parameters ``factory`` accepts: its own, and, when it forwards ``**params`` to an
    estimator, the names that estimator's ``get_params()`` gives."""
    names, var_kw = _accepted_params(factory)
    if var_kw:
        try:
            est = factory(random_state=0)
            names = sorted(set(names) | set(getattr(est, "get_params", lambda: {})()))
        except Exception:  # pragma: no cover - a broken factory is reported at construction below
            pass
    return names


def _unknown_param_issues(name: str, params: dict[str, Any], names: list[str], loc: tuple,
                          what: str) -> list[tuple[tuple, str]]:
    """The parameters of ``params`` that are not among ``names`` (none when ``names`` is empty)."""
    known = [n for n in names if n not in ("random_state",)]
    return [(loc + ("params", k), f"unknown parameter {k!r} for {what} {name!r}{did_you_mean(k, known)}")
            for k in params if k != "random_state" and known and k not in names]


def _construction_issues(factory: Any, base: dict[str, Any], name: str, params: dict[str, Any], loc: tuple,
                         what: str) -> list[tuple[tuple, str]]:
    """The first point of the grid ``params`` that the estimator refuses to be built with, or whose
    values its own parameter validation refuses (beyond what its defaults already break)."""
    try:  # what the estimator's own defaults break is the estimator's business (a subclass widening a domain)
        own = set(_constraint_failures(factory(random_state=0, **base)))
    except Exception:
        own = set()
    for p in expand_grid(params):
        try:
            est = factory(random_state=0, **{**base, **p})
        except Exception as e:  # any construction error is a protocol error
            return [(_param_loc(loc + ("params",), p, str(e)), f"{what} {name!r} rejects {p}: {type(e).__name__}: {e}")]
        problem = next((m for k, m in _constraint_failures(est).items() if k not in own), None)
        if problem:
            return [(_param_loc(loc + ("params",), p, problem), f"{what} {name!r} rejects {p}: {problem}")]
    return []


def _constraint_failures(est: Any) -> dict[tuple[str, str], str]:
    """scikit-learn's own parameter validation of ``est`` and of the estimators among its
    parameters, without fitting: ``(path, parameter) -> message`` for each parameter that
    ``_validate_params`` refuses against its ``_parameter_constraints`` (asked one parameter
    at a time, so that one refusal does not hide the next; a boolean never read as a number:
    :func:`touchbench.core.constraints.declared_failures`)."""
    parts: dict[str, Any] = {"": est}
    try:
        parts.update({k: v for k, v in est.get_params(deep=True).items() if hasattr(v, "_parameter_constraints")})
    except Exception:  # an estimator without scikit-learn's get_params: nothing more to ask
        pass
    out: dict[tuple[str, str], str] = {}
    for path, part in parts.items():
        constraints = getattr(part, "_parameter_constraints", None)
        if not callable(getattr(part, "_validate_params", None)) or not isinstance(constraints, dict):
            continue
        found = declared_failures(constraints, part.get_params(deep=False), type(part).__name__)
        out.update({(path, k): m for k, m in found.items()})
    return out


def _param_loc(at: tuple, params: dict[str, Any], message: str) -> tuple:
    """``at`` + the parameter ``message`` names, when it names exactly one of ``params``."""
    named = [k for k in params if re.search(r"(?<![\w])" + re.escape(str(k)) + r"(?![\w])", message)]
    return at + (named[0],) if len(named) == 1 else at


def _classifier_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    issues = []
    for i, spec in enumerate(protocol.classifiers):
        issues += _estimator_issues(spec.name, spec.params, ("classifiers", i), "classifier")
    for i, m in enumerate(protocol.methods):
        if m.name is not None:
            issues += _estimator_issues(m.name, m.params, ("methods", i), "method")
        else:
            issues += _estimator_issues(m.estimator or "", m.params, ("methods", i), "classifier")
    return issues


def entry_extras(protocol: Protocol, labels: Collection[str] | None = None) -> list[tuple[tuple, str, str]]:
    """``(field, what, extra)`` of each classifier or method entry of ``protocol`` (those whose method
    label is in ``labels``; all without) whose estimator needs an optional extra (its ``extra`` tag:
    ``"deep"``, ``"peers,deep"``...), once per field; ``what`` names the entry (``classifier 'cnn'``)."""
    out = []
    for _, k, loc in protocol._entry_pairs():
        if labels is not None and k.label not in labels:
            continue
        est_name = _estimator_and_defaults(k.name)[0]
        extra = CLASSIFIERS.entry(est_name).tags.get("extra") if est_name in CLASSIFIERS else None
        if extra:
            named = loc[0] == "methods" and protocol.methods[loc[1]].name is not None
            out.append((loc, f"{'method' if named else 'classifier'} {k.name!r}", str(extra)))
    return list(dict.fromkeys(out))


def needed_extras(protocol: Protocol) -> dict[str, list[str]]:
    """Each optional extra some entry of ``protocol`` needs, with its distributions not installed
    here (``[]``: installed), in the order the protocol names them."""
    extras = [part.strip() for _, _, extra in entry_extras(protocol) for part in extra.split(",")]
    return {extra: missing_extra(extra) for extra in dict.fromkeys(extras)}


def require_extras(protocol: Protocol, labels: Collection[str] | None = None) -> None:
    """Refuse to run the entries of ``protocol`` (those whose method label is in ``labels``; all
    without) that need an optional extra not installed here, each at its field with the install line."""
    issues = []
    for loc, what, extra in entry_extras(protocol, labels):
        missing = missing_extra(extra)
        if missing:
            issues.append((loc, f"{what} needs the optional {extra!r} extra, not installed here "
                                f"({', '.join(missing)} missing): pip install 'touchbench[{extra}]'"))
    if issues:
        raise _make_error(protocol.path, protocol._lines, issues, protocol._booleans)


def _duplicate_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """Two entries that describe the same method (what a task's identity takes of it: its content,
    name and parameters), refused at the second one's field: a repeated classifier entry at its
    own, a repeated feature combination at its own, a repeated ``methods:`` entry at its own."""
    combo_at = [j for j, combo in enumerate(protocol.features)
                for _ in itertools.product(*[expand_grid(r.params) for r in combo])]
    n_clf = sum(len(expand_grid(spec.params)) for spec in protocol.classifiers)
    seen: dict[str, tuple[tuple, int | None]] = {}
    issues = []
    for n, (c, k, loc) in enumerate(protocol._entry_pairs()):
        combo = combo_at[n // n_clf] if loc[0] == "classifiers" and n_clf and n // n_clf < len(combo_at) else None
        try:
            m = protocol._method(c, k, loc)
        except TouchbenchError:
            continue  # refused by its own check
        ident = canonical_json([m.key, m.name, m.params])
        if ident not in seen:
            seen[ident] = (loc, combo)
            continue
        first, first_combo = seen[ident]
        at = ("features", combo) if loc == first and combo is not None else loc
        was = ("features", first_combo) if at[0] == "features" else first
        issues.append((at, f"this entry describes the same method as {_loc_str(was)} ({m.label!r}), so the "
                           "same tasks: list each method once"))
    return issues


def _design_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    """A ``design`` block naming a method the protocol does not evaluate (the leaderboard's design
    note would say something false), at the name's line, with the nearest names. A method is named
    as the leaderboard names it: its label, or ``features / label``."""
    names: set[str] = set()
    for c, k, loc in protocol._entry_pairs():
        try:
            m = protocol._method(c, k, loc)
        except TouchbenchError:
            return []  # refused by its own check
        names |= {m.label, f"{m.features_label} / {m.label}"}
    issues = []
    for at, design in [(("design",), protocol.design)] + [
            (("evaluations", i, "design"), ev.design) for i, ev in enumerate(protocol.evaluations)]:
        blocks = design if isinstance(design, list) else [] if design is None else [design]
        for b, block in enumerate(blocks):
            where = at + ((b,) if isinstance(design, list) else ()) + ("methods",)
            for j, name in enumerate(block.methods):
                if name not in names:
                    issues.append((where + (j,), f"design names method {name!r}, which this protocol does not "
                                                 f"evaluate{did_you_mean(name, sorted(names))}"))
    return issues


def _expected_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    if protocol.expected is None:
        return []
    entries = protocol._entry_pairs()
    combos = [c for c, _, _ in entries]
    by_names = {"+".join(c.names) for c in combos} | {c.label for c in combos}
    clfs = [k for _, k, _ in entries]
    clf_names = ({c.label for c in clfs} | {c.name for c in clfs} | {s.label for s in protocol.classifiers if s.label}
                 | {m.label for m in protocol.methods if m.label})
    labels = sorted(c.label for c in clfs)
    issues = []
    for i, r in enumerate(protocol.expected.results):
        key = "+".join(r.features)
        if key not in by_names:
            issues.append((("expected", "results", i, "features"),
                           f"no feature combination {r.features} in this protocol{did_you_mean(key, sorted(by_names))}"))
        if r.classifier not in clf_names:
            issues.append((("expected", "results", i, "classifier"),
                           f"no classifier {r.classifier!r} in this protocol{did_you_mean(r.classifier, sorted(clf_names))}"))
    for field in ("standard_deviations", "confusions"):
        for i, c in enumerate(getattr(protocol.expected, field)):
            if c.classifier not in labels:
                issues.append((("expected", field, i, "classifier"),
                               f"no classifier entry labelled {c.classifier!r} in this protocol"
                               f"{did_you_mean(c.classifier, labels)} (labels: {', '.join(labels)})"))
    for i, b in enumerate(protocol.expected.best_parameters):
        issues += [(("expected", "best_parameters", i) + loc, msg) for loc, msg in _best_issues(protocol, b)]
    return issues


def _best_issues(protocol: Protocol, best: ExpectedBest) -> list[tuple[tuple, str]]:
    """Whether ``best`` names a grid of one of the protocol's classifiers and one of its values."""
    specs = [s for s in protocol.classifiers if s.name == best.classifier]
    if not specs:
        names = sorted({s.name for s in protocol.classifiers})
        return [(("classifier",), f"no classifier {best.classifier!r} in this protocol{did_you_mean(best.classifier, names)}")]
    grids = {k: v["grid"] for s in specs for k, v in s.params.items() if _is_grid(v)}
    if best.parameter not in grids:
        return [(("parameter",), f"{best.classifier} has no grid of {best.parameter!r} to take the best of"
                                 f"{did_you_mean(best.parameter, sorted(grids))}")]
    if best.value not in grids[best.parameter]:
        return [(("value",), f"{best.value!r} is not in the grid of {best.parameter}: "
                             f"{', '.join(map(_fmt_value, grids[best.parameter]))}")]
    return []


def _target_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    try:
        protocol.splitter(0).check_target()
    except SplitError as e:
        return [(("target",), str(e))]
    except Exception as e:
        return [(("scheme",), f"{type(e).__name__}: {e}")]
    return []


def _dataset_issues(protocol: Protocol) -> list[tuple[tuple, str]]:
    ref = protocol_dataset_ref(protocol)
    if protocol.dataset.format is not None:
        problem = format_ref_problem(ref.value, protocol.dataset.format)
        if problem is not None:
            return [(("dataset", "format" if protocol.dataset.format not in FORMATS else "name"), problem)]
        problems = FORMATS.get(protocol.dataset.format).option_problems(protocol.dataset.options)
        return [(("dataset", "options", k), why) for k, why in problems.items()]
    problem = dataset_ref_problem(ref)
    if problem is not None:
        return [(("dataset", "name"), problem)]
    return _dataset_option_issues(ref.value, protocol.dataset.options) if ref.kind == "registered" else []


def _dataset_option_issues(name: str, options: dict[str, Any]) -> list[tuple[tuple, str]]:
    """A registered dataset's options: names its loader takes (with the nearest), then its own
    check of their values (its entry's ``check_options`` tag: ``(option, why)`` or None)."""
    entry = DATASETS.entry(name)
    names, var_kw = _accepted_params(entry.obj)
    known = [n for n in names if n not in LOADER_PLACES]
    issues = [(("dataset", "options", k), f"unknown option {k!r} for dataset {name!r}{did_you_mean(k, known)} "
                                          f"(accepted: {', '.join(known) or 'none'})")
              for k in options if not var_kw and k not in known and k not in WRITE_LOCATIONS]
    check = entry.tags.get("check_options")
    if issues or check is None:
        return issues
    problem = check(options)
    return [] if problem is None else [(("dataset", "options", problem[0]), problem[1])]

def _evaluation_issues(proto: Protocol, subs: list[Protocol], *, clean_so_far: bool) -> list[tuple[tuple, str]]:
    """Each evaluation's scheme and dataset, and (while nothing else is wrong: ``clean_so_far``
    and its own are clean) its target; located in the evaluation that sets the field."""
    issues: list[tuple[tuple, str]] = []
    for i, sub in enumerate(subs):
        at = ("evaluations", i) if proto.evaluations else ()
        own = _scheme_issues(sub)
        own += _dataset_issues(sub)
        if not own and clean_so_far and not issues:
            own += _target_issues(sub)
        issues += [((at + loc) if at and loc[:1] and loc[0] in EVALUATION_FIELDS and _given(proto, i, loc[0])
                    else loc, msg) for loc, msg in own]
    return issues


def _given(proto: Protocol, i: int, key: str) -> bool:
    """Whether evaluation ``i`` sets ``key`` itself (else the protocol's is used)."""
    return getattr(proto.evaluations[i], key, None) is not None
