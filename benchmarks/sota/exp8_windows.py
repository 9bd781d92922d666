"""Inner-LOSO: features on sub-windows (train on every window, average window probabilities at test)
and gain augmentation; ET(500, mf=0.3)."""
import sys, time, numpy as np
from common import data, challenge_split, inner_loso
from feats import touch_dynamics, cell_spectral
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.preprocessing import LabelEncoder
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
def feats(Xw):
    return np.hstack([touch_dynamics(Xw)[0], cell_spectral(Xw)[0]])
def windows(L, S):
    starts = list(range(0, 432 - L + 1, S))
    W = np.concatenate([X[:, s:s + L] for s in starts])  # (k*N, L, 8, 8), window-major
    return W, len(starts)
cfg = sys.argv[1]
L, S = map(int, cfg.split("/"))
t = time.time(); W, k = windows(L, S); FW = feats(W).reshape(k, len(X), -1); print(cfg, "windows", k, "feat time", round(time.time() - t), flush=True)
np.save(f"/tmp/sota_FW_{L}_{S}.npy", FW)
acc = []; P = np.zeros((len(y), 7))
for sub, a, b in inner_loso(meta, tr):
    m = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(FW[:, a].reshape(-1, FW.shape[2]), np.tile(y[a], k))
    P[b] = np.mean([m.predict_proba(FW[j, b]) for j in range(k)], 0); acc.append((P[b].argmax(1) == y[b]).mean())
print(cfg, round(np.mean(acc), 4), np.round(acc, 2), flush=True)
np.save(f"/tmp/sota_P8_{L}_{S}.npy", P)
