"""Profiles of the paper reproduction: what each trades for time.

Profiles (:data:`PROFILES`) trade fidelity for time, and say so in the
report. A profile changes three things, nothing else:

- ``classifier_caps``: ``{classifier name: {parameter: maximum}}``. The
  value a protocol gives (or, when it gives none, the classifier's
  registered default) is replaced by ``min(value, maximum)``; in a grid each
  value is capped and repeats are dropped. E.g. ``gaus-rf`` at most 100
  trees instead of the paper's 1000.
- ``scheme_caps``: ``{scheme name: {parameter: maximum}}``, the same for the
  scheme's parameters (Flagg's 100-fold cross-validation becomes 10-fold).
- ``dataset_options``: ``{dataset reference: {option: value}}`` merged into
  the protocol's ``dataset.options`` (a smaller synthetic scene: fewer
  repetitions per person and gesture). Real data is never reduced, and
  neither profile reduces a scene: a scene smaller than the paper's data
  lowers every accuracy on it (measured: Zhou's KNN rows 4 to 8 points
  lower with 4 of the 16 repetitions).

and, for ``--audit``, ``audit_options``: keyword arguments of
:func:`touchbench.engine.audit.run_audit` (the quick profile's
``window_folds``: the window variant runs 2 of its 10 folds; the audit's
variants also get the classifier caps, being made from the profiled protocol).

A profile never changes features, feature parameters, classifiers'
other parameters, filters or seeds, and never touches the expected numbers:
a method is never adjusted to a number. The quick and full profiles write
to different results directories and their methods have different
parameter hashes, so they are never combined.
"""


from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..classifiers import CLASSIFIERS
from ..core.errors import TouchbenchError
from ..protocols.derive import derive, protocol_data
from ..protocols.library import PAPERS_DIR
from ..protocols.schema import Protocol

__all__ = ["PROFILES", "Profile", "apply_profile", "paper_protocols"]


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    classifier_caps: dict[str, dict[str, float]] = field(default_factory=dict)
    scheme_caps: dict[str, dict[str, int]] = field(default_factory=dict)
    dataset_options: dict[str, dict[str, Any]] = field(default_factory=dict)
    audit_options: dict[str, Any] = field(default_factory=dict)


PROFILES: dict[str, Profile] = {
    "full": Profile(
        "full",
        "the papers' settings: every classifier, scheme and dataset as the protocol files give them "
        "(1000-tree forests, 500 boosting iterations, 100-fold CV, full-size scenes, up to 100 CNN epochs)",
    ),
    "quick": Profile(
        "quick",
        "fewer trees and epochs and 10 folds instead of 100, so that every protocol runs on two cores in "
        "under 20 minutes; real HAART data and the synthetic scenes are used whole (the papers' numbers of "
        "people and repetitions); leave-one-subject-out keeps every subject's fold (ten on HAART); with --audit, "
        "the CNN's window variant (24,900 windows) runs the first 2 of its 10 folds, its other variants all "
        "their folds",
        classifier_caps={
            "gaus-rf": {"n_estimators": 100},
            "gaus-boost": {"n_trees": 100, "n_estimators": 10},
            "cnn": {"max_epochs": 15, "patience": 4},
            "flagg-mlp": {"max_epochs": 100},
            "flagg-rf": {"n_estimators": 10},
            "zhou-bagged-trees": {"n_estimators": 30},
            "xgboost": {"n_estimators": 100},
        },
        scheme_caps={"kfold": {"k": 10}, "within-subject": {"k": 10}},
        audit_options={"window_folds": 2},
    ),
}


def paper_protocols(directory: Path | None = None) -> list[Path]:
    d = Path(directory) if directory is not None else PAPERS_DIR
    files = sorted(d.glob("*.yaml"))
    if not files:
        raise TouchbenchError(f"no protocols in {d}")
    return files


def _cap(value: Any, cap: float) -> Any:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return value
    out = min(value, cap)
    return int(out) if isinstance(value, int) and float(out).is_integer() else out


def _cap_param(value: Any, cap: float) -> Any:
    if isinstance(value, dict) and set(value) == {"grid"}:
        vals = []
        for v in value["grid"]:
            c = _cap(v, cap)
            if c not in vals:
                vals.append(c)
        return {"grid": vals}
    return _cap(value, cap)


def apply_profile(original: Protocol, profile: Profile) -> tuple[Protocol, list[str]]:
    """``original`` under ``profile``'s overrides (a protocol made from the protocol,
    :func:`touchbench.protocols.derive.derive`), and the list of changes."""
    data = protocol_data(original)
    changes = (_cap_classifiers(data, profile) + _cap_scheme(data, profile) + _dataset_overrides(data, profile))
    if not changes:
        return original, []
    name = original.path.name if original.path is not None else original.name
    head = (f"# {name} under the '{profile.name}' profile of touchbench papers reproduce:\n"
            + "".join(f"#   {c}\n" for c in changes))
    return derive(original, data, head), changes


def _cap_classifiers(data: dict[str, Any], profile: Profile) -> list[str]:
    """Each classifier's parameters capped as the profile says (in ``data``); the changes."""
    changes = []
    for spec in data.get("classifiers") or []:
        caps = profile.classifier_caps.get(spec["name"], {})
        params = dict(spec.get("params") or {})
        defaults = CLASSIFIERS.entry(spec["name"]).tags.get("defaults") or {}
        for p, cap in caps.items():
            current = params.get(p, defaults.get(p))
            new = None if current is None else _cap_param(current, cap)
            if new is not None and new != current:
                params[p] = new
                changes.append(f"{spec.get('label') or spec['name']}: {p} {_show(current)} -> {_show(new)}")
        if params:
            spec["params"] = params
    return changes


def _cap_scheme(data: dict[str, Any], profile: Profile) -> list[str]:
    """The scheme's parameters capped as the profile says (in ``data``); the changes."""
    sch, changes = data["scheme"], []
    for p, cap in profile.scheme_caps.get(sch["name"], {}).items():
        if p in sch:
            new = _cap(sch[p], cap)
            if new != sch[p]:
                changes.append(f"scheme {sch['name']}: {p} {sch[p]} -> {new}")
                sch[p] = new
    return changes


def _dataset_overrides(data: dict[str, Any], profile: Profile) -> list[str]:
    """The dataset options the profile sets (in ``data``); the changes."""
    dspec = data["dataset"]
    opts = profile.dataset_options.get(dspec["name"])
    if not opts:
        return []
    dspec["options"] = {**(dspec.get("options") or {}), **opts}
    return [f"dataset {dspec['name']}: " + ", ".join(f"{k}={v}" for k, v in opts.items())]


def _show(v: Any) -> str:
    if isinstance(v, dict) and set(v) == {"grid"}:
        return "[" + ", ".join(map(str, v["grid"])) + "]"
    return str(v)
