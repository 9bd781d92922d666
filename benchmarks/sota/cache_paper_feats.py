"""Compute the registered paper feature sets on haart once (none is fold-dependent) for exploration."""
import time, numpy as np
from common import data
from touchbench.features.base import FEATURES
ds, X, meta = data("haart")
for name in ["msd", "sd", "bmh", "flagg-stats", "zhou-basic", "zhou-wavelet", "smmhh", "lbptop"]:
    fs = FEATURES.create(name, sensor=ds.sensor)
    t = time.time(); F = fs.fit(ds.captures).transform(ds.captures)
    print(name, F.shape, round((time.time() - t) / len(X) * 1000, 2), "ms/capture", flush=True)
    np.save(f"/tmp/sota_paper_{name}.npy", F)
