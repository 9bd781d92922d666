"""A trained model: fitted feature sets + fitted classifier + manifest, in one file.

:class:`TrainedModel` is what ``touchbench train`` writes and ``touchbench
predict`` / ``touchbench stream`` read. It holds

- the feature sets of the chosen combination, fitted on the training
  captures (or on windows cut from them, see :mod:`.windows`), built the way
  the run engine builds them (:func:`touchbench.features.base.make_feature_set`,
  with the dataset's sensor);
- the classifier, built by :func:`touchbench.classifiers.make_classifier`
  (with the dataset's sensor, as the run engine builds it)
  and fitted, as the engine does, on integer codes ``0..C-1`` of the sorted
  class names (XGBoost needs contiguous codes), with everything limited to
  one thread;
- the manifest: what the model was trained on (dataset name, reference and
  content hash of the training captures, the selection, and one checksum per
  training capture, :data:`CHECKSUM_CHARS` hexadecimal characters of
  :func:`touchbench.datasets.model.frames_checksum`, so that ``predict`` can
  tell captures the model was trained on), the training subjects, their
  recordings (subject and capture id) and, where the dataset has them, their
  sessions (so that ``predict`` tells the captures of people the model was
  trained on, whatever their frames), the sensor spec,
  the feature sets and classifier with their parameters and seed, the
  window lengths, the class names and the package versions.

The file (``MODEL_FORMAT``, ``MODEL_VERSION``), written atomically, is a
first line ``touchbench-model``, a second line of JSON (the format version,
the size of the fitted parts, one SHA-256 over the manifest (its canonical
JSON) and the fitted parts, and the manifest), then the fitted parts as
skops data (:mod:`.safe_format`: a zip of JSON and numpy arrays, read back
only as the types it trusts, by name; no pickle). The manifest is also
written beside it as ``<file>.json`` for reading without Python. Loading
checks, before anything is read, that the manifest and the fitted parts are
the ones touchbench wrote (checksum and size: a damaged, truncated or edited
file, manifest included, is refused); the checksum catches damage and edits,
the trusted types a file crafted to harm. Files of format versions 2 and 3
hold a joblib pickle, which runs code when read: they are read only when the
user trusts them (``trust=True``, ``--trust``), else refused saying why (a
version-2 file's checksum covered the pickle only: read with a note that its
manifest is not covered). Then loading checks that the parts agree with the
manifest: the class list as the fit encoded it (sorted, unique, one per
class the estimator knows) and the feature sets' sensor.

Sensor check: data is refused when its sensor differs from the model's in
grid, channels, frame rate, value range or polarity (the name alone may
differ: a user's reader names its sensor ``custom``).
"""

from __future__ import annotations

import hashlib
import io
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import joblib
import numpy as np

from ..classifiers.adapt import uses_unlabelled_test
from ..core.atomic import atomic_write_bytes
from ..core.errors import DataError, TouchbenchError
from ..core.hashing import canonical_json
from ..core.threads import single_thread
from ..core.versions import package_versions
from ..datasets.model import SensorSpec, TouchDataset, frames_checksum, sensor_differences
from ..classifiers.fitting import FittedEstimator, FittedMethod
from ..methods import MethodSpec
from ..methods.fitting import fit_method
from .safe_format import dump_parts, load_parts
from ..datasets.windows import seconds_to_frames
from ..streams.replay import window_samples

__all__ = [
    "CHECKSUM_CHARS",
    "MODEL_FORMAT",
    "MODEL_VERSION",
    "SensorMismatchError",
    "TrainedModel",
    "capture_checksum",
    "fit_model",
    "package_versions",
    "sensor_differences",
]

MODEL_FORMAT = "touchbench-model"
MODEL_VERSION = 4
# older files, whose fitted parts are a joblib pickle: read with trust only (2: the checksum covered the
# pickle only, noted when read)
_PICKLE_VERSIONS = (2, 3)
_MAGIC = (MODEL_FORMAT + "\n").encode()
_MAX_HEADER = 1 << 26  # bytes of the JSON line: a manifest (with one checksum per training capture), never more
#: hexadecimal characters kept of each training capture's checksum (64 bits)
CHECKSUM_CHARS = 16
_VERSIONED = ("numpy", "scipy", "scikit-learn", "joblib", "pandas", "PyWavelets", "xgboost", "xgboost-cpu", "torch")
# Fitted parts are only guaranteed to read back with the versions that wrote them; these matter most.
_CHECKED = ("scikit-learn", "numpy", "xgboost", "xgboost-cpu", "torch")


class SensorMismatchError(TouchbenchError):
    """Data from a sensor the model was not trained for."""


@dataclass
class TrainedModel:
    """A fitted method + its manifest (see the module docstring)."""

    fitted: FittedMethod
    manifest: dict[str, Any]
    #: what loading the file found worth saying (an older format...)
    file_notes: list[str] = field(default_factory=list, init=False, repr=False, compare=False)

    # ------------------------------------------------------------ accessors
    @property
    def feature_sets(self) -> list[Any]:
        """The fitted feature sets (none: the estimator takes the captures)."""
        return self.fitted.sets

    @property
    def estimator(self) -> Any | None:
        """The fitted estimator (None when the training data held one class)."""
        return self.fitted.estimator

    @property
    def classes(self) -> np.ndarray:
        return self.fitted.classes

    @property
    def sensor(self) -> SensorSpec:
        return SensorSpec.from_dict(self.manifest["sensor"])

    @property
    def windows(self) -> list[float] | None:
        """Training window lengths in seconds, or None (trained on whole captures)."""
        w = self.manifest.get("windows")
        return None if not w else [float(v) for v in w["lengths_s"]]

    @property
    def training_checksums(self) -> set[str] | None:
        """The checksums of the captures the model was trained on (None: the file does not record them)."""
        sums = self.manifest.get("dataset", {}).get("capture_checksums")
        return None if sums is None else set(sums)

    def seen_in_training(self, captures: Sequence[np.ndarray]) -> np.ndarray | None:
        """Per capture, whether the model was trained on it (same frames); None when the file does not say."""
        known = self.training_checksums
        if known is None:
            return None
        return np.array([capture_checksum(c) in known for c in captures], dtype=bool)

    def seen_people(self, meta: Any) -> dict[str, np.ndarray] | None:
        """Per row of ``meta``, whether the model was trained on its subject (``subject``), on its
        recording (``recording``: the same subject and capture id, whatever the frames) and, where both
        have sessions, on its session (``session``); None when the file does not record its subjects."""
        ds = self.manifest.get("dataset", {})
        if ds.get("subjects") is None:
            return None
        subjects = meta["subject"].astype(str).to_numpy()
        out = {"subject": np.isin(subjects, list(ds["subjects"])),
               "recording": np.isin([f"{s}/{c}" for s, c in zip(subjects, meta["capture_id"].astype(str))],
                                    list(ds.get("recordings", [])))}
        if ds.get("sessions") is not None and "session" in meta.columns:
            out["session"] = np.isin([f"{s}/{v}" for s, v in zip(subjects, meta["session"].astype(str))],
                                     list(ds["sessions"]))
        return out

    @property
    def adapts_to_session(self) -> bool:
        """Whether the model's classifier adapts to each new session from its unlabelled captures
        (:func:`touchbench.classifiers.adapt.uses_unlabelled_test`): ``predict`` adapts it to the
        captures it is given, ``stream`` refuses it."""
        name = (self.manifest.get("classifier") or {}).get("name")
        return self.estimator is not None and name is not None and uses_unlabelled_test(str(name))

    @property
    def method(self) -> str:
        return f"{self.manifest['features']['label']}/{self.manifest['classifier']['label']}"

    def check_sensor(self, sensor: SensorSpec, source: str = "data") -> None:
        """Refuse data from another sensor (:class:`SensorMismatchError`)."""
        diffs = sensor_differences(self.sensor, sensor)
        if diffs:
            raise SensorMismatchError(
                f"{source}: sensor {sensor.name!r} does not match the model's sensor {self.sensor.name!r} ("
                + "; ".join(diffs) + ")"
            )

    # ------------------------------------------------------------ inference
    def transform(self, captures: Sequence[np.ndarray]) -> np.ndarray | list[np.ndarray]:
        """The feature matrix of ``captures`` (the combination's sets, concatenated); the captures
        themselves for a method whose estimator takes captures (no feature sets)."""
        return self.fitted.transform(captures)

    def proba_from_features(self, X: np.ndarray, fast: bool = True) -> np.ndarray:
        """``(n, C)`` probabilities, columns in the order of :attr:`classes`.

        A classifier without ``predict_proba`` gives 1 for its predicted
        class. ``fast`` uses the flat-array forest walk for forests (same
        numbers as scikit-learn, see :mod:`.fastforest`).
        """
        return self.fitted.proba_rows(X, fast=fast)

    def predict_proba(self, captures: Sequence[np.ndarray], fast: bool = True) -> np.ndarray:
        return self.proba_from_features(self.transform(captures), fast=fast)

    def predict(self, captures: Sequence[np.ndarray]) -> np.ndarray:
        """Labels: the classifier's own ``predict`` (not the argmax of probabilities)."""
        return self.predict_from_features(self.transform(captures))

    def predict_from_features(self, X: np.ndarray) -> np.ndarray:
        if self.estimator is None:
            return np.array([self.classes[0]] * len(X), dtype=object)
        return self.classes[np.asarray(self.estimator.predict(X)).astype(np.int64)]

    # ------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write the model (its fitted parts as skops data) and ``<path>.json`` (the manifest), atomically."""

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        payload = {
            "feature_sets": self.feature_sets,
            "estimator": self.estimator,
            "classes": [str(c) for c in self.classes],
        }
        body = dump_parts(payload)
        manifest = json.loads(json.dumps(self.manifest, default=str))  # as the file holds it
        header = {"version": MODEL_VERSION, "sha256": _checksum(manifest, body), "size": len(body),
                  "manifest": manifest}
        line = json.dumps(header, sort_keys=True).encode() + b"\n"
        atomic_write_bytes(path, _MAGIC + line + body)
        text = json.dumps(self.manifest, indent=2, sort_keys=True, default=str) + "\n"
        atomic_write_bytes(manifest_path(path), text.encode())
        return path

    @classmethod
    def load(cls, path: str | Path, trust: bool = False) -> "TrainedModel":
        """Read a model written by :meth:`save`. ``trust``: the user trusts the file, so it may name
        types outside the trusted list, and an older file (a pickle, which runs code when read) is read."""

        path = Path(path)
        if not path.is_file():
            raise DataError("no such model file", path)
        header, body = _read_model_file(path)
        payload = _read_parts(header["version"], body, path, trust)
        if not isinstance(payload, dict) or not {"feature_sets", "estimator", "classes"} <= payload.keys():
            raise DataError("not a touchbench model (its parts are missing)", path)
        classes = np.array(payload["classes"], dtype=object)
        model = cls(FittedMethod(list(payload["feature_sets"]), FittedEstimator(classes, payload["estimator"])),
                    header["manifest"])
        problems = model.consistency_problems()
        if problems:
            raise DataError("the model's parts disagree (" + "; ".join(problems) + "); train it again", path)
        if header["version"] == _PICKLE_VERSIONS[0]:
            model.file_notes.append(f"{path}: an older model file, whose checksum does not cover its manifest "
                                    "(an edited manifest would go unnoticed); train it again to cover it")
        if header["version"] in _PICKLE_VERSIONS:
            model.file_notes.append(f"{path}: an older model file, a Python pickle read because of --trust; "
                                    "train it again for a file that holds data only")
        return model

    def consistency_problems(self) -> list[str]:
        """Why the fitted parts disagree with each other or with the manifest; empty when they agree.

        The fit encodes the labels as the positions of the sorted class names
        (:func:`touchbench.methods.fitting.encode_labels`), so the class list must
        be sorted and unique, equal the manifest's, and count the classes the
        estimator was fitted on; every feature set built for a sensor must have
        the model's.
        """
        out = []
        classes = [str(c) for c in self.classes]
        if classes != sorted(set(classes)):
            out.append("its class list is not the sorted list of distinct class names the fit encoded")
        if classes != [str(c) for c in self.manifest.get("classes", [])]:
            out.append("its class list differs from its manifest's")
        known = getattr(self.estimator, "classes_", None)
        if known is not None and len(known) != len(classes):
            out.append(f"the classifier knows {len(known)} classes, the class list names {len(classes)}")
        try:
            sensor = self.sensor
        except (KeyError, TypeError, ValueError):
            return [*out, "its manifest has no readable sensor"]
        for fs in self.feature_sets:
            fs_sensor = getattr(fs, "sensor", None)
            if isinstance(fs_sensor, SensorSpec) and sensor_differences(sensor, fs_sensor):
                out.append(f"feature set {type(fs).__name__} was built for another sensor "
                           f"({'; '.join(sensor_differences(sensor, fs_sensor))})")
        return out

    def version_notes(self) -> list[str]:
        """Packages whose installed version differs from the one the model was saved with."""
        saved = self.manifest.get("versions", {})
        now = package_versions(installed_only=True)
        return [*self.file_notes, *(
            f"model saved with {k} {saved[k]}, running {now.get(k, 'none')}"
            for k in _CHECKED if k in saved and saved[k] != now.get(k)
        )]

    def describe(self) -> str:
        m = self.manifest
        s = self.sensor
        ds = m["dataset"]
        w = self.windows
        lines = [
            f"method        {self.method}",
            f"classes       {', '.join(str(c) for c in self.classes)} (target: {m['target']})",
            f"trained on    {ds['name']} ({ds['selection']}): {ds['n_captures']} captures, "
            f"{ds['n_samples']} training samples, hash {ds['content_hash'][:16]}",
            f"sensor        {s.name}: {s.grid[0]} x {s.grid[1]} at {s.frame_rate:g} Hz, range {list(s.value_range)}",
            "windows       " + (self._windows_text() if w
                               else f"whole captures ({m['capture_frames']['median']:g} frames median)"),
            f"seed          {m['classifier']['random_state']}",
            "versions      " + ", ".join(f"{k} {v}" for k, v in m["versions"].items()),
        ]
        return "\n".join(lines)


    def _windows_text(self) -> str:
        """The training windows with each one's own hop: ``0.5 s (hop 0.2 s), 1 s (hop 0.5 s)``."""
        w = self.manifest["windows"]
        rate = self.sensor.frame_rate
        return ", ".join(f"{length:g} s (hop {hop / rate:g} s)"
                         for length, hop in zip(w["lengths_s"], w["train_hop_frames"]))


def _read_parts(version: int, body: bytes, path: Path, trust: bool) -> Any:
    """The fitted parts of a checked body: skops data (:mod:`.safe_format`), or an older file's pickle
    with ``trust`` only (a pickle runs code when read)."""
    if version == MODEL_VERSION:
        return load_parts(body, path, trust)
    if not trust:
        raise DataError(f"an older model file (format version {version}): its fitted parts are a Python pickle, "
                        "which can run any code when it is read, so touchbench does not read it; if you trust "
                        "who made the file, read it with --trust, or train the model again", path)
    try:
        return joblib.load(io.BytesIO(body))
    except Exception as e:  # noqa: BLE001 - a module missing here, a class changed since...
        raise DataError(f"not a readable touchbench model ({type(e).__name__}: {e})", path) from None


def _read_model_file(path: Path) -> tuple[dict[str, Any], bytes]:
    """The header and the fitted parts of a model file, the parts checked against the header's
    checksum before anything is read from them."""
    try:
        data = path.read_bytes()
    except OSError as e:
        raise DataError(f"cannot read ({e.strerror or e})", path) from None
    if not data.startswith(_MAGIC):
        raise DataError("not a touchbench model file, or one written by an older touchbench "
                        "(train one with `touchbench train`)", path)
    end = data.find(b"\n", len(_MAGIC), len(_MAGIC) + _MAX_HEADER)
    try:
        if end < 0:
            raise ValueError("no end of header")
        header = json.loads(data[len(_MAGIC):end])
        version, digest, size = header["version"], header["sha256"], header["size"]
        header["manifest"]["sensor"]  # noqa: B018 - must be there
    except (ValueError, KeyError, TypeError) as e:
        raise DataError(f"the model file's header is damaged ({type(e).__name__}); train it again", path) from None
    if version not in (MODEL_VERSION, *_PICKLE_VERSIONS):
        raise DataError(f"written by another touchbench model format (version {version}, this version reads "
                        f"{', '.join(map(str, _PICKLE_VERSIONS))} and {MODEL_VERSION}); train it again", path)
    body = data[end + 1:]
    if len(body) != size:
        raise DataError(f"the model file is {len(body) - size:+d} bytes off the size touchbench wrote "
                        "(truncated or edited); nothing was loaded", path)
    expected = hashlib.sha256(body).hexdigest() if version == _PICKLE_VERSIONS[0] else _checksum(header["manifest"], body)
    if expected != digest:
        raise DataError("the model file (manifest or fitted parts) does not match the checksum touchbench wrote "
                        "with it (damaged or edited); nothing was loaded", path)
    return header, body


def _checksum(manifest: dict[str, Any], body: bytes) -> str:
    """The SHA-256 a model file carries: the manifest's canonical JSON, a newline, the fitted parts."""
    return hashlib.sha256(canonical_json(manifest).encode() + b"\n" + body).hexdigest()


def capture_checksum(capture: np.ndarray) -> str:
    """The checksum a model file records per training capture (:data:`CHECKSUM_CHARS` characters of
    :func:`touchbench.datasets.model.frames_checksum`: the same recording from any reader matches)."""
    return frames_checksum(capture)[:CHECKSUM_CHARS]


def manifest_path(model_path: str | Path) -> Path:
    p = Path(model_path)
    return p.with_name(p.name + ".json")


def fit_model(
    dataset: TouchDataset,
    spec: MethodSpec,
    *,
    seed: int = 0,
    target: str = "gesture",
    windows: Sequence[float] | None = None,
    train_hop: float | None = None,
    features_label: str | None = None,
    label: str | None = None,
    selection: str = "all captures",
    source: dict[str, Any] | None = None,
    samples: tuple[Sequence[np.ndarray], np.ndarray, np.ndarray] | None = None,
) -> TrainedModel:
    """Fit the method ``spec`` on every capture of ``dataset``, or on ``samples`` (windows, their
    labels and groups) cut from it elsewhere (a stream evaluation's windows cut from its training
    streams: ``windows`` and ``train_hop`` then say their lengths and hop).

    ``windows`` (seconds): train on windows of these lengths cut from the
    captures every ``train_hop`` seconds (default: half of each window),
    labelled with their capture's ``target``; None trains on whole captures.
    ``features_label`` and ``label`` name the method as the results do.
    ``source`` is recorded in the manifest (protocol name and hash, dataset
    reference...).
    """
    if len(dataset) == 0:
        raise TouchbenchError(f"dataset {dataset.name!r}: no captures to train on")
    if target not in dataset.meta.columns:
        raise TouchbenchError(f"dataset {dataset.name!r} has no {target!r} column to train on")
    if samples is None:
        cut, src, lengths, hops = _training_samples(dataset, windows, train_hop)
        samples = (cut, dataset.meta[target].to_numpy()[src], dataset.meta["subject"].to_numpy()[src])
    else:
        rate = dataset.sensor.frame_rate
        lengths = [seconds_to_frames(w, rate, "--window") for w in windows or ()]
        hops = [seconds_to_frames(train_hop, rate, "--train-hop") if train_hop else max(1, L // 2) for L in lengths]
    with single_thread():  # the run engine's own fit path: label codes, subjects as groups, one class
        fitted = fit_method(spec, seed, samples[0], samples[1], samples[2], dataset.sensor)
    samples = samples[0]
    manifest = {
        "format": MODEL_FORMAT,
        "format_version": MODEL_VERSION,
        "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "dataset": _dataset_manifest(dataset, target, selection, len(samples), source),
        "sensor": dataset.sensor.to_dict(),
        "target": target,
        "features": {
            "label": features_label or "+".join(spec.feature_names),
            "sets": [{"name": n, "params": dict(p)} for n, p in spec.feature_sets],
            "n_columns": _n_columns(fitted),  # None: the estimator takes captures
        },
        "classifier": {
            "label": label or spec.name,
            "name": spec.estimator,
            "params": dict(spec.estimator_params),
            "random_state": int(seed),
        },
        "classes": [str(c) for c in fitted.classes],
        "windows": _windows_manifest(windows, lengths, hops, train_hop, dataset.sensor.frame_rate),
        "capture_frames": _frames_manifest(dataset),
        "capture_dtype": np.dtype(dataset.captures[0].dtype).str,
        "timings": {"features_s": round(fitted.feature_seconds, 3), "fit_s": round(fitted.fit_seconds, 3)},
        "versions": package_versions(installed_only=True),
    }
    return TrainedModel(fitted, manifest)


def _dataset_manifest(dataset: TouchDataset, target: str, selection: str, n_samples: int,
                      source: dict[str, Any] | None) -> dict[str, Any]:
    """What a model was trained on: the dataset, the selection, the counts per class."""
    y = np.array([str(v) for v in dataset.meta[target].tolist()], dtype=object)
    return {
        "name": dataset.name,
        "content_hash": dataset.content_hash,
        "selection": selection,
        "n_captures": int(len(dataset)),
        "n_samples": int(n_samples),
        "by_class": {str(k): int(v) for k, v in zip(*np.unique(y, return_counts=True))},
        "capture_checksums": [capture_checksum(c) for c in dataset.captures],
        **_people_manifest(dataset.meta),
        **(source or {}),
    }


def _people_manifest(meta: Any) -> dict[str, Any]:
    """Who and what the model was trained on, whatever the frames: the subjects, the recordings
    (``subject/capture_id``) and, where the dataset has a ``session`` column, the sessions
    (``subject/session``)."""
    subjects = meta["subject"].astype(str).to_numpy()
    out: dict[str, Any] = {
        "subjects": sorted(set(subjects.tolist())),
        "recordings": sorted({f"{s}/{c}" for s, c in zip(subjects, meta["capture_id"].astype(str))}),
    }
    if "session" in meta.columns:
        out["sessions"] = sorted({f"{s}/{v}" for s, v in zip(subjects, meta["session"].astype(str))})
    return out


def _frames_manifest(dataset: TouchDataset) -> dict[str, Any]:
    n = dataset.n_frames
    return {"min": int(n.min()), "median": float(np.median(n)), "max": int(n.max())}


def _n_columns(fitted: FittedMethod) -> int | None:
    """The number of feature columns, as the fitted sets say (None: the estimator takes the captures)."""
    return int(sum(fs.n_features_out_ for fs in fitted.sets)) if fitted.sets else None


def _training_samples(dataset: TouchDataset, windows: Sequence[float] | None,
                      train_hop: float | None) -> tuple[list[np.ndarray], np.ndarray, list[int], list[int]]:
    """The samples to train on and the capture each comes from: windows of each length (frames) cut
    every hop (frames; default half a window, :func:`touchbench.streams.replay.window_samples`), or the
    whole captures (no lengths, no hops)."""
    if not windows:
        return list(dataset.captures), np.arange(len(dataset)), [], []
    return window_samples(dataset.captures, windows, train_hop, dataset.sensor.frame_rate)


def _windows_manifest(windows: Sequence[float] | None, lengths: list[int], hops: list[int],
                      train_hop: float | None, frame_rate: float) -> dict[str, Any] | None:
    """The training windows a model file records (None: whole captures)."""
    if not windows:
        return None
    return {
        "lengths_s": [float(w) for w in windows],
        "lengths_frames": [int(v) for v in lengths],
        "train_hop_s": float(train_hop) if train_hop else float(min(hops) / frame_rate),
        "train_hop_frames": [int(v) for v in hops],
    }
