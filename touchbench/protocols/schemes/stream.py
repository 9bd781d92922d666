"""The ``stream`` scheme: any subject-level scheme, its test side replayed as continuous streams.

Live recognition as an evaluation: each fold trains on the base scheme's
training captures (or on windows cut from them) and replays its test
subjects' streams through the recogniser ``touchbench stream`` runs
(:class:`touchbench.streams.recognizer.WindowRecognizer`: the windows, the
hop, the decision rules), frame by frame; the engine scores every decision
against each frame's truth (frame, event and timing scores).

``source`` says what the streams are (:mod:`touchbench.streams.timeline`):
``spliced`` (the test subject's captures end to end in a seeded random
order, separated by ``gap_s`` seconds of its ``idle`` captures; the splice
points are artificial; a synthetic scene's are named ``scene``: a person's
gestures with pauses of rest between them), ``recorded`` (a user's
recordings labelled frame by frame). ``rules`` lists the decision rules to compare
(:mod:`touchbench.streams.rules`): one task per fold and method trains once
and replays every rule. Each rule is checked by its parameter model when
the protocol is read; a rule whose ``idle`` is not the scheme's, or one
listed twice, is refused. Caps: a window is at most :data:`MAX_WINDOW_S`
seconds, an idle stretch (``gap_s``) at most :data:`MAX_GAP_S` (a stretch is
cut from one idle capture, so it is at most that capture's length too).

``train_on`` says what the method is trained on: ``windows`` (of the
recogniser's lengths cut from the training captures, each labelled as its
capture), ``captures`` (whole), or ``streams`` (the training side made into
streams the same way as the test side, spliced with the same seeded recipe
or recorded, and cut into the windows the recogniser meets at every
``train_hop_s``, default the hop, each labelled with the truth of its last
frame: windows across onsets, transitions and real idle stretches).

``choose_rule: true`` chooses the rule inside each fold: the training
subjects (or sessions) are left out one at a time (``inner_folds`` groups
of them when given), the method is trained on the others and their streams
replayed with every rule; the rule with the best mean frame accuracy among
those averaging at most ``max_false_per_min`` false activations per idle
minute (else the fewest false activations) is the fold's choice, reported
as a row of its own (the test subjects are never looked at to choose).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
import pandas as pd
from pydantic import Field, Strict, ValidationInfo, field_validator, model_validator

from ...datasets.windows import no_frame, seconds_to_frames
from ...streams.replay import InnerFold, LiveSpec
from ...streams.rules import RuleError, RuleSpec, rule_spec
from ...streams.timeline import recorded_streams, spliced_streams
from ..errors import _ErrorAt
from .base import SPLITTERS, DataContext, Fold, SplitError, WrappingParams, WrappingSplitter, check_base, named

if TYPE_CHECKING:
    from ...datasets.model import TouchDataset

#: the metadata columns the scheme adds in ``prepare`` (its folds are made from the metadata alone):
#: each capture's number of frames and frame rate, and what a spliced stream of it is (``scene`` for a
#: synthetic scene's captures, else ``spliced``)
N_FRAMES = "stream_frames"
FRAME_RATE = "stream_frame_rate"
SOURCE = "stream_source"

#: the longest window (seconds) the scheme replays: a touch gesture lasts seconds, and a window is
#: held in memory for every hop of every stream
MAX_WINDOW_S = 60.0
#: the longest idle stretch (seconds) between two spliced captures: a stretch is cut from one idle
#: capture (at most its length) or, for a subject with none, made of the sensor's rest
MAX_GAP_S = 60.0

#: a number the scheme reads (seconds, or a rate): finite, a boolean or a string refused
_Finite = Annotated[float, Strict(), Field(allow_inf_nan=False)]


class _StreamParams(WrappingParams):
    source: Literal["spliced", "recorded"] = "spliced"
    idle: str = Field(min_length=1)
    gap_s: tuple[_Finite, _Finite] = (1.0, 3.0)
    per_stream: int | None = Field(default=None, ge=1)
    windows_s: list[Annotated[_Finite, Field(gt=0, le=MAX_WINDOW_S)]] = Field(default=[0.5, 1.0], min_length=1)
    hop_s: _Finite = Field(default=0.1, gt=0)
    train_on: Literal["windows", "captures", "streams"] = "windows"
    train_hop_s: _Finite | None = Field(default=None, gt=0)
    choose_rule: bool = False
    inner_folds: int | None = Field(default=None, ge=2)
    max_false_per_min: _Finite = Field(default=5.0, ge=0)
    rules: list[Any] = Field(default=[{"name": "max", "threshold": 0.5}], min_length=1, validate_default=True)
    none_label: str = "none"

    @model_validator(mode="before")
    @classmethod
    def _base(cls, d: Any) -> Any:
        d = named(d, "base")
        if isinstance(d, dict) and isinstance(d.get("rules"), list):
            d = {**d, "rules": [{"name": r} if isinstance(r, str) else r for r in d["rules"]]}
        return d

    @field_validator("rules", mode="before")
    @classmethod
    def _rules(cls, v: Any, info: ValidationInfo) -> Any:
        """Each rule validated by its parameter model into a :class:`RuleSpec`; the first rule in the
        wrong reported at its fields (every problem of it), as the protocol gives them. A rule whose
        idle class is not the scheme's, and a rule twice (the same name and parameters, defaults
        filled in), are refused."""
        if not isinstance(v, list):
            return v
        out: list[RuleSpec] = []
        for k, r in enumerate(v):
            try:
                out.append(rule_spec(r))
            except RuleError as e:
                (loc, msg), *more = e.issues
                raise _ErrorAt((k, *loc), msg, [((k, *at), m) for at, m in more]) from None
        idle = info.data.get("idle")  # absent when the scheme's own is in the wrong (reported there)
        seen: dict[tuple, int] = {}
        for k, spec in enumerate(out):
            own = getattr(spec.params, "idle", idle)
            if idle is not None and own != idle:
                raise _ErrorAt((k, "idle"), f"the rule's idle class {own!r} is not the scheme's ({idle!r})")
            key = (spec.rule, spec.params)  # every parameter, defaults filled in
            if key in seen:
                raise _ErrorAt((k,), f"the same rule as rules[{seen[key]}] ({spec.name}, the same parameters): "
                               "each rule is replayed once")
            seen[key] = k
        return out

    @model_validator(mode="after")
    def _check(self) -> "_StreamParams":
        lo, hi = self.gap_s
        if not 0 < lo <= hi:
            raise _ErrorAt(("gap_s",), "gap_s is [shortest, longest] idle stretch in seconds, 0 < shortest <= longest")
        if hi > MAX_GAP_S:
            raise _ErrorAt(("gap_s", 1), f"an idle stretch is at most {MAX_GAP_S:g} s (the scheme's cap), got {hi:g} s")
        check_base(self.base, "stream")
        if self.none_label == self.idle:
            raise ValueError("none_label must differ from the idle class")
        return self


@SPLITTERS.register(
    "stream",
    description="any subject-level scheme, its test subjects replayed as continuous streams (live recognition)",
    paper="Ward, Lukowicz & Gellersen 2011 (scoring); Flagg 2012, Sec. 4.5 (sliding windows)",
)
class Stream(WrappingSplitter):
    """Live recognition over the base scheme's folds (module docstring)."""

    name = "stream"
    Params = _StreamParams
    swept_params = ("rules",)  # each rule's scores are rows of their own in the stream table

    @classmethod
    def heading(cls, params: dict[str, Any], dataset: str) -> str | None:
        """``live, leave one subject out: windows 0.5 + 1 s, hop 0.1 s`` (the streams' source is in
        the stream table's title; the rules are its rows)."""
        base = named(params, "base").get("base")
        name = base.get("name") if isinstance(base, dict) else None
        windows, hop = params.get("windows_s", [0.5, 1.0]), params.get("hop_s", 0.1)
        if not isinstance(name, str) or not isinstance(windows, list):
            return None
        try:
            w = " + ".join(f"{float(x):g}" for x in windows)
            return f"live over {name}: windows {w} s, hop {float(hop):g} s"
        except (TypeError, ValueError):
            return None

    def check_target(self) -> None:
        self.base.check_target()
        if self.target != "gesture":
            raise SplitError("scheme 'stream' scores gestures over time: its target must be 'gesture'")

    def prepare(self, ds: "TouchDataset", context: DataContext) -> "TouchDataset":
        ds = super().prepare(ds, context)
        if self.params.idle not in set(ds.meta[self.target].astype(str)):
            raise SplitError(f"scheme 'stream': the idle class {self.params.idle!r} is not a {self.target} of the "
                             f"dataset ({', '.join(sorted(set(ds.meta[self.target].astype(str))))})")
        self._check_lengths(ds, context)
        spliced = "scene" if str(context.dataset_name).startswith("scene:") else "spliced"
        meta = ds.meta.assign(**{N_FRAMES: np.asarray(ds.n_frames, dtype=np.int64),
                                 FRAME_RATE: float(ds.sensor.frame_rate),
                                 SOURCE: self.params.source if self.params.source == "recorded" else spliced})
        context.notes.append(f"{meta[SOURCE].iloc[0]} streams of the test subjects, replayed with windows "
                             f"{', '.join(f'{w:g}' for w in sorted(self.params.windows_s))} s and hop {self.params.hop_s:g} s")
        return type(ds)(ds.name, ds.captures, meta, ds.sensor)

    def _check_lengths(self, ds: "TouchDataset", context: DataContext) -> None:
        """Refuse a window or hop of no frame at the data's rate, and an idle stretch longer than the
        shortest idle capture it could be cut from (it would be cut short without a word)."""
        p, rate = self.params, float(ds.sensor.frame_rate)
        lengths = [(("windows_s", i), w) for i, w in enumerate(p.windows_s)] + [(("hop_s",), p.hop_s)]
        lengths += [(("train_hop_s",), p.train_hop_s)] if p.train_hop_s is not None else []
        for at, seconds in lengths:
            problem = no_frame(seconds, rate)
            if problem:
                raise context.error_at(("scheme", *at), problem)
        idle = np.asarray(ds.n_frames, dtype=np.int64)[ds.meta[self.target].astype(str).to_numpy() == p.idle]
        if p.source != "recorded" and len(idle) and round(p.gap_s[1] * rate) > idle.min():
            raise context.error_at(("scheme", "gap_s", 1), (
                f"an idle stretch is cut from one {p.idle!r} capture, and the shortest is {idle.min() / rate:g} s "
                f"({idle.min()} frames at {rate:g} Hz): a stretch of {p.gap_s[1]:g} s would be cut short"))

    def _check_streams(self, streams: list, rate: float, fold: str) -> None:
        """Refuse a hop or shortest window not shorter than the shortest stream of ``fold`` (no
        decision or a single one on it)."""
        p, shortest = self.params, min(streams, key=lambda s: s.n_frames)
        first = min(range(len(p.windows_s)), key=p.windows_s.__getitem__)
        for at, seconds in ((("hop_s",), p.hop_s), (("windows_s", first), p.windows_s[first])):
            if seconds_to_frames(seconds, rate) >= shortest.n_frames:
                raise SplitError(f"{at[0]} {seconds:g} s is not shorter than the shortest stream of fold {fold!r} "
                                 f"({shortest.name}: {shortest.n_frames / rate:g} s)", field=at)

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        if N_FRAMES not in meta.columns or FRAME_RATE not in meta.columns:
            raise SplitError("scheme 'stream' builds streams from the captures: run it through a protocol")
        base_folds = self.base.folds(meta)
        self.notes_.extend(self.base.notes_)
        n_frames = meta[N_FRAMES].to_numpy(np.int64)
        out = []
        for f in base_folds:
            streams = self._streams(meta, n_frames, f)
            test = np.unique(np.concatenate([s.captures for s in streams]))
            self._check_streams(streams, float(meta[FRAME_RATE].iloc[0]), f.name)
            out.append(f.with_extra(self._live(streams, meta, n_frames, f), test=test))
        return out

    def _streams(self, meta: pd.DataFrame, n_frames: np.ndarray, fold: Fold) -> list:
        streams = self._streams_of(meta, n_frames, fold.test, fold.name)
        if not streams:
            raise SplitError(f"scheme 'stream': fold {fold.name!r} has no test subject to make a stream of")
        return streams

    def _streams_of(self, meta: pd.DataFrame, n_frames: np.ndarray, rows: np.ndarray, key: str) -> list:
        """The streams of ``rows``: recorded, or spliced with a generator seeded by ``key``."""
        p = self.params
        if p.source == "recorded":
            return recorded_streams(meta, n_frames, rows)
        rate = float(meta[FRAME_RATE].iloc[0])
        gap = (max(1, int(round(p.gap_s[0] * rate))), max(1, int(round(p.gap_s[1] * rate))))
        rng = np.random.default_rng([self.random_state, *key.encode()])
        source = str(meta[SOURCE].iloc[0]) if SOURCE in meta.columns else "spliced"
        return spliced_streams(meta, n_frames, rows, self.target, p.idle, gap, rng, source=source,
                               per_stream=p.per_stream)

    def _training_streams(self, meta: pd.DataFrame, n_frames: np.ndarray, rows: np.ndarray, key: str) -> tuple:
        """The training rows as streams, when the method trains on streams (else none)."""
        if self.params.train_on != "streams":
            return ()
        return tuple(self._streams_of(meta, n_frames, rows, f"train:{key}"))

    def _inner(self, meta: pd.DataFrame, n_frames: np.ndarray, fold: Fold) -> tuple[InnerFold, ...]:
        """The inner folds choosing the rule: the fold's training subjects left out one at a time, or
        in ``inner_folds`` groups (sorted subjects dealt in turn); none without ``choose_rule``."""
        p = self.params
        if not p.choose_rule:
            return ()
        train = np.asarray(fold.train, dtype=np.int64)
        subjects = meta["subject"].astype(str).to_numpy()[train]
        names = sorted(set(subjects))
        if len(names) < 2:
            raise SplitError(f"scheme 'stream': choose_rule needs two training subjects or more in fold "
                             f"{fold.name!r} (it has {len(names)})")
        k = len(names) if p.inner_folds is None else min(p.inner_folds, len(names))
        out = []
        for g in range(k):
            held = {n for j, n in enumerate(names) if j % k == g}
            test, rest = train[np.isin(subjects, list(held))], train[~np.isin(subjects, list(held))]
            key = f"{fold.name}/inner{g}"
            out.append(InnerFold(tuple(int(i) for i in rest), tuple(self._streams_of(meta, n_frames, test, key)),
                                 self._training_streams(meta, n_frames, rest, key)))
        return tuple(out)

    def training_spec(self, meta: pd.DataFrame, rows: np.ndarray, key: str) -> LiveSpec:
        """The settings to train a model on ``rows`` of the prepared metadata as a fold named ``key``
        trains (its training streams and, with ``choose_rule``, its inner folds; no test stream):
        ``touchbench train`` on a stream evaluation."""
        fold = Fold(key, np.asarray(rows, dtype=np.int64), np.zeros(0, dtype=np.int64))
        return self._live([], meta, meta[N_FRAMES].to_numpy(np.int64), fold)

    def _live(self, streams: list, meta: pd.DataFrame, n_frames: np.ndarray, fold: Fold) -> LiveSpec:
        p = self.params
        return LiveSpec(streams=tuple(streams), idle=p.idle, windows_s=tuple(sorted(p.windows_s)), hop_s=p.hop_s,
                        train_on=p.train_on, train_hop_s=p.train_hop_s,
                        rules=tuple(p.rules), none_label=p.none_label,
                        train_streams=self._training_streams(meta, n_frames, fold.train, fold.name),
                        inner=self._inner(meta, n_frames, fold), max_false_per_min=p.max_false_per_min)

