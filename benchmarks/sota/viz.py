import numpy as np, matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
from common import data
ds, X, meta = data("haart")
subs = ["s04", "s09"]; gests = ["pat", "rub", "scratch", "stroke", "tickle"]
fig, ax = plt.subplots(len(gests), 4, figsize=(16, 11))
for i, g in enumerate(gests):
    for j, (s, cov) in enumerate([(subs[0], "none"), (subs[0], "fur"), (subs[1], "none"), (subs[1], "fur")]):
        m = meta[(meta.subject == s) & (meta.gesture == g) & (meta.cover == cov) & (meta.substrate == "foam")]
        if len(m) == 0: continue
        c = X[m.index[0]].reshape(432, 64); base = np.percentile(c, 5, 0); S = np.clip(c - base, 0, None)
        a = ax[i, j]; a.plot(S.sum(1), lw=.7, label="sum"); a2 = a.twinx()
        w = S + 1e-9; cy = (w * np.repeat(np.arange(8), 8)).sum(1) / w.sum(1); cx = (w * np.tile(np.arange(8), 8)).sum(1) / w.sum(1)
        a2.plot(cx, "r", lw=.5); a2.plot(cy, "g", lw=.5); a2.set_ylim(0, 7)
        a.set_title(f"{g} {s} {cov}", fontsize=8)
plt.tight_layout(); plt.savefig("/tmp/viz.png", dpi=60)
