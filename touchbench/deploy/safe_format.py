"""The fitted parts of a model file as data: skops, with a fixed list of trusted types.

A model file's fitted parts (feature sets, estimator, class names) are
written with ``skops.io``: a zip of JSON and numpy arrays that names the type
of every object. Reading rebuilds objects only of the types skops trusts by
default (scikit-learn's estimators, numpy, scipy, Python's containers) and of
:data:`TRUSTED_TYPES`, the types touchbench's methods are made of, listed by
name; a file naming any other type is refused before anything is built
(:func:`load_parts`), naming the file and the types, unless the user trusts the
file (``--trust``); then the types it builds beyond the list are named in a
warning (logger ``touchbench.deploy``) before anything is built.

Why these types are safe to rebuild: skops makes an object of a listed class
without calling its constructor, then gives it its saved attributes
(``__setstate__``). For the listed classes that only sets attributes, or
builds from numbers and arrays: a network of our own from its weights
(:mod:`touchbench.classifiers.torch_state`), an XGBoost booster from
XGBoost's own JSON (:class:`touchbench.classifiers.xgb.XGBoostClassifier`),
a torch module of aeon's from its attributes. No listed type runs code named
by the file.

One more check: scikit-learn's decision trees (``sklearn.tree._tree.Tree``)
are walked by compiled code that trusts their node arrays, so a crafted tree
could read outside its memory. Every loaded tree is checked
(:func:`check_trees`): children after their parent and inside the tree,
split features inside the columns its estimator takes, one value row per
node. Torch tensors are never in the file: the estimators that hold them save
numpy arrays instead.
"""

from __future__ import annotations

import logging
from typing import Any, Iterator
from zipfile import ZIP_DEFLATED

import numpy as np

from ..core.errors import DataError

log = logging.getLogger("touchbench.deploy")

__all__ = ["TRUSTED_TYPES", "check_trees", "dump_parts", "load_parts", "untrusted_types"]

#: the types of touchbench's fitted methods that skops does not trust by default, by module path
TRUSTED_TYPES: tuple[str, ...] = (
    # scikit-learn: a tree's nodes (checked after loading: check_trees); a splitter kept by a fitted search
    "sklearn.tree._tree.Tree",
    "sklearn.model_selection._split.GroupKFold",
    # touchbench: the sensor, the fitted method's containers and helpers
    "touchbench.datasets.model.SensorSpec",
    "touchbench.classifiers.fitting.FittedEstimator",
    "touchbench.classifiers.fitting.FittedMethod",
    "touchbench.classifiers.torch_state.ModuleState",
    "touchbench.classifiers.torch_state.TensorArray",
    "touchbench.classifiers.zhou.squared_inverse_weights",
    # touchbench: classifiers
    "touchbench.classifiers._util.SampleStandardScaler",
    "touchbench.classifiers._util.WekaRandomForestClassifier",
    "touchbench.classifiers.adapt.SessionCentred",
    "touchbench.classifiers.augment.ShiftAugmented",
    "touchbench.classifiers.bayesnet.K2BayesNetClassifier",
    "touchbench.classifiers.boosting.GausBoostingClassifier",
    "touchbench.classifiers.boosting.ResampledBoostingClassifier",
    "touchbench.classifiers.cnn.HaartCNNClassifier",
    "touchbench.classifiers.flagg.WekaLogisticRegression",
    "touchbench.classifiers.fusion.Fusion",
    "touchbench.classifiers.inception.InceptionTimeClassifier",
    "touchbench.classifiers.jung.StandardizedSVC",
    "touchbench.classifiers.mlp.WekaMLPClassifier",
    "touchbench.classifiers.peers.MiniRocketPeer",
    "touchbench.classifiers.peers.MultiRocketHydraPeer",
    "touchbench.classifiers.peers.MultiRocketPeer",
    "touchbench.classifiers.peers.QuantPeer",
    "touchbench.classifiers.peers.RDSTPeer",
    "touchbench.classifiers.quiet.QuietGated",
    "touchbench.classifiers.search.NestedSelection",
    "touchbench.classifiers.touch.NestedTunedExtraTrees",
    "touchbench.classifiers.touch.SelectedExtraTrees",
    "touchbench.classifiers.two_stage.TwoStage",
    "touchbench.classifiers.xgb.XGBoostClassifier",
    "touchbench.classifiers.zhou.MatlabKNNClassifier",
    "touchbench.classifiers.zhou.MatlabSVMClassifier",
    # touchbench: feature sets
    "touchbench.features.contact.ContactEvidence",
    "touchbench.features.live_summary.LiveSummary",
    "touchbench.features.flagg.FlaggStats",
    "touchbench.features.gaus_bmh.BinaryMotionHistory",
    "touchbench.features.gaus_lbptop.LBPTOP",
    "touchbench.features.gaus_msd.MotionStatisticalDistribution",
    "touchbench.features.gaus_sd.StatisticalDistribution",
    "touchbench.features.gaus_smmhh.SpatialMultiScaleMHH",
    "touchbench.features.raw.RawWindow",
    "touchbench.features.touch.CellRhythm",
    "touchbench.features.touch.ContactMotion",
    "touchbench.features.touch.TouchRhythm",
    "touchbench.features.touch_windows.TouchWindows",
    "touchbench.features.zhou.ZhouBasic",
    "touchbench.features.zhou.ZhouWavelet",
    # aeon's models inside the peers (no __setstate__ of their own; Hydra's torch module via ModuleState)
    "aeon.classification.convolution_based._hydra._SparseScaler",
    "aeon.classification.convolution_based._mr_hydra.MultiRocketHydraClassifier",
    "aeon.classification.interval_based._quant.QUANTClassifier",
    "aeon.transformations.collection.convolution_based._hydra.HydraTransformer",
    "aeon.transformations.collection.convolution_based._hydra._HydraInternal",
    "aeon.transformations.collection.interval_based._quant.QUANTTransformer",
    "aeon.classification.convolution_based._minirocket.MiniRocketClassifier",
    "aeon.classification.convolution_based._multirocket.MultiRocketClassifier",
    "aeon.classification.shapelet_based._rdst.RDSTClassifier",
    "aeon.transformations.collection.convolution_based._minirocket.MiniRocket",
    "aeon.transformations.collection.convolution_based._multirocket.MultiRocket",
    "aeon.transformations.collection.shapelet_based._dilated_shapelet_transform.RandomDilatedShapeletTransform",
)


def dump_parts(payload: Any) -> bytes:
    """The skops bytes of the fitted parts."""
    from skops.io import dumps

    return dumps(payload, compression=ZIP_DEFLATED)


def untrusted_types(body: bytes) -> list[str]:
    """The types the skops bytes name that neither skops nor :data:`TRUSTED_TYPES` trusts."""
    from skops.io import get_untrusted_types

    return sorted(set(get_untrusted_types(data=body)) - set(TRUSTED_TYPES))


def load_parts(body: bytes, path: Any, trust: bool = False) -> Any:
    """The fitted parts of skops bytes, built only from trusted types (every type with ``trust``),
    their decision trees checked (:func:`check_trees`); a DataError naming the file otherwise."""
    from skops.io import loads

    try:
        unknown = untrusted_types(body)
    except Exception as e:  # noqa: BLE001 - not a skops file: a damaged zip, a schema skops does not know
        raise DataError(f"the model's fitted parts are not readable ({type(e).__name__}: {e})", path) from None
    if unknown and not trust:
        raise DataError(f"the model file names {len(unknown)} type(s) outside touchbench's trusted list: "
                        f"{', '.join(unknown)}; nothing was built. Building them can run their code: only if you "
                        "trust who made the file, read it with --trust (`touchbench predict MODEL DATA --trust`, "
                        "`TrainedModel.load(path, trust=True)`)", path)
    if unknown:
        log.warning("%s: --trust: building %d type(s) outside touchbench's trusted list: %s",
                    path, len(unknown), ", ".join(unknown))
    try:
        payload = loads(body, trusted=[*TRUSTED_TYPES, *unknown])
    except Exception as e:  # noqa: BLE001 - a module missing here, a class changed since...
        raise DataError(f"not a readable touchbench model ({type(e).__name__}: {e})", path) from None
    problems = check_trees(payload)
    if problems:
        raise DataError("the model file holds a damaged decision tree (" + "; ".join(problems[:3]) + "); "
                        "nothing was loaded", path)
    return payload


def check_trees(obj: Any) -> list[str]:
    """Why the scikit-learn decision trees in ``obj`` could not be walked safely; empty when they can."""
    from sklearn.tree._tree import Tree

    out = []
    for owner in _objects(obj):
        tree = getattr(owner, "tree_", None)
        if isinstance(tree, Tree):
            n_in = getattr(owner, "n_features_in_", None)
            if n_in is None or int(n_in) != int(tree.n_features):
                out.append(f"a tree of {tree.n_features} features in an estimator of {n_in}")
            out += _tree_problems(tree)
        sub = getattr(owner, "estimators_", None)
        n_in = getattr(owner, "n_features_in_", None)
        if isinstance(sub, list) and n_in is not None and not hasattr(owner, "estimators_features_"):
            out += [f"a part of {getattr(e, 'n_features_in_', None)} features in an estimator of {n_in}"
                    for e in sub if hasattr(e, "tree_") and getattr(e, "n_features_in_", None) != n_in]
    return out


def _tree_problems(tree: Any) -> list[str]:
    """What is wrong with one tree's node arrays (see the module docstring)."""
    n = int(tree.node_count)
    left, right = np.asarray(tree.children_left), np.asarray(tree.children_right)
    feature, value = np.asarray(tree.feature), np.asarray(tree.value)
    if not (len(left) == len(right) == len(feature) == n >= 1) or value.shape[0] != n:
        return [f"node arrays of {len(left)}, {len(right)}, {len(feature)}, {value.shape[0]} rows for {n} nodes"]
    idx = np.arange(n)
    leaf = left == -1
    inner = ~leaf
    bad = (leaf != (right == -1)) | (inner & ((left <= idx) | (right <= idx) | (left >= n) | (right >= n)))
    bad |= inner & ((feature < 0) | (feature >= int(tree.n_features)))
    return [f"{int(bad.sum())} of its {n} nodes point outside it"] if bad.any() else []


def _objects(obj: Any, seen: set[int] | None = None) -> Iterator[Any]:
    """Every object reachable from ``obj`` through containers and attributes (each once)."""
    seen = set() if seen is None else seen
    stack = [obj]
    while stack:
        o = stack.pop()
        if id(o) in seen or isinstance(o, (str, bytes, int, float, np.ndarray, type)) or o is None:
            continue
        seen.add(id(o))
        yield o
        if isinstance(o, dict):
            stack.extend(o.values())
        elif isinstance(o, (list, tuple, set)):
            stack.extend(o)
        elif hasattr(o, "__dict__"):
            stack.extend(vars(o).values())
