"""Outer evaluation (run once per design frozen by inner CV): challenge + LOSO with ET on F1+F2."""
import time, numpy as np
from common import data, challenge_split, loso
from sklearn.ensemble import ExtraTreesClassifier
ds, X, meta = data("haart"); y = meta.gesture.to_numpy()
F = np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy")]); tr, te = challenge_split(meta)
mk = lambda: ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0)
m = mk().fit(F[tr], y[tr]); print("challenge", (m.predict(F[te]) == y[te]).mean())
acc = []
for sub, a, b in loso(meta):
    m = mk().fit(F[a], y[a]); acc.append((m.predict(F[b]) == y[b]).mean())
print("LOSO", np.mean(acc), np.round(acc, 3))
