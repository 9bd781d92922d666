"""The ``learning-curve`` scheme: any scheme that keeps subjects apart, each of its folds trained
on n of the fold's training subjects, n swept, the n subjects drawn at random.

Each point of a fold (n subjects, one draw) trains on the captures of the drawn subjects only and
tests exactly the base fold's test captures, so the points of a fold are paired. The subjects
are drawn with a generator seeded from the scheme's ``random_state``, the fold, n and the draw
(never by their position in the table); the draws of one n are distinct subsets. The full point
(every training subject, draw 0) is always evaluated: each curve ends at the plain scheme's model.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
from pydantic import Field, field_validator, model_validator

from .base import (CURVE_SCHEMES, SPLITTERS, CurveParams, CurvePoint, Fold, SplitError, WrappingSplitter, check_base,
                   make_splitter, require_columns, sorted_values, str_col)

class _LearningCurveParams(CurveParams):
    subjects: list[int] | None = Field(default=None, min_length=1)
    fractions: list[float] | None = Field(default=None, min_length=1)
    stratify: str | None = Field(default=None, min_length=1)

    @field_validator("subjects")
    @classmethod
    def _subjects(cls, v: list[int] | None) -> list[int] | None:
        if v is not None and min(v) < 1:
            raise ValueError(f"every number of subjects must be at least 1 (got {min(v)})")
        return v

    @field_validator("fractions")
    @classmethod
    def _fractions(cls, v: list[float] | None) -> list[float] | None:
        bad = [f for f in v or [] if not (np.isfinite(f) and 0 < f <= 1)]
        if bad:
            raise ValueError(f"every fraction of the training subjects must be in (0, 1] (got {bad[0]:g})")
        return v

    @model_validator(mode="after")
    def _check(self) -> "_LearningCurveParams":
        if (self.subjects is None) == (self.fractions is None):
            raise ValueError("give exactly one of 'subjects' (numbers of training subjects) or 'fractions' "
                             "(fractions of them)")
        check_base(self.base, "learning-curve", CURVE_SCHEMES)
        params = {k: v for k, v in self.base.items() if k != "name"}
        try:
            base = make_splitter(self.base["name"], **params)
        except Exception:  # a base that cannot be built is reported at its own fields
            return self
        if not base.keeps_subjects_apart():
            raise ValueError(f"base: scheme {self.base['name']!r} with these parameters does not keep subjects "
                             "apart, so its folds have no training subjects of their own to draw from; use loso, "
                             "kfold with grouped: true, person-independent, transfer or challenge with subjects")
        return self


@SPLITTERS.register(
    "learning-curve",
    description="any subject-level scheme, each fold trained on n of its training subjects drawn at random, n swept",
    paper="",
)
class LearningCurve(WrappingSplitter):
    """Accuracy as a function of the number of training subjects (module docstring).

    ``subjects: [1, 2, 4]`` (numbers) or ``fractions: [0.25, 0.5]`` (of each fold's training
    subjects, rounded half up, at least 1) list the points; the full point is added. ``draws``
    distinct random subsets are drawn per point; where fewer distinct subsets exist, each is
    evaluated once (said in the fold's notes). ``stratify: COLUMN`` (a column with one value per
    subject) spreads the n subjects over the column's values as evenly as possible (which values
    get one more is drawn too).
    """

    name = "learning-curve"
    Params = _LearningCurveParams
    swept_params = ("subjects", "fractions", "draws")

    def tests_each_capture_once(self) -> bool:
        return False  # once per point of the curve

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        base_folds = self.base.folds(meta)
        self.notes_.extend(self.base.notes_)
        require_columns(meta, self.name, "subject")
        subj = meta["subject"].astype(str).to_numpy()
        strata = self._strata(meta, subj)
        out = [point for f in base_folds for point in self._points(f, subj, strata)]
        p = self.params
        sizes = (f"n = {', '.join(map(str, p.subjects))}" if p.subjects is not None
                 else f"fractions {', '.join(f'{x:g}' for x in p.fractions)}")
        self.notes_.append(f"learning curve: each fold trained on {sizes} and all of its training subjects, "
                           f"{p.draws} random draws of the subjects per point"
                           + (f", spread over the values of {p.stratify!r}" if p.stratify else "")
                           + "; every point tests the base fold's test captures")
        return out

    def _strata(self, meta: pd.DataFrame, subj: np.ndarray) -> dict[str, str] | None:
        """Each subject's value of the ``stratify`` column (None when not stratified)."""
        col = self.params.stratify
        if col is None:
            return None
        require_columns(meta, self.name, col)
        values = str_col(meta, col)
        out = {}
        for s in sorted_values(subj):
            own = set(values[subj == s].tolist())
            if None in own or len(own) != 1:
                raise SplitError(f"scheme 'learning-curve': stratify: {col!r} must give each subject one value; "
                                 f"subject {s!r} has {sorted(map(str, own))}")
            out[s] = own.pop()
        return out

    def _sizes(self, fold: Fold, n_train: int) -> list[tuple[float, int]]:
        """``(curve size, number of subjects)`` of each point of ``fold``, the full point last."""
        p = self.params
        if p.subjects is not None:
            over = [n for n in p.subjects if n > n_train]
            if over:
                raise SplitError(f"scheme 'learning-curve': subjects: {over[0]} is more than the {n_train} training "
                                 f"subjects of fold {fold.name!r}")
            return [(float(n), n) for n in sorted(set(p.subjects)) if n < n_train] + [(float(n_train), n_train)]
        return ([(f, max(1, int(math.floor(f * n_train + 0.5)))) for f in sorted(set(p.fractions)) if f < 1]
                + [(1.0, n_train)])

    def _points(self, fold: Fold, subj: np.ndarray, strata: dict[str, str] | None) -> list[Fold]:
        """The folds of every point of ``fold``'s curve."""
        subjects = sorted_values(subj[fold.train])
        shared = sorted(set(subjects) & set(subj[fold.test].tolist()))
        if shared:
            raise SplitError(f"scheme 'learning-curve': fold {fold.name!r} has subject(s) {shared} on both sides")
        prefix = "n" if self.params.subjects is not None else "f"
        out = []
        for size, n in self._sizes(fold, len(subjects)):
            subsets, note = self._subsets(fold.name, subjects, n, strata)
            for d, chosen in enumerate(subsets):
                train = fold.train[np.isin(subj[fold.train], chosen)]
                out.append(fold.with_extra(CurvePoint("subjects", size, d), name=f"{prefix}{size:g}#{d}/{fold.name}",
                                       train=train, notes=fold.notes + note))
        return out

    def _subsets(self, fold: str, subjects: list[str], n: int,
                 strata: dict[str, str] | None) -> tuple[list[list[str]], tuple[str, ...]]:
        """The subsets of ``n`` of ``subjects`` the draws of one point train on, and the fold note
        saying that fewer distinct subsets than draws exist (each is then drawn once)."""
        groups = ([subjects] if strata is None
                  else [[s for s in subjects if strata[s] == v] for v in sorted_values(strata[s] for s in subjects)])
        options = _quotas(n, [len(g) for g in groups])
        total = sum(math.prod(math.comb(len(g), q) for g, q in zip(groups, qs)) for qs in options)
        draws = self.params.draws
        if total <= draws:  # every distinct subset once, in a seeded order
            every = [sorted(itertools.chain(*parts)) for qs in options
                     for parts in itertools.product(*(itertools.combinations(g, q) for g, q in zip(groups, qs)))]
            order = self._rng(fold, n, "every").permutation(len(every))
            note = () if total == draws or n == len(subjects) else (
                f"{n} of {len(subjects)} training subjects: only {total} distinct subset(s)"
                + (" spread evenly over the strata" if strata is not None else "")
                + f", fewer than draws={draws}: each is drawn once",)
            return [every[i] for i in order], note
        seen: set[tuple[str, ...]] = set()
        out = []
        for d in range(draws):
            rng = self._rng(fold, n, d)
            while True:  # distinct from the earlier draws (more than `draws` subsets exist)
                qs = options[int(rng.integers(len(options)))]
                chosen = tuple(sorted(itertools.chain(*(rng.choice(g, size=q, replace=False).tolist()
                                                        for g, q in zip(groups, qs)))))
                if chosen not in seen:
                    break
            seen.add(chosen)
            out.append(list(chosen))
        return out, ()


def _quotas(n: int, sizes: list[int]) -> list[tuple[int, ...]]:
    """Every way to spread ``n`` subjects over groups of ``sizes`` as evenly as possible: each group
    gets ``level`` (or all it has when fewer), and ``n`` minus those go one each to some of the groups
    that have more than ``level`` (which ones is the choice)."""
    level = 0
    while sum(min(s, level + 1) for s in sizes) <= n and level < max(sizes):
        level += 1
    base = [min(s, level) for s in sizes]
    more = [i for i, s in enumerate(sizes) if s > level]
    extra = n - sum(base)
    out = []
    for chosen in itertools.combinations(more, extra):
        out.append(tuple(b + (i in chosen) for i, b in enumerate(base)))
    return out
