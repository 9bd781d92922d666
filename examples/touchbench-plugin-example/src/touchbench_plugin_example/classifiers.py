"""The classifier ``example-nearest-centroid``: the label of the nearest class mean."""

from __future__ import annotations

from sklearn.neighbors import NearestCentroid

from touchbench.classifiers.base import CLASSIFIERS

DEFAULTS = {"metric": "euclidean", "shrink_threshold": None}


@CLASSIFIERS.register("example-nearest-centroid",
                      description="example plugin: the label of the nearest class mean (nearest centroid)",
                      source="example plugin (scikit-learn NearestCentroid)", defaults=DEFAULTS)
def nearest_centroid(random_state: int | None = None, metric: str = "euclidean",
                     shrink_threshold: float | None = None) -> NearestCentroid:
    """Each class is its mean feature vector; a row gets the label of the nearest one.

    A thin wrapper of scikit-learn's ``NearestCentroid``, so the estimator
    follows the scikit-learn API touchbench expects (``fit``, ``predict``,
    ``predict_proba``, ``get_params``). ``random_state`` is accepted like
    every touchbench classifier's and not used: the method has no
    randomness. ``metric`` is ``"euclidean"`` or ``"manhattan"`` (then the
    centroid is the per-feature median); ``shrink_threshold`` shrinks the
    centroids towards the overall mean (the nearest shrunken centroid);
    None keeps the class means.
    """
    return NearestCentroid(metric=metric, shrink_threshold=shrink_threshold)
