"""How many forests gaus-boost and gaus-boost-oob keep on Gaus et al.'s feature sets (HAART challenge
training captures, 100-tree forests, 10 iterations), with each forest's weighted error and weight.

    PYTHONPATH=. python docs/research/paper-misses/boost-iterations.py
"""

import numpy as np

from touchbench.catalog import load_dataset
from touchbench.classifiers import make_classifier
from touchbench.features.base import make_feature_set

ds = load_dataset("haart-challenge")
keep = np.flatnonzero(ds.meta["split"].astype(str).to_numpy() == "train")
caps = [ds.captures[i] for i in keep]
y = ds.meta["gesture"].astype(str).to_numpy()[keep]
for name in ["msd", "smmhh", "lbptop"]:
    X = make_feature_set(name, {}, ds.sensor).fit(caps, y).transform(caps)
    for clf in ["gaus-boost", "gaus-boost-oob"]:
        b = make_classifier(clf, random_state=0, n_trees=100, n_estimators=10).fit(X, y)
        print(name, clf, b.n_iterations_, b.stop_reason_, "errors", np.round(b.estimator_errors_, 3),
              "weights", np.round(b.estimator_weights_, 2), flush=True)
