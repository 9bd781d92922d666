import time, numpy as np
from common import data
from touchbench.features.base import FEATURES
ds, X, meta = data("haart")
out = {}
for name in ["touch-rhythm", "cell-rhythm", "contact-motion"]:
    fs = FEATURES.create(name, sensor=ds.sensor).fit(ds.captures[:2])
    t = time.time(); F = fs.transform(ds.captures); dt = time.time() - t
    t = time.time(); [fs.transform([ds.captures[i]]) for i in range(20)]; d1 = (time.time() - t) / 20
    print(name, F.shape, "batch ms/capture", round(dt / len(X) * 1e3, 2), "single ms", round(d1 * 1e3, 2), "finite", np.isfinite(F).all(), flush=True)
    np.save(f"/tmp/sota_pkg_{name}.npy", F)
