import time, sys, numpy as np
from common import data, challenge_split, inner_loso, loso
from feats import touch_dynamics
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier
ds, X, meta = data("haart")
y = meta.gesture.to_numpy()
t0 = time.time(); F, names = touch_dynamics(X); print("features", F.shape, time.time() - t0, "s"); np.save("/tmp/sota_F1.npy", F)
tr, te = challenge_split(meta)
def innercv(make, F):
    accs = []
    for sub, a, b in inner_loso(meta, tr):
        m = make().fit(F[a], y[a]); accs.append((m.predict(F[b]) == y[b]).mean())
    return np.mean(accs), np.round(accs, 2)
for nm, make in [("ET", lambda: ExtraTreesClassifier(500, n_jobs=2, random_state=0)),
                 ("RF", lambda: RandomForestClassifier(500, n_jobs=2, random_state=0))]:
    t = time.time(); print(nm, innercv(make, F), time.time() - t)
