"""Compute the own and the paper feature sets of haart and haart-challenge once into /tmp/exp (for exp 15, 16)."""
import numpy as np, time, sys
from touchbench.catalog import load_dataset
from touchbench.features.base import FEATURES
for dsname in ["haart", "haart-challenge"]:
    ds = load_dataset(dsname)
    caps = np.stack(ds.captures)
    out = {}
    for n in ["touch-rhythm", "cell-rhythm", "contact-motion", "zhou-wavelet", "zhou-basic", "msd", "flagg-stats", "smmhh", "lbptop"]:
        t = time.time()
        fs = FEATURES.create(n, sensor=ds.sensor)
        out[n] = fs.fit(caps[:2]).transform(caps)
        print(dsname, n, out[n].shape, round(time.time() - t, 1), flush=True)
    ds.meta.reset_index(drop=True).to_parquet(f"/tmp/exp/{dsname}-meta.parquet")
    np.savez(f"/tmp/exp/{dsname}-feats.npz", **out)
