"""MiniRocket features on three inputs; transform fitted on challenge-train subjects only."""
import time, numpy as np
from common import data, challenge_split
from feats_series import summary_series, cells_log
from aeon.transformations.collection.convolution_based import MiniRocket
ds, X, meta = data("haart"); tr, te = challenge_split(meta)
inputs = {"cells_raw": lambda: X.reshape(len(X), 432, 64).transpose(0, 2, 1).copy(),
          "cells_log": lambda: cells_log(X), "summary": lambda: summary_series(X)}
for k, f in inputs.items():
    Z = np.ascontiguousarray(f(), dtype=np.float64)
    t = time.time(); mr = MiniRocket(random_state=0, n_jobs=1).fit(Z[tr]); R = mr.transform(Z)
    print(k, R.shape, time.time() - t, flush=True); np.save(f"/tmp/sota_R_{k}.npy", R.astype(np.float32))
