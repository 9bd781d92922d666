"""The protocol file: a YAML document validated by a pydantic schema.

A protocol names everything a benchmark run needs::

    name: haart-loso-msd-rf            # default: the file name without .yaml
    description: one line shown by `touchbench protocols list`
    dataset:                           # or just `dataset: haart`
      name: haart                      # registered name, scene:NAME, or a .parquet path
      filters: {gesture: [pat, rub]}   # keep only these values (any metadata column)
      exclude: {subject: [s03]}        # drop these values
      options: {}                      # keyword arguments of the loader / scene generator
    target: gesture                    # or subject (person identification, Flagg 2012), or any metadata column
    metrics: [f1_weighted]             # optional: scikit-learn scorer names, computed for every task
    scheme: {name: loso}               # or just `scheme: loso`; parameters beside name
    features:                          # a list of combinations; each is concatenated
      - [msd]
      - [sd, bmh]
      - [{name: smmhh, params: {...}}]
    classifiers:
      - gaus-rf
      - {name: gaus-rf, params: {n_estimators: 100}, label: rf100}
      - {name: cnn, params: {epochs: {grid: [10, 20]}}}   # a grid: one entry per value
    seed: 0                            # every randomness is derived from it
    repetitions: 1                     # the whole evaluation repeated with derived seeds (default: 1;
                                       # 5 seeds of every method where the scheme has a single test set)
    expected:                          # optional: the paper's numbers, in percent
      metric: accuracy
      tolerance: 3.0                   # percentage points
      results:
        - {features: [msd], classifier: gaus-rf, value: 54.82}
      standard_deviations:             # of the accuracy over the folds
        - {classifier: gaus-rf, value: 13, tolerance: 5, source: Table 2}
      confusions:                      # a confusion matrix as printed
        - classifier: gaus-rf
          source: Table 6
          tolerance: 10                # points of per-class recall
          rows: predicted              # the paper's rows: predicted (or true) class
          classes: [pat, rub]          # the order of its rows and columns
          matrix: [[30, 2], [6, 34]]
      best_parameters:                 # the best value of a parameter grid
        - {classifier: cnn, parameter: L, value: 30, source: Fig. 5}

**Repetitions.** Each repetition re-draws the scheme's folds (its seed) and
every method's seed (``engine.planning``). A scheme whose folds each test one
fixed set of captures (``Splitter.single_test_set``: ``challenge``,
``transfer``, ``cross-dataset``) has the same folds in every repetition, so
its repetitions are seeds of the methods alone; left unsaid, such an
evaluation runs :data:`touchbench.protocols.schemes.DEFAULT_SEEDS` (5) of
them, the protocol's or the evaluation's ``repetitions`` (``1`` for one)
deciding otherwise. The engine cannot tell a deterministic method (it cannot
see whether an estimator or a feature set draws from its seed), so every
method is repeated; a deterministic one shows a spread of 0 over its seeds.

**Parameter grids.** A feature or classifier parameter written
``{grid: [v1, v2, ...]}`` expands to one entry per value (the cartesian
product when several parameters have grids). Expanded entries are labelled
``name(param=value)``. A plain list is a list-valued parameter, never a grid.

**Errors.** The YAML is composed with node positions, so every error names
the file, the line and the field: ``protocols/x.yaml:12: classifiers[1].name:
unknown classifier 'gaus-fr'; did you mean 'gaus-rf'?``. The file is read
with bounds (:mod:`touchbench.core.yamlsafe`: size, aliases, expanded
values, depth; duplicate keys refused). Validation happens in passes: the
shape (pydantic; ``repetitions`` at most :data:`MAX_REPETITIONS`), the
number of entries the grids expand to (at most :data:`MAX_ENTRIES`, counted
before anything is expanded), then the scheme's own parameters (each
scheme has a pydantic ``Params`` model), feature and classifier parameter
names (against the constructors) and values (the feature sets' own checks;
classifiers are built with their parameters and asked scikit-learn's
parameter validation; a missing optional extra is refused with its install
command), and the ``expected`` references. Checks that need the data
(filter values, metadata columns) run in :mod:`touchbench.engine.runner`
before any work and report through :meth:`Protocol.error_at`.

Where: :class:`Protocol` here; its parts in :mod:`touchbench.protocols.entries`,
:mod:`touchbench.protocols.specs` and :mod:`touchbench.protocols.expected`; reading and the
passes in :mod:`touchbench.protocols.loading` and :mod:`touchbench.protocols.checks`; the errors
in :mod:`touchbench.protocols.errors`.
"""

from __future__ import annotations

import hashlib
import itertools
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field, PrivateAttr, field_validator, model_validator

from ..catalog import DatasetRef, parse_dataset_ref
from ..core.errors import TouchbenchError
from ..core.hashing import canonical_json
from ..core.suggest import did_you_mean
from ..methods import CAPTURES, METHODS, Method, features_label, resolve_entry
from .entries import (
    ClassifierEntry,
    ClassifierSpec,
    FeatureCombination,
    FeatureRef,
    MethodRef,
    _is_grid,
    _label,
    _Model,
    expand_grid,
)
from .errors import ProtocolError, UnknownEvaluation, _ErrorAt, _make_error
from .expected import Expected, ExpectedBest
from .seeding import derive_seed
from .schemes import DEFAULT_SEEDS, SPLITTERS, Splitter
from .schemes.base import scheme_class
from .specs import (EVALUATION_FIELDS, AuditSpec, DatasetSpec, DesignSpec, EvaluationSpec, ReportSpec, SchemeSpec,
                    _folder_name, _one_block_a_method)

__all__ = ["Protocol", "resolve_dataset_ref"]

METRICS = ("accuracy", "balanced_accuracy", "macro_f1")
#: bounds checked before anything is expanded: a protocol is a plan of work,
#: and a typo (an extra zero, a grid of a grid) must not plan years of it
MAX_REPETITIONS = 1000
MAX_ENTRIES = 10_000  # feature combinations x classifier entries + methods, grids expanded


class Protocol(_Model):
    """A validated protocol. Build with :func:`touchbench.protocols.loading.load_protocol` /
    :func:`touchbench.protocols.loading.parse_protocol`."""

    name: str
    description: str = ""
    dataset: DatasetSpec
    target: str = Field(default="gesture", min_length=1)
    scheme: SchemeSpec
    #: several (dataset, scheme) pairs for the same methods (each its own results folder)
    evaluations: list[EvaluationSpec] = Field(default_factory=list)
    #: the evaluation this protocol is (set on the protocols :meth:`evaluation_protocols` gives)
    evaluation: str = ""
    #: the data methods were designed on: one block, or a list of blocks each naming its methods
    design: DesignSpec | list[DesignSpec] | None = None
    #: the leaderboard's extra columns: recall of named classes, accuracy per metadata value
    report: ReportSpec | None = None
    #: the leakage audit of this protocol's methods (see :mod:`touchbench.engine.audit`)
    audit: AuditSpec | None = None
    features: list[list[FeatureRef]] | None = Field(default=None, min_length=1)
    classifiers: list[ClassifierSpec] | None = Field(default=None, min_length=1)
    methods: list[MethodRef] = Field(default_factory=list)
    seed: int = 0
    repetitions: int = Field(default=1, ge=1)
    expected: Expected | None = None
    #: scikit-learn scorer names computed for every task besides the three fixed metrics
    metrics: list[str] = Field(default_factory=list)

    _path: Path | None = PrivateAttr(default=None)
    _text: str = PrivateAttr(default="")
    _lines: dict[tuple, int] = PrivateAttr(default_factory=dict)
    _booleans: dict[tuple, str] = PrivateAttr(default_factory=dict)  # what YAML read as booleans, as written
    _subs: list["Protocol"] | None = PrivateAttr(default=None)
    _splitters: dict[tuple, Splitter] = PrivateAttr(default_factory=dict)  # see splitter()
    _scheme_models: dict[str, BaseModel] = PrivateAttr(default_factory=dict)  # see scheme_params()
    _scheme_json: tuple[SchemeSpec, str] | None = PrivateAttr(default=None)  # see scheme_json

    @field_validator("metrics")
    @classmethod
    def _known_scorers(cls, v: list[str]) -> list[str]:
        from sklearn.metrics import get_scorer_names

        names = sorted(get_scorer_names())
        for name in v:
            if name not in names:
                raise ValueError(f"unknown metric {name!r}{did_you_mean(name, names)}: a scikit-learn scorer name "
                                 f"(sklearn.metrics.get_scorer_names(), e.g. f1_weighted, matthews_corrcoef, "
                                 f"neg_log_loss)")
        if len(set(v)) != len(v):
            raise ValueError("a metric is named twice")
        return v

    @field_validator("target")
    @classmethod
    def _target_name(cls, v: str) -> str:
        if v != v.strip() or not v:
            raise ValueError(f"target {v!r}: the name of a metadata column of the dataset (gesture, subject, cover...)")
        return v

    @field_validator("repetitions")
    @classmethod
    def _few_repetitions(cls, v: int) -> int:
        if v > MAX_REPETITIONS:
            raise ValueError(f"{v} repetitions: at most {MAX_REPETITIONS} (each repeats the whole evaluation)")
        return v

    _name_ok = field_validator("name")(_folder_name)
    _design_ok = field_validator("design")(_one_block_a_method)

    @model_validator(mode="before")
    @classmethod
    def _shorthands(cls, d: Any) -> Any:
        if not isinstance(d, dict):
            return d
        d = dict(d)
        evs = d.get("evaluations")
        if isinstance(evs, list) and evs and isinstance(evs[0], dict):  # the first evaluation's by default
            for k in ("dataset", "scheme"):
                if k not in d and k in evs[0]:
                    d[k] = evs[0][k]
        if isinstance(d.get("dataset"), str):
            d["dataset"] = {"name": d["dataset"]}
        if isinstance(d.get("scheme"), str):
            d["scheme"] = {"name": d["scheme"]}
        feats = d.get("features")
        if isinstance(feats, list):
            out = []
            for combo in feats:
                if isinstance(combo, (str, dict)):
                    combo = [combo]
                if isinstance(combo, list):
                    combo = [{"name": f} if isinstance(f, str) else f for f in combo]
                out.append(combo)
            d["features"] = out
        clfs = d.get("classifiers")
        if isinstance(clfs, list):
            d["classifiers"] = [{"name": c} if isinstance(c, str) else c for c in clfs]
        return d

    @model_validator(mode="after")
    def _seeds_of_a_single_test_set(self) -> "Protocol":
        """Repetitions left unsaid: :data:`DEFAULT_SEEDS` for a scheme with a single test set (set in
        the instance's values, not as given: :meth:`evaluation_protocols` lets each evaluation's
        scheme decide)."""
        cls = scheme_class(self.scheme.name)
        if "repetitions" not in self.model_fields_set and cls is not None and cls.single_test_set:
            self.__dict__["repetitions"] = DEFAULT_SEEDS
        return self

    @model_validator(mode="after")
    def _methods_or_cross_product(self) -> "Protocol":
        if (self.features is None) != (self.classifiers is None):
            missing = "classifiers" if self.classifiers is None else "features"
            raise _ErrorAt((missing,), "features and classifiers go together (their cross product), "
                                       "or list methods: alone")
        if self.features is None and not self.methods:
            raise _ErrorAt(("methods",), "a protocol needs methods:, or features and classifiers")
        if self.features is None:
            self.features, self.classifiers = [], []
        return self

    # ----------------------------------------------------------- accessors
    @property
    def path(self) -> Path | None:
        return self._path

    @property
    def text(self) -> str:
        return self._text

    @property
    def text_hash(self) -> str:
        """SHA-256 of the protocol file's text."""
        return hashlib.sha256(self._text.encode()).hexdigest()

    def content(self) -> dict[str, Any]:
        """The validated protocol as plain data (what determines results)."""
        skip = {"description", "expected", "design", "report", "audit"}
        if not self.evaluations:
            skip.add("evaluations")
        if not self.evaluation:
            skip.add("evaluation")
        return self.model_dump(mode="json", exclude=skip)

    def evaluation_protocols(self) -> list["Protocol"]:
        """One protocol per evaluation (the methods, seed and metrics shared; the evaluation's
        dataset, scheme, target, repetitions and design), or ``[self]`` without evaluations."""
        if not self.evaluations:
            return [self]
        if self._subs is None:
            base = self.model_dump(mode="python", exclude={"evaluations", "evaluation"})
            if "repetitions" not in self.model_fields_set:  # each evaluation's scheme decides
                base.pop("repetitions")
            if not base.get("features"):  # methods: alone
                base.pop("features", None)
                base.pop("classifiers", None)
            subs = []
            for i, ev in enumerate(self.evaluations):
                data = dict(base, evaluation=ev.name)
                for k in EVALUATION_FIELDS:
                    v = getattr(ev, k)
                    if v is not None:
                        data[k] = v.model_dump(mode="python") if isinstance(v, BaseModel) else v
                sub = Protocol.model_validate(data)
                sub._path, sub._text = self._path, self._text
                at = ("evaluations", i)
                sub._lines, sub._booleans = ({**m, **{k[2:]: v for k, v in m.items()
                                                      if k[:2] == at and k[2:3] and k[2] in EVALUATION_FIELDS}}
                                             for m in (self._lines, self._booleans))
                subs.append(sub)
            self._subs = subs
        return self._subs

    def evaluations_named(self, names: "typing.Sequence[str]") -> list["Protocol"]:
        """The evaluations ``names`` (every one when empty), in the protocol's order; a name the
        protocol does not have is an :class:`UnknownEvaluation` naming the ones it has."""
        subs = self.evaluation_protocols()
        known = [s.evaluation for s in subs if s.evaluation]
        for name in names:
            if name not in known:
                where = f"(evaluations: {', '.join(known)})" if known else "(it has none: leave out --evaluation)"
                raise UnknownEvaluation(f"{name!r} is not an evaluation of protocol {self.name!r}"
                                        f"{did_you_mean(name, known)} {where}")
        return [s for s in subs if not names or s.evaluation in names]

    @property
    def content_hash(self) -> str:
        return hashlib.sha256(canonical_json(self.content()).encode()).hexdigest()

    def error_at(self, loc: tuple, message: str) -> ProtocolError:
        """A :class:`ProtocolError` at field ``loc`` (for checks that need the data)."""
        return _make_error(self._path, self._lines, [(loc, message)], self._booleans)

    def combinations(self) -> list[FeatureCombination]:
        """Feature combinations with parameter grids expanded."""
        out = []
        for combo in self.features:
            per_set = []
            for ref in combo:
                grid_keys = [k for k, v in ref.params.items() if _is_grid(v)]
                per_set.append([(ref.name, p, grid_keys) for p in expand_grid(ref.params)])
            for choice in itertools.product(*per_set):
                sets = [(n, p) for n, p, _ in choice]
                label = "+".join(_label(n, p, sorted(g)) if g else n for n, p, g in choice)
                out.append(FeatureCombination(label=label, sets=sets))
        # Entries that differ only in non-grid parameters get labels with all parameters.
        labels = [c.label for c in out]
        for c in out:
            if labels.count(c.label) > 1:
                c.label = "+".join(_label(n, p) for n, p in c.sets)
        return out

    def classifier_entries(self) -> list[ClassifierEntry]:
        """Classifier entries with parameter grids expanded."""
        out = []
        for spec in self.classifiers:
            grid_keys = sorted(k for k, v in spec.params.items() if _is_grid(v))
            for p in expand_grid(spec.params):
                base = spec.label or spec.name
                label = _label(base, p, grid_keys) if grid_keys else base
                out.append(ClassifierEntry(label=label, name=spec.name, params=p, tuned_on_test=(
                    f"{base} ({', '.join(grid_keys)} chosen on test)" if spec.tuned_on_test else ""),
                    stopped_on_test=spec.stopped_on_test))
        labels = [c.label for c in out]
        for c in out:
            if labels.count(c.label) > 1:
                c.label = _label(c.label, c.params)
        return out

    def _method_entries(self) -> list[tuple[int, FeatureCombination, ClassifierEntry]]:
        """The ``methods:`` entries (index, combination, classifier entry), grids expanded.

        A registered method, or an estimator on captures, stands beside the
        ``[raw-window]`` combination (the captures as recorded), exactly as
        ``features: [[raw-window]]`` with ``classifiers: [touch-et]`` reads;
        an inline pipeline has its own feature sets.
        """
        out = []
        for i, m in enumerate(self.methods):
            if m.name is not None:
                combo = FeatureCombination(label=CAPTURES, sets=[(CAPTURES, {})])
                name = m.name
            else:
                sets = [(f.name, f.params) for f in (m.features or [])]
                combo = FeatureCombination(label="+".join(_label(n, p) for n, p in sets), sets=sets)
                name = m.estimator or ""
            grid_keys = sorted(k for k, v in m.params.items() if _is_grid(v))
            base = (m.label or name) + ("+subject-id" if m.subject_id_feature else "")
            for p in expand_grid(m.params):
                out.append((i, combo, ClassifierEntry(label=_label(base, p, grid_keys) if grid_keys else base,
                                                      name=name, params=p, subject_id_feature=m.subject_id_feature,
                                                      tuned_on_test=f"{base} ({', '.join(grid_keys)} chosen on test)"
                                                      if m.tuned_on_test else "", stopped_on_test=m.stopped_on_test)))
        return out

    def _entry_pairs(self) -> list[tuple[FeatureCombination, ClassifierEntry, tuple]]:
        """Every (combination, classifier entry) pair as the protocol spells it, with its field (the
        classifier entry's own index): the ``features`` x ``classifiers`` cross product, then
        ``methods:`` (grids expanded)."""
        at = [i for i, spec in enumerate(self.classifiers) for _ in expand_grid(spec.params)]  # each entry's own
        out = [(c, k, ("classifiers", i)) for c in self.combinations() for k, i in zip(self.classifier_entries(), at)]
        return out + [(c, k, ("methods", i)) for i, c, k in self._method_entries()]

    def evaluated_methods(self) -> list[Method]:
        """Every method the protocol evaluates, each spelling read into a :class:`Method`."""
        return [self._method(c, k, loc) for c, k, loc in self._entry_pairs()]

    def _method(self, combo: FeatureCombination, clf: ClassifierEntry, loc: tuple) -> Method:
        """The method of one (combination, classifier entry) pair; a pairing that means nothing
        (a registered method beside feature sets of its own) is refused at ``loc``."""
        try:
            spec = resolve_entry(combo.sets, clf.name, clf.params)
        except TouchbenchError as e:
            raise self.error_at(loc, str(e)) from None
        frames = dict(combo.sets[0][1]).get("frames") if clf.name in METHODS else None
        return Method(label=clf.label, spec=spec, name=clf.name, params=dict(clf.params),
                      features_label=features_label(spec, combo.label), subject_id_feature=clf.subject_id_feature,
                      tuned_on_test=clf.tuned_on_test, stopped_on_test=clf.stopped_on_test,
                      input_frames=None if frames is None else int(frames))

    def features_label_of(self, names: list[str]) -> str:
        """The features label reports give the methods of the combination ``names`` (an
        ``expected`` reference names the combination as the protocol wrote it)."""
        key = "+".join(names)
        labels = {self._method(c, k, loc).features_label for c, k, loc in self._entry_pairs()
                  if c.names == list(names) or c.label == key}
        return labels.pop() if len(labels) == 1 else key

    def method_name_of(self, result) -> str:
        """The name reports give the method of an ``expected`` result (``features / classifier``)."""
        return f"{self.features_label_of(list(result.features))} / {result.classifier}"

    def best_label(self, best: ExpectedBest) -> str:
        """The label of the classifier entry that ``best`` (an entry of
        ``expected.best_parameters``) says is the best, e.g. ``cnn(L=30)``."""
        for c in self.classifier_entries():
            if c.name == best.classifier and c.params.get(best.parameter) == best.value:
                return c.label
        raise self.error_at(("expected", "best_parameters"), f"no {best.classifier} entry with "
                                                             f"{best.parameter} = {best.value!r}")

    @property
    def scheme_json(self) -> str:
        """The scheme and its parameters in canonical form (``{"name": ..., parameters}``): what keys
        the scheme, in task identities and seeds. Computed once per protocol (a copy with another
        scheme computes its own)."""
        if self._scheme_json is None or self._scheme_json[0] is not self.scheme:
            self._scheme_json = (self.scheme, canonical_json({"name": self.scheme.name, **self.scheme.params}))
        return self._scheme_json[1]

    def scheme_params(self) -> BaseModel:
        """The scheme's parameters validated by its ``Params`` model, once per protocol: the checks
        that read the protocol ask first (a ``ValidationError`` is reported at the fields), and the
        scheme is built from the validated model (:meth:`splitter`)."""
        key = self.scheme_json
        if key not in self._scheme_models:
            params = SPLITTERS.get(self.scheme.name).Params.model_validate(self.scheme.params)
            self._scheme_models[key] = params
        return self._scheme_models[key]

    def splitter(self, repetition: int = 0) -> Splitter:
        """The scheme, seeded for ``repetition``: built once per repetition (from
        :meth:`scheme_params`, not validated again) and shared by every layer that asks it something
        (the checks, the data preparation, the folds, the plan, the leakage label). A scheme's folds
        depend only on its settings, its seed and the data it is handed (its random draws are seeded
        at each use, its notes reset by each ``folds``), so sharing it changes no result. Keyed by
        what builds it, so a copy of the protocol with another scheme, target or seed builds its own."""
        seed = derive_seed(self.seed, "split", repetition)
        key = (self.scheme_json, self.target, seed)
        if key not in self._splitters:
            self._splitters[key] = SPLITTERS.get(self.scheme.name).from_params(
                self.scheme_params(), target=self.target, random_state=seed)
        return self._splitters[key]


def protocol_dataset_ref(protocol: Protocol) -> DatasetRef:
    """The protocol's dataset reference, relative paths taken from the protocol's folder."""
    return parse_dataset_ref(protocol.dataset.name, None if protocol.path is None else protocol.path.parent)


def resolve_dataset_ref(protocol: Protocol) -> str:
    """The dataset reference as a string, relative paths resolved against the protocol's folder."""
    return str(protocol_dataset_ref(protocol))
