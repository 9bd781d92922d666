"""Inner-LOSO ET(500, mf=0.3): thresholded series (v1) and gain augmentation (v2)."""
import sys, time, numpy as np
from common import data, challenge_split, inner_loso
from feats import touch_dynamics, cell_spectral, thresholded_series
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.preprocessing import LabelEncoder
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
F12 = np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy")])
t = time.time(); F3, n3 = thresholded_series(X); print("F3", F3.shape, round(time.time() - t), flush=True); np.save("/tmp/sota_F3.npy", F3)
def ev(F, aug=None, tag=""):
    acc = []; P = np.zeros((len(y), 7))
    for sub, a, b in inner_loso(meta, tr):
        Xa, ya = F[a], y[a]
        if aug is not None:
            Xa = np.vstack([Xa] + [G[a] for G in aug]); ya = np.concatenate([ya] * (1 + len(aug)))
        m = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(Xa, ya)
        P[b] = m.predict_proba(F[b]); acc.append((P[b].argmax(1) == y[b]).mean())
    print(tag, round(np.mean(acc), 4), np.round(acc, 2), flush=True); return P
ev(F3, tag="F3 alone")
ev(np.hstack([F12, F3]), tag="F1+F2+F3")
# gain augmentation: S scaled by g (baseline kept)
aug = []
for g in [0.5, 2.0]:
    C = X.reshape(len(X), 432, 64); b = np.percentile(C, 5, axis=1)[:, None, :]
    Xg = (b + g * (C - b)).reshape(X.shape)
    Fg = np.hstack([touch_dynamics(Xg)[0], cell_spectral(Xg)[0], thresholded_series(Xg)[0]]); aug.append(Fg)
np.save("/tmp/sota_Fgain.npy", np.stack(aug))
ev(np.hstack([F12, F3]), aug=aug, tag="F1+F2+F3 gain-aug x0.5,x2")
