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
and replays every rule.
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pandas as pd
from pydantic import Field, field_validator, model_validator

from ...core.errors import TouchbenchError
from ...core.hashing import canonical_json
from ...streams.replay import LiveSpec
from ...streams.rules import make_rule
from ...streams.timeline import recorded_streams, spliced_streams
from .base import SPLITTERS, DataContext, Fold, SplitError, WrappingParams, WrappingSplitter, check_base, named

if TYPE_CHECKING:
    from ...datasets.model import TouchDataset

#: the metadata columns the scheme adds in ``prepare`` (its folds are made from the metadata alone):
#: each capture's number of frames and frame rate, and what a spliced stream of it is (``scene`` for a
#: synthetic scene's captures, else ``spliced``)
N_FRAMES = "stream_frames"
FRAME_RATE = "stream_frame_rate"
SOURCE = "stream_source"


class _StreamParams(WrappingParams):
    source: Literal["spliced", "recorded"] = "spliced"
    idle: str = Field(min_length=1)
    gap_s: tuple[float, float] = (1.0, 3.0)
    per_stream: int | None = Field(default=None, ge=1)
    windows_s: list[float] = Field(default=[0.5, 1.0], min_length=1)
    hop_s: float = Field(default=0.1, gt=0)
    train_on: Literal["windows", "captures"] = "windows"
    train_hop_s: float | None = Field(default=None, gt=0)
    rules: list[dict[str, Any]] = Field(default=[{"name": "max", "threshold": 0.5}], min_length=1)
    none_label: str = "none"

    @model_validator(mode="before")
    @classmethod
    def _base(cls, d: Any) -> Any:
        d = named(d, "base")
        if isinstance(d, dict) and isinstance(d.get("rules"), list):
            d = {**d, "rules": [{"name": r} if isinstance(r, str) else r for r in d["rules"]]}
        return d

    @field_validator("windows_s")
    @classmethod
    def _windows(cls, v: list[float]) -> list[float]:
        if any(not np.isfinite(w) or w <= 0 for w in v):
            raise ValueError("window lengths must be positive numbers of seconds")
        return sorted(v)

    @field_validator("rules")
    @classmethod
    def _rules(cls, v: list[dict[str, Any]]) -> list[dict[str, Any]]:
        for k, r in enumerate(v):
            try:
                make_rule(r)
            except TouchbenchError as e:
                raise ValueError(f"rules[{k}]: {e}") from None
        return v

    @model_validator(mode="after")
    def _check(self) -> "_StreamParams":
        lo, hi = self.gap_s
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo <= hi):
            raise ValueError("gap_s is [shortest, longest] idle stretch in seconds, 0 < shortest <= longest")
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
        spliced = "scene" if str(context.dataset_name).startswith("scene:") else "spliced"
        meta = ds.meta.assign(**{N_FRAMES: np.asarray(ds.n_frames, dtype=np.int64),
                                 FRAME_RATE: float(ds.sensor.frame_rate),
                                 SOURCE: self.params.source if self.params.source == "recorded" else spliced})
        context.notes.append(f"{meta[SOURCE].iloc[0]} streams of the test subjects, replayed with windows "
                             f"{', '.join(f'{w:g}' for w in self.params.windows_s)} s and hop {self.params.hop_s:g} s")
        return type(ds)(ds.name, ds.captures, meta, ds.sensor)

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
            out.append(replace(f, test=test, live=self._live(streams)))
        return out

    def _streams(self, meta: pd.DataFrame, n_frames: np.ndarray, fold: Fold) -> list:
        p = self.params
        if p.source == "recorded":
            return recorded_streams(meta, n_frames, fold.test)
        rate = float(meta[FRAME_RATE].iloc[0])
        gap = (max(1, int(round(p.gap_s[0] * rate))), max(1, int(round(p.gap_s[1] * rate))))
        rng = np.random.default_rng([self.random_state, *fold.name.encode()])
        source = str(meta[SOURCE].iloc[0]) if SOURCE in meta.columns else "spliced"
        streams = spliced_streams(meta, n_frames, fold.test, self.target, p.idle, gap, rng, source=source,
                                  per_stream=p.per_stream)
        if not streams:
            raise SplitError(f"scheme 'stream': fold {fold.name!r} has no test subject to make a stream of")
        return streams

    def _live(self, streams: list) -> LiveSpec:
        p = self.params
        return LiveSpec(streams=tuple(streams), idle=p.idle, windows_s=tuple(p.windows_s), hop_s=p.hop_s,
                        train_on=p.train_on, train_hop_s=p.train_hop_s,
                        rules=tuple(canonical_json(r) for r in p.rules), none_label=p.none_label)


def rule_specs(live: LiveSpec) -> list[dict[str, Any]]:
    """The live spec's rules as declared."""
    return [json.loads(r) for r in live.rules]
