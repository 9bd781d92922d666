"""The feature-set base class and registry.

A feature set is a scikit-learn transformer whose ``X`` is a sequence of
captures, each a ``(T, H, W)`` array (see :mod:`touchbench.datasets.model`).
``transform`` returns a 2-D float64 array with stable column names
(``get_feature_names_out``). ``fit`` learns only data-dependent parameters
(histogram edges, for example) and only from the training fold; a set whose
``fit`` learns nothing declares ``fold_dependent = False`` so the run engine
may compute its features once per capture and cache them.

``X`` may be a list of captures, one ``(N, T, H, W)`` array, or a
:class:`touchbench.datasets.model.TouchDataset` (then errors name the
capture by its ``capture_id``). Captures of a batch may differ in length
but must share the grid.

Subclasses implement either ``_transform_one(capture)`` (one capture ->
1-D row) or, to vectorise across captures, ``_transform_batch(stack)``
(``(N, T, H, W)`` stack of captures of the same length -> ``(N, n_out)``).
:meth:`FeatureSet.transform` groups captures by length, stacks each group
in chunks of bounded size (``_BATCH_VALUES`` values; ``_LOOP_BATCH_VALUES``
for a set whose compiled loops run, see ``compiled_loops``) and puts the rows
back in input order, so a capture's features never depend on its neighbours.
"""

from __future__ import annotations

import time
from typing import Any, Callable, ClassVar, Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin, clone

from ..core.constraints import declared_failures
from ..core.errors import TouchbenchError
from ..core.introspect import sensor_problem, with_accepted
from ..core.paramdoc import of_constraints
from ..core.registry import Registry
from ..core.compiled import kernels

# Filled by every module of touchbench.features (imported on first use of the registry).
FEATURES: Registry = Registry("feature set", package="touchbench.features",
                              tags_of=lambda cls: {"paper": cls.paper, "cost": cls.cost}, params_of=of_constraints)

# Upper bound on the values stacked at once by ``transform``: bounds peak
# memory whatever the dataset size, and keeps a chunk's float64 temporaries
# (1 MB each) in the CPU cache, which is faster than larger chunks.
_BATCH_VALUES = 131_072
# The bound for sets whose compiled loops run (``FeatureSet.compiled_loops``): the loops take one
# capture at a time, with no temporaries the size of a chunk, so larger chunks only save the fixed
# cost of a batch (its stack, constants and calls); still a bounded memory (16 MB as float64).
_LOOP_BATCH_VALUES = 2_097_152


class FeatureInputError(TouchbenchError, ValueError):
    """A capture a feature set cannot take (NaN, wrong shape, wrong grid...).

    A ``ValueError`` for scikit-learn users and a ``TouchbenchError`` for
    the command line, which prints it as one line.
    """


class SensorNeededError(FeatureInputError):
    """A set whose parameters leave a value to the sensor, built without one.

    Not a bad parameter: the run engine passes the dataset's sensor, so a
    protocol's parameter check (which has no sensor) skips this one and the
    plan asks again with the sensor.
    """


def _capture_names(captures: Any) -> tuple[Sequence[Any], list[str] | None]:
    """Unwrap a TouchDataset into (captures, capture ids); else ids are None."""
    caps = getattr(captures, "captures", None)
    meta = getattr(captures, "meta", None)
    if caps is not None and meta is not None and "capture_id" in getattr(meta, "columns", ()):
        return caps, [str(v) for v in meta["capture_id"].tolist()]
    return captures, None


def check_captures(captures: Any, *, name: str = "features") -> list[np.ndarray]:
    """Validate a batch of captures: 3-D, same grid, at least one frame, finite.

    NaN or infinite input is refused with the index of the offending capture
    (and its ``capture_id`` when ``captures`` is a TouchDataset). Accepts a
    single ``(N, T, H, W)`` array, a list of arrays or a TouchDataset.
    Raises :class:`FeatureInputError`.
    """
    captures, ids = _capture_names(captures)
    if isinstance(captures, np.ndarray) and captures.ndim == 4:
        captures = list(captures)
    elif isinstance(captures, np.ndarray):
        raise FeatureInputError(f"{name}: expected a list of (frames, H, W) captures or an (N, frames, H, W) array, got an array of shape {captures.shape}")
    out = []
    grid = None
    for i, c in enumerate(captures):
        label = f"capture {i}" + (f" ({ids[i]!r})" if ids is not None else "")
        a = np.asarray(c)
        if a.dtype.kind not in "biuf":
            raise FeatureInputError(f"{name}: {label} has non-numeric dtype {a.dtype}")
        if a.ndim != 3:
            raise FeatureInputError(f"{name}: {label} must be a (frames, H, W) array, got shape {a.shape}")
        if a.shape[0] < 1:
            raise FeatureInputError(f"{name}: {label} has no frames")
        if a.shape[1] < 1 or a.shape[2] < 1:
            raise FeatureInputError(f"{name}: {label} has an empty grid {a.shape[1:]}")
        if grid is None:
            grid = a.shape[1:]
        elif a.shape[1:] != grid:
            raise FeatureInputError(f"{name}: {label} has grid {a.shape[1:]}, capture 0 has {grid}")
        if a.dtype.kind == "f" and not np.isfinite(a).all():
            bad = np.argwhere(~np.isfinite(a))[0]
            raise FeatureInputError(
                f"{name}: {label} contains NaN or infinite values (first at frame {bad[0]}, row {bad[1]}, column {bad[2]})"
            )
        out.append(a)
    return out


class FeatureSet(TransformerMixin, BaseEstimator):
    """Base class: subclasses implement ``_transform_one`` or ``_transform_batch``.

    Class attributes (read by the registry listing and the run engine):
    ``paper`` (citation with section), ``cost`` (``cheap`` / ``moderate`` /
    ``expensive``), ``fold_dependent`` (``fit`` learns from data).
    """

    paper: ClassVar[str] = ""
    cost: ClassVar[str] = "cheap"
    fold_dependent: ClassVar[bool] = False
    #: each parameter's domain, declared once (scikit-learn's form: types, ``Interval``, ``StrOptions``,
    #: ``None``; a boolean is never a number): checked when a protocol is read and before any capture
    _parameter_constraints: ClassVar[dict] = {}
    #: each parameter's description, one or two sentences (the generated "Parameters" section reads
    #: it; a subclass's line replaces its base's)
    _parameter_docs: ClassVar[dict[str, str]] = {
        "sensor": "the dataset's sensor (:class:`touchbench.datasets.model.SensorSpec`); the run engine passes it."}
    #: the kernels module (:func:`touchbench.core.compiled.kernels`) whose loops take this set's
    #: captures one at a time; while they run, its chunks hold up to ``_LOOP_BATCH_VALUES`` values
    compiled_loops: ClassVar[str | None] = None

    def batch_values(self) -> int:
        """The most values :class:`FeatureStack` stacks at once for this set (a stack takes the
        least of its sets'): larger while the set's compiled loops run."""
        return _LOOP_BATCH_VALUES if self.compiled_loops and kernels(self.compiled_loops) is not None else _BATCH_VALUES

    def fit(self, captures, y=None):
        caps = check_captures(captures, name=type(self).__name__)
        self.grid_ = caps[0].shape[1:] if caps else None
        self.check_declared()
        self._check_params()
        self._fit(caps, y)
        self.n_features_out_ = self.n_features(self.grid_) if self.grid_ is not None else 0
        return self

    def check_declared(self) -> None:
        """Refuse a parameter outside its declared domain (``_parameter_constraints``), naming it."""
        owner = next((e.name for e in FEATURES.registered() if e.obj is type(self)), type(self).__name__)
        found = declared_failures(self._parameter_constraints, self.get_params(deep=False), owner)
        if found:
            raise FeatureInputError(next(iter(found.values())))

    def _check_params(self) -> None:
        """Check constructor parameters; raise ``FeatureInputError``. Nothing by default.

        Sets whose values depend on the sensor (frame rate, value range,
        presets) resolve them here, so a set built without the sensor it
        needs is refused by ``fit`` / ``transform`` with the reason.
        """

    def check_sensor(self, sensor: Any, min_frames: int | None = None) -> str | None:
        """Why this set, with its parameters, cannot serve ``sensor``; None when it can.

        ``min_frames`` is the shortest capture the set will see (None:
        unknown). The run engine asks at plan time, so ``protocols
        validate`` and ``run`` refuse a protocol before any task. Default:
        the parameter checks, with ``sensor`` as the set's sensor.
        """
        probe = self
        if "sensor" in self.get_params(deep=False) and getattr(self, "sensor", None) != sensor:
            probe = clone(self).set_params(sensor=sensor)
        try:
            probe.check_declared()
            probe._check_params()
        except FeatureInputError as e:
            return str(e)
        return None

    def _check_grid(self, grid: tuple[int, int]) -> None:
        """Refuse a grid these parameters cannot serve (before any output is allocated); nothing
        by default."""

    def _fit(self, captures: list[np.ndarray], y=None) -> None:
        """Learn data-dependent parameters; nothing by default."""

    def transform(self, captures) -> np.ndarray:
        return FeatureStack([self]).transform(captures)

    def _ready(self, grid: tuple[int, int], checked: bool) -> int:
        """Refuse captures of ``grid`` this fitted set cannot take (another grid than it was fitted
        on, a set that learns from data not fitted yet) and, unless ``checked``, parameters outside
        their domain; the output width for ``grid``."""
        fitted_grid = getattr(self, "grid_", None)
        if fitted_grid is not None and tuple(grid) != tuple(fitted_grid):
            raise FeatureInputError(f"{type(self).__name__}: fitted on grid {tuple(fitted_grid)}, got captures of grid {tuple(grid)}")
        if self.fold_dependent and fitted_grid is None:
            raise FeatureInputError(f"{type(self).__name__}: call fit before transform (this set learns from the training fold)")
        if not checked:
            self.check_declared()
            self._check_params()
        self._check_grid(tuple(grid))
        return self.n_features(grid)

    def _batch_rows(self, stack: np.ndarray, shared: "SharedPrep") -> np.ndarray:
        """:meth:`_transform_batch` of ``stack``; ``shared`` holds what sets of one
        :class:`FeatureStack` compute alike from the same stack (``shared.get``: the first set
        reading it computes it)."""
        return self._transform_batch(stack)

    def _refuse_non_finite(self, captures: Any, caps: list[np.ndarray], part: np.ndarray, rows: np.ndarray) -> None:
        """Features are finite or refused: name the capture, its largest value and the sensor's range.

        Every set is finite for values of a sensor's range (the extreme-value tests); values far
        beyond it (1e150 and up) overflow float64 in sums of squares and products.
        """
        k = int(np.flatnonzero(~np.isfinite(rows).all(axis=1))[0])
        i = int(part[k])
        _, ids = _capture_names(captures)
        label = f"capture {i}" + (f" ({ids[i]!r})" if ids is not None else "")
        big = float(np.max(np.abs(caps[i].astype(np.float64))))
        sensor = getattr(self, "sensor", None)
        rng = getattr(sensor, "value_range", None)
        where = (f"outside the sensor's range [{rng[0]:g}, {rng[1]:g}]" if rng is not None
                 and (caps[i].min() < rng[0] or caps[i].max() > rng[1]) else "too large for float64 statistics")
        raise FeatureInputError(f"{type(self).__name__}: {label} gives non-finite features: its values reach "
                                f"{big:.3g}, {where}; give the data in the sensor's units (or rescale it)")

    def _transform_batch(self, stack: np.ndarray) -> np.ndarray:
        """Features of ``stack`` (N, T, H, W), captures of equal length."""
        return np.vstack([np.asarray(self._transform_one(c), dtype=np.float64).reshape(1, -1) for c in stack])

    def _transform_one(self, capture: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def feature_names(self, grid: tuple[int, int]) -> list[str]:
        """Column names for a grid of shape ``grid``; length = output size."""
        raise NotImplementedError

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        return np.asarray(self.feature_names(self.grid_), dtype=object)

    def n_features(self, grid: tuple[int, int]) -> int:
        """Output size for ``grid`` (subclasses with long name lists compute it directly)."""
        return len(self.feature_names(grid))


def cell_names(grid: tuple[int, int]) -> list[str]:
    """``r{i}_c{j}`` for every cell of ``grid``, row-major (the order of ``reshape``)."""
    h, w = grid
    return [f"r{i}_c{j}" for i in range(h) for j in range(w)]


def learns_from_data(name: str) -> bool:
    """Whether the registered feature set ``name`` learns from its training captures (its class's
    ``fold_dependent``): one that does not may be computed once per capture and cached."""
    return bool(getattr(FEATURES.get(name), "fold_dependent", True))


class SharedPrep:
    """What the sets of one :class:`FeatureStack` batch compute alike from the same stack (the
    touch sets' pressure, the Zhou sets' frame descriptors): each value computed once, by the
    first set that asks, and the seconds it took charged to every set that reads it (``made``:
    seconds spent making values, ``read``: seconds of the values read, since :meth:`start`)."""

    def __init__(self) -> None:
        self._values: dict[Any, tuple[Any, float]] = {}
        self.made = 0.0
        self.read = 0.0

    def start(self) -> None:
        """Start the account of the next set."""
        self.made = self.read = 0.0

    def get(self, key: Any, make: Callable[[], Any]) -> Any:
        """The value under ``key``, made now by ``make()`` when no set made it before (it must
        not be written into by its readers)."""
        if key not in self._values:
            t0 = time.perf_counter()
            value = make()
            self._values[key] = (value, time.perf_counter() - t0)
            self.made += self._values[key][1]
        value, seconds = self._values[key]
        self.read += seconds
        return value


class FeatureStack:
    """Fitted feature sets applied together to batches of captures, their outputs side by side.

    The captures are checked once (:func:`check_captures`, named by the first set), grouped by
    length and stacked in chunks of at most the least of the sets' :meth:`FeatureSet.batch_values`
    values once for all the sets, and
    a preprocessing several sets share (``_batch_rows``' ``shared``, a :class:`SharedPrep`: the
    touch sets' pressure, the Zhou sets' frame descriptors) is computed once per chunk; a capture's
    rows never depend on its neighbours, nor on the other sets of the stack. What does not depend
    on the captures (each set's parameters, its grid checks and output width) is checked on the
    first batch of a grid and remembered, so a stack kept for many small batches (a live
    recogniser's windows) checks it once. One kept for a fitted method must see its sets'
    parameters unchanged (``set_params`` after fitting needs a new stack).
    """

    def __init__(self, sets: Sequence[Any]):
        self.sets = list(sets)
        self._widths: dict[tuple[int, ...], list[int]] = {}
        self._own = all(isinstance(fs, FeatureSet) for fs in self.sets)  # else: each set's own transform

    def widths(self, grid: tuple[int, ...]) -> list[int]:
        """Each set's output width for captures of ``grid``, checked the first time (``_ready``)."""
        if grid not in self._widths:
            checked = bool(self._widths)  # the parameters were checked with the first grid
            self._widths[grid] = [fs._ready(grid, checked) for fs in self.sets]
        return self._widths[grid]

    def transform(self, captures: Any, seconds: list[float] | None = None) -> np.ndarray:
        """The sets' rows of ``captures`` side by side; ``seconds`` (one per set) receives each
        set's compute time, a shared preprocessing counted in every set that reads it (each set
        costs what it would cost alone)."""
        if not self._own:  # a transformer of the captures written outside this module
            return np.hstack(self._each_own(captures, seconds))
        caps = check_captures(captures, name=type(self.sets[0]).__name__)
        if not caps:
            grids = [getattr(fs, "grid_", None) for fs in self.sets]
            return np.zeros((0, sum(fs.n_features(g) if g else 0 for fs, g in zip(self.sets, grids))))
        grid = tuple(caps[0].shape[1:])
        edges = np.cumsum([0] + self.widths(grid)).tolist()
        out = np.empty((len(caps), edges[-1]), dtype=np.float64)
        lengths = np.array([c.shape[0] for c in caps])
        cells, bound = grid[0] * grid[1], min(fs.batch_values() for fs in self.sets)
        for t in np.unique(lengths).tolist():
            idx = np.flatnonzero(lengths == t)
            step = max(1, bound // (t * cells))
            for k in range(0, len(idx), step):
                self._batch(captures, caps, idx[k:k + step], edges, out, seconds)
        return out

    def transform_each(self, captures: Any, seconds: list[float] | None = None) -> list[np.ndarray]:
        """:meth:`transform`'s matrix cut into each set's own (the rows each set gives alone)."""
        if not self._own:
            return self._each_own(captures, seconds)
        X = self.transform(captures, seconds)
        caps = captures if isinstance(captures, (list, tuple)) else check_captures(captures)
        if not len(caps):
            return [X[:, :0] for _ in self.sets]
        edges = np.cumsum([0] + self.widths(tuple(caps[0].shape[1:]))).tolist()
        return [X[:, a:b] for a, b in zip(edges[:-1], edges[1:])]

    def _each_own(self, captures: Any, seconds: list[float] | None) -> list[np.ndarray]:
        """Each set's own ``transform`` (sets written outside this module)."""
        parts = []
        for i, fs in enumerate(self.sets):
            t0 = time.perf_counter()
            parts.append(np.asarray(fs.transform(captures), dtype=np.float64))
            if seconds is not None:
                seconds[i] += time.perf_counter() - t0
        return parts

    def _batch(self, captures: Any, caps: list[np.ndarray], part: np.ndarray, edges: list[int], out: np.ndarray,
               seconds: list[float] | None) -> None:
        """Every set's rows of the captures ``part`` (of one length) into ``out``."""
        stack = np.stack([caps[i] for i in part])
        shared = SharedPrep()
        for j, (fs, a, b) in enumerate(zip(self.sets, edges[:-1], edges[1:])):
            shared.start()
            t0 = time.perf_counter()
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                rows = np.asarray(fs._batch_rows(stack, shared), dtype=np.float64)
            if seconds is not None:
                seconds[j] += time.perf_counter() - t0 - shared.made + shared.read
            if rows.shape != (len(part), b - a):
                raise AssertionError(f"{type(fs).__name__}: produced {rows.shape}, expected {(len(part), b - a)}")
            if not np.isfinite(rows).all():
                fs._refuse_non_finite(captures, caps, part, rows)
            out[part, a:b] = rows


def stack_features(sets: Sequence[Any], captures: Sequence[np.ndarray]) -> np.ndarray | list[np.ndarray]:
    """The fitted feature sets' outputs for ``captures``, concatenated as float64 (one
    :class:`FeatureStack`); the captures themselves when there are no sets (an estimator that takes
    captures)."""
    if not sets:
        return list(captures)
    return FeatureStack(sets).transform(captures)


def make_feature_set(name: str, params: dict[str, Any] | None = None, sensor: Any = None) -> FeatureSet:
    """Build the registered feature set ``name`` with ``params``, passing ``sensor`` (a
    :class:`touchbench.datasets.model.SensorSpec`) when its constructor takes it."""
    cls = FEATURES.get(name)
    return cls(**with_accepted(cls, params or {}, sensor=sensor))


def feature_set_refusal(name: str, params: dict[str, Any] | None, sensor: Any, min_frames: int | None = None) -> str | None:
    """Why the feature set ``name`` with ``params`` cannot serve ``sensor`` (captures from ``min_frames``
    frames), as ``"name: reason"`` with the name said once, or None."""
    problem = sensor_problem(make_feature_set(name, params, sensor), sensor, min_frames)
    if not problem:
        return None
    return problem if problem.startswith(f"{name}:") else f"{name}: {problem}"
