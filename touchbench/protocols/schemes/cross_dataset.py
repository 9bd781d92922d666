"""The ``cross-dataset`` scheme: train on the protocol's dataset, test on another (adapted to the
training sensor when declared).
"""

from __future__ import annotations

from pathlib import PurePath
from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ...datasets.adapt import AdapterError, adapt
from ...datasets.model import TouchDataset, concat, frames_checksum
from .base import (SPLITTERS, DataContext, Fold, SchemeParams, SplitError, Splitter, named, natural_key,
                   require_columns, str_col)

#: the metadata column :meth:`CrossDataset.prepare` adds to the combined table (``train`` / ``test``)
ORIGIN = "origin"
#: the column holding each capture's frame checksum (:meth:`CrossDataset.prepare` adds it)
FRAMES_SHA = "frames_sha256"


class _CrossParams(SchemeParams):
    test: dict[str, Any]
    adapters: list[dict[str, Any]] = Field(default_factory=list)

    @model_validator(mode="before")
    @classmethod
    def _test_ref(cls, d: Any) -> Any:
        return named(d, "test")

    @model_validator(mode="after")
    def _check(self) -> "_CrossParams":
        if not isinstance(self.test.get("name"), str) or not self.test["name"]:
            raise ValueError("test must name the test dataset: test: {name: DATASET}")
        unknown = sorted(set(self.test) - {"name", "format", "filters", "exclude", "options"})
        if unknown:
            raise ValueError(f"test: unknown key(s) {unknown} (name, format, filters, exclude, options)")
        return self


@SPLITTERS.register(
    "cross-dataset",
    description="train on the protocol's dataset, test on another (same sensor, or declared adapters)",
    paper="",
)
class CrossDataset(Splitter):
    """One fold: train on every capture of the protocol's dataset (after its
    filters), test on every capture of ``test`` (a dataset reference with
    its own ``format``, ``filters``, ``exclude``, ``options``).

    :meth:`prepare` loads the test data, adapts it to the training sensor
    with the declared ``adapters`` (:mod:`touchbench.datasets.adapt`, each
    recorded in the run's notes), refuses a sensor mismatch left after them,
    and stacks both with an ``origin`` column (``train`` / ``test``) and
    each capture's frame checksum (of the frames as read). A test
    capture whose frames are those of a training capture is refused: the
    same recording read twice would be tested on what was trained on.
    """

    name = "cross-dataset"
    single_test_set = True
    Params = _CrossParams

    @classmethod
    def heading(cls, params: dict[str, Any], dataset: str) -> str | None:
        """``cross-dataset: trained on DATASET, tested on TEST``: the test dataset by its name, or a
        folder's or file's own name (never its path, options or filters)."""
        test = cls._test_name(params)
        return None if test is None else f"cross-dataset: trained on {dataset}, tested on {test}"

    @staticmethod
    def _test_name(params: dict[str, Any]) -> str | None:
        """The test dataset's name for a title, or a folder's or file's own name (never its path)."""
        test = named(params, "test").get("test")
        name = test.get("name") if isinstance(test, dict) else None
        if not isinstance(name, str) or not name.strip("/"):
            return None
        return PurePath(name.rstrip("/")).name or name

    def keeps_subjects_apart(self) -> bool:
        return True

    def apart_column(self) -> str | None:
        return ORIGIN

    def tests_each_capture_once(self) -> bool:
        return True

    def prepare(self, ds: TouchDataset, context: DataContext) -> TouchDataset:
        loc = ("scheme", "test")
        test = context.load(self.params.test, loc)
        test_sha = [frames_checksum(c) for c in test.captures]  # before adapting: the recordings as read
        try:
            test, steps = adapt(test, ds.sensor, list(self.params.adapters), "scheme.adapters")
        except AdapterError as e:
            raise context.error_at(("scheme", "adapters") if self.params.adapters else loc, str(e)) from None
        context.notes.extend(steps)
        name = self.params.test["name"]
        context.notes.append(f"trained on {len(ds)} captures of {context.dataset_name}, "
                             f"tested on {len(test)} of {name}")
        both = [_with_origin(ds, "train", [frames_checksum(c) for c in ds.captures], ds.name),
                _with_origin(test, "test", test_sha, ds.name)]
        if {c.dtype for c in both[0].captures} != {c.dtype for c in both[1].captures}:  # one dtype for the stack
            both = [TouchDataset(d.name, [np.asarray(c, dtype=np.float64) for c in d.captures], d.meta, d.sensor,
                                 provenance=d.provenance) for d in both]
        out = concat(both, f"{ds.name}->{name}")
        out.provenance = {"train": ds.provenance, "test": test.provenance}
        return out

    def _split(self, meta: pd.DataFrame) -> list[Fold]:
        train, test = self._sides(meta)
        name = "train->test"
        return [Fold(name, train, test, group=name)]

    def _sides(self, meta: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
        """The positions of the training and the test dataset's captures; a test capture whose frames
        are a training capture's is refused, and subject names in both datasets are noted."""
        require_columns(meta, self.name, ORIGIN, FRAMES_SHA)
        origin = str_col(meta, ORIGIN)
        train, test = np.flatnonzero(origin == "train"), np.flatnonzero(origin == "test")
        sha = str_col(meta, FRAMES_SHA)
        seen = set(sha[train].tolist())
        again = [i for i in test.tolist() if sha[i] in seen]
        if again:
            ids = meta["capture_id"].astype(str).to_numpy()[again]
            raise SplitError(f"scheme {self.name!r}: {len(again)} test capture(s) have the frames of a training "
                             f"capture ({', '.join(ids[:5].tolist())}{'...' if len(again) > 5 else ''}): the same "
                             f"recordings are in both datasets; filter them out of one")
        subj = str_col(meta, "subject")
        shared = sorted(set(subj[train]) & set(subj[test]), key=natural_key)
        if shared:
            self.notes_.append(f"subject name(s) {shared} are in both datasets (the same people, or a clash of names)")
        return train, test


def _with_origin(ds: TouchDataset, origin: str, checksums: list[str], name: str) -> TouchDataset:
    meta = ds.meta.copy()
    meta["capture_id"] = [f"{origin}:{c}" for c in meta["capture_id"].astype(str)]
    meta[ORIGIN] = origin
    meta[FRAMES_SHA] = checksums
    return TouchDataset(name, ds.captures, meta, ds.sensor, provenance=ds.provenance)
