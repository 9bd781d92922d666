"""Inner CV (challenge training subjects only): whole-capture features + their mean/sd over sub-windows (exp 15)."""
import numpy as np, pandas as pd, time
from sklearn.ensemble import ExtraTreesClassifier
from common import inner_setup, own_features
DS = "haart-challenge"
ds, caps, meta, F, y, tr, folds, X0 = inner_setup(DS)
def feats(c):
    return own_features(ds, c)
W = []
for k in range(4):
    W.append(feats(caps[:, k*108:(k+1)*108]))
W = np.stack(W)  # (4, N, D)
agg = np.hstack([W.mean(0), W.min(0), W.max(0), W.std(0)])
def ev(Xm, tag):
    t = time.time(); ok = []
    for s, a, b in folds:
        m = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(Xm[a], y[a]); ok.append(m.predict(Xm[b]) == y[b])
    print(tag, round(float(np.mean(np.concatenate(ok))), 4), [round(float(o.mean()), 2) for o in ok], f"{time.time()-t:.0f}s", flush=True)
ev(X0, "base")
ev(np.hstack([X0, agg]), "base+win4agg")
ev(np.hstack([X0, W.mean(0), W.std(0)]), "base+win4 mean,std")
# half windows (216) augmentation: train on whole + 3 windows of 216 (hop 108), test average of proba over windows + whole
H = [feats(caps[:, k*108:k*108+216]) for k in range(3)]
ok = []
for s, a, b in folds:
    Xa = np.vstack([X0[a]] + [h[a] for h in H]); ya = np.concatenate([y[a]] * 4)
    m = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(Xa, ya)
    P = m.predict_proba(X0[b]) + sum(m.predict_proba(h[b]) for h in H)
    ok.append(P.argmax(1) == y[b])
print("whole+3x216 aug, TTA", round(float(np.mean(np.concatenate(ok))), 4), [round(float(o.mean()), 2) for o in ok], flush=True)
