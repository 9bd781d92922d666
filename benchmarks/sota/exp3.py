import time, numpy as np
from common import data, challenge_split, inner_loso
from feats import cell_spectral
from sklearn.ensemble import ExtraTreesClassifier
ds, X, meta = data("haart"); y = meta.gesture.to_numpy()
F1 = np.load("/tmp/sota_F1.npy"); tr, te = challenge_split(meta)
t = time.time(); F2, n2 = cell_spectral(X); print("cell_spectral", F2.shape, time.time() - t); np.save("/tmp/sota_F2.npy", F2)
def innercv(F, seed=0):
    acc = []
    for sub, a, b in inner_loso(meta, tr):
        m = ExtraTreesClassifier(500, n_jobs=2, random_state=seed).fit(F[a], y[a]); acc.append((m.predict(F[b]) == y[b]).mean())
    return round(np.mean(acc), 4), np.round(acc, 2)
print("F1", innercv(F1)); print("F2", innercv(F2)); print("F1+F2", innercv(np.hstack([F1, F2])))
