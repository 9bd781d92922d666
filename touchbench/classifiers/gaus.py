"""Gaus et al. 2015, section 4: "For RF, 1000 trees were used. In
the Boosting implementation, the Random Forest was used as the weak
learners. 500 iterations were used in all experiments. Both are implemented
using Weka software."

Interpretation. The paper gives only the tree and iteration counts; the
rest is Weka 3.7's ``RandomForest`` defaults, which we match where
scikit-learn can: fully grown trees (Weka ``-depth 0``, min. 1 instance per
leaf), information-gain splits (``criterion="entropy"``, Weka's
``RandomTree`` splits on gain), ``int(log2(M)) + 1`` attributes tried per
split (Weka ``-K 0``; scikit-learn's own default would be ``sqrt(M)``),
bootstrap bags of the training-set size, class distributions averaged over
trees. Not matched: Weka's random number streams and its tie-breaking
between equal splits, so forests differ tree by tree for the same seed.

Boosting: "Stage-wise Additive Modelling" with random forests as weak
learners, read as SAMME (Zhu et al. 2009) inside Weka's AdaBoostM1 loop
(see :mod:`touchbench.classifiers.boosting` for the algorithm and for the
finding that a forest fitting the training set perfectly stops the loop at
the first iteration, so the default ``gaus-boost`` is one 1000-tree forest).
``gaus-boost-oob`` is the variant that keeps boosting (not the paper's): each
forest fitted on a resample drawn by the boosting weights and weighed by its
error on the captures the resample left out (its class docstring lists the
interpretations).
"""

from __future__ import annotations

from ._util import WekaRandomForestClassifier, build
from .base import CLASSIFIERS
from .boosting import GausBoostingClassifier, ResampledBoostingClassifier

SOURCE = "Gaus et al. 2015, section 4; Weka defaults otherwise"

RF_DEFAULTS = {"n_estimators": 1000, "criterion": "entropy", "max_features": "weka", "n_jobs": 1}

BOOST_DEFAULTS = {
    "n_estimators": 500,
    "n_trees": 1000,
    "max_features": "weka",
    "criterion": "entropy",
    "weak_error": "train",
    "learning_rate": 1.0,
    "n_jobs": 1,
}


@CLASSIFIERS.register(
    "gaus-rf",
    description="random forest, 1000 trees, Weka's int(log2 M)+1 features per split, entropy",
    source=SOURCE,
    defaults=RF_DEFAULTS,
    extra=None, cheap_params=dict(n_estimators=5))
def gaus_rf(random_state=None, **params):
    """Gaus et al.'s random forest (module docstring: what is and is not Weka's)."""
    return build(WekaRandomForestClassifier, RF_DEFAULTS, random_state, params, name="gaus-rf")


@CLASSIFIERS.register(
    "gaus-boost",
    description="SAMME boosting of 1000-tree forests, 500 iterations (stops after 1: forests fit perfectly)",
    source=SOURCE + "; SAMME (Zhu et al. 2009) in Weka AdaBoostM1's loop",
    defaults=BOOST_DEFAULTS,
    extra=None, cheap_params=dict(n_estimators=3, n_trees=3))
def gaus_boost(random_state=None, **params):
    """Gaus et al.'s boosting; ``weak_error="oob"`` is the non-paper variant
    that keeps boosting when forests fit the training set perfectly."""
    return build(GausBoostingClassifier, BOOST_DEFAULTS, random_state, params, name="gaus-boost")


OOB_BOOST_DEFAULTS = {k: v for k, v in BOOST_DEFAULTS.items() if k != "weak_error"}


@CLASSIFIERS.register(
    "gaus-boost-oob",
    description="SAMME boosting of 1000-tree forests on weighted resamples, each weighed by its "
                "out-of-bag error (keeps boosting; not the paper's)",
    source=SOURCE + "; SAMME in Weka AdaBoostM1's resampling loop, the error out of bag",
    defaults=OOB_BOOST_DEFAULTS,
    extra=None, cheap_params=dict(n_estimators=3, n_trees=3))
def gaus_boost_oob(random_state=None, **params):
    """Boosting that keeps boosting when forests fit their training set perfectly (see
    :class:`touchbench.classifiers.boosting.ResampledBoostingClassifier`)."""
    return build(ResampledBoostingClassifier, OOB_BOOST_DEFAULTS, random_state, params, name="gaus-boost-oob")
