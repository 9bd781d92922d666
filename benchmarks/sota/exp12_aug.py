"""Inner-LOSO, package feature sets (touch-rhythm + cell-rhythm + contact-motion), ET(500, mf=0.3):
gain / time-warp augmentation at training, and test-time augmentation."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from touchbench.features.base import FEATURES
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.preprocessing import LabelEncoder
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
sets = [FEATURES.create(n, sensor=ds.sensor) for n in ["touch-rhythm", "cell-rhythm", "contact-motion"]]
feat = lambda caps: np.hstack([s.fit(caps[:1]).transform(caps) for s in sets])
F0 = np.hstack([np.load(f"/tmp/sota_pkg_{n}.npy") for n in ["touch-rhythm", "cell-rhythm", "contact-motion"]])
C = X.reshape(len(X), 432, 64); k = int(0.05 * 431); b = np.partition(C, k, axis=1)[:, k][:, None, :]
def gain(g): return list((b + g * (C - b)).reshape(X.shape))
def warp(f):
    n = int(round(432 / f)); idx = np.linspace(0, 431, n); i0 = np.floor(idx).astype(int); i1 = np.minimum(i0 + 1, 431); a = (idx - i0)[None, :, None, None]
    return list((1 - a) * X[:, i0] + a * X[:, i1])
V = {}
for tag, fn in [("g0.5", lambda: gain(0.5)), ("g2", lambda: gain(2.0)), ("g0.33", lambda: gain(1 / 3)), ("g3", lambda: gain(3.0)),
                ("w0.8", lambda: warp(0.8)), ("w1.25", lambda: warp(1.25))]:
    t = time.time(); V[tag] = feat(fn()); print(tag, round(time.time() - t), flush=True)
np.savez("/tmp/sota_V12.npz", **V)
def ev(train_aug, test_aug=(), tag=""):
    acc = []; P = np.zeros((len(y), 7)); t = time.time()
    for sub, a, bb in inner_loso(meta, tr):
        Xa = np.vstack([F0[a]] + [V[g][a] for g in train_aug]); ya = np.tile(y[a], 1 + len(train_aug))
        m = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(Xa, ya)
        P[bb] = np.mean([m.predict_proba(F0[bb])] + [m.predict_proba(V[g][bb]) for g in test_aug], 0); acc.append((P[bb].argmax(1) == y[bb]).mean())
    print(tag, round(np.mean(acc), 4), np.round(acc, 2), round(time.time() - t), "s", flush=True); return P
ev((), tag="no aug")
ev(("g0.5", "g2"), tag="gain .5,2")
ev(("g0.5", "g2"), ("g0.5", "g2"), tag="gain .5,2 + TTA")
ev(("g0.5", "g2", "g0.33", "g3"), tag="gain .33,.5,2,3")
ev(("w0.8", "w1.25"), tag="warp .8,1.25")
ev(("g0.5", "g2", "w0.8", "w1.25"), tag="gain .5,2 + warp .8,1.25")
