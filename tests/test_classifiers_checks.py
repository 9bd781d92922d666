"""scikit-learn's estimator checks for every registered classifier but the
deep ones and the aeon peers (tests/test_classifiers_cnn.py,
tests/test_classifiers_inception.py and tests/test_classifiers_peers.py run
them for those), the other estimators that take the captures themselves
(registry tag ``input="captures"``) and compute feature sets inside: the
nested search over methods (tests/test_methods_nested_select.py) and the
training for shift (tests/test_augment.py), and the classifiers that adapt to a
new session before they predict (tag ``unlabelled_test``: tests/test_adapt.py
runs the checks on ``session-centred`` adapted to its training rows).

The papers' defaults (1000 trees, 500 boosting iterations, 500 MLP epochs,
L-BFGS to 1e-10) are slow, so each classifier is checked with the smaller
settings each entry declares as ``cheap_params`` in the registry; the code
paths are the same. Checks that do not apply
are listed in ``NOT_APPLICABLE`` with the reason, and run as expected
failures (strict: if one starts passing, the test says so).

A registry entry whose class is scikit-learn's own (a nearest centroid, a
decision tree...) is checked by scikit-learn's suite already; what the
registry can break there is only its parameters, so those entries run the
checks that fit with them (``PARAMETER_CHECKS``) instead of the whole suite.
"""

from __future__ import annotations

import pytest
from sklearn.utils import estimator_checks
from sklearn.utils.estimator_checks import parametrize_with_checks

from touchbench.classifiers import CLASSIFIERS, make_classifier
from touchbench.datasets.model import SensorSpec

_BOOTSTRAP = ("bags are drawn at random (with probability proportional to the weights), so a weight of 2 "
              "equals a repeated row in distribution only, not for one seed (scikit-learn's own "
              "RandomForestClassifier fails this check for the same reason)")
_EQUIV = ("check_sample_weight_equivalence_on_dense_data", "check_sample_weight_equivalence_on_sparse_data")

NOT_APPLICABLE = {
    "gaus-rf": dict.fromkeys(_EQUIV, _BOOTSTRAP),
    "flagg-rf": dict.fromkeys(_EQUIV, _BOOTSTRAP),
    "zhou-bagged-trees": dict.fromkeys(_EQUIV, _BOOTSTRAP),
    "gaus-boost": {_EQUIV[0]: "its weak learners are bootstrapped random forests: " + _BOOTSTRAP},
    "gaus-boost-oob": dict.fromkeys(_EQUIV, "each weak learner is fitted on a resample drawn by the weights: "
                                           + _BOOTSTRAP),
    "xgboost": {_EQUIV[0]: "row subsampling (subsample=0.8) draws rows, so weights are not repeats"},
    "jung-svm": {_EQUIV[0]: "libsvm rescales C per sample, which is not equivalent to repeating rows "
                            "(scikit-learn marks SVC likewise)"},
    "zhou-tree": dict.fromkeys(_EQUIV, "min_samples_split=10 (MATLAB's MinParentSize) counts rows, not weights"),
}

NAMES = [n for n in CLASSIFIERS.names()
         if not {"deep", "peers"} & set((CLASSIFIERS.entry(n).tags.get("extra") or "").split(","))
         and CLASSIFIERS.entry(n).tags.get("input") != "captures" and not CLASSIFIERS.entry(n).tags.get("unlabelled_test")]


def _expected(est):
    return NOT_APPLICABLE.get(est._touchbench_name, {})


#: the checks' rows are any number of columns: a one-cell sensor makes every row whole frames
#: (the raw-frame classifiers take their grid and frame rate from the sensor)
ONE_CELL = SensorSpec("one-cell", (1, 1), 50.0)


def _build(name):
    est = make_classifier(name, random_state=0, sensor=ONE_CELL, **CLASSIFIERS.entry(name).tags.get("cheap_params", {}))
    est._touchbench_name = name  # read by _expected; not a constructor parameter, clone drops it
    return est


#: the checks that fit a classifier with the registry's parameters: whether it learns, keeps its
#: classes, refits to the same model, survives one class, one sample or one feature, pickles, and
#: round-trips its parameters
PARAMETER_CHECKS = ("check_classifiers_train", "check_classifiers_classes", "check_fit_idempotent",
                    "check_classifiers_one_label", "check_fit2d_1sample", "check_fit2d_1feature",
                    "check_supervised_y_2d", "check_estimators_pickle", "check_get_params_invariance",
                    "check_set_params")


def _library_class(name: str) -> bool:
    """Whether the registry builds one of scikit-learn's own classes for ``name``."""
    return not type(_build(name)).__module__.startswith("touchbench.")


OWN = [n for n in NAMES if not _library_class(n)]
LIBRARY = [n for n in NAMES if _library_class(n)]


@parametrize_with_checks([_build(n) for n in OWN], expected_failed_checks=_expected, xfail_strict=True)
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


@pytest.mark.parametrize("check", PARAMETER_CHECKS)
@pytest.mark.parametrize("name", LIBRARY)
def test_library_classes_fit_with_the_registry_parameters(name, check):
    est = _build(name)
    if check in _expected(est):
        pytest.xfail(_expected(est)[check])
    getattr(estimator_checks, check)(name, est)


def test_the_library_classes_are_the_ones_scikit_learn_checks_itself():
    assert {"zhou-lda", "zhou-tree", "jung-naive-bayes"} <= set(LIBRARY)
    assert "touch-extra-trees" in OWN and "gaus-rf" in OWN


def test_every_not_applicable_entry_names_a_registered_classifier():
    assert set(NOT_APPLICABLE) <= set(NAMES)
    assert all(reason for checks in NOT_APPLICABLE.values() for reason in checks.values())


@pytest.mark.parametrize("name", NAMES)
def test_clone_keeps_the_registry_parameters(name):
    from sklearn.base import clone

    est = make_classifier(name, random_state=3)
    assert clone(est).get_params() == est.get_params()
