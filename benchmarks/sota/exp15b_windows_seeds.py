"""Inner CV (challenge training subjects only): whole-capture features + their mean/sd over sub-windows (exp 15)."""
import numpy as np, pandas as pd, time, sys
from sklearn.ensemble import ExtraTreesClassifier
from common import inner_setup, own_features
from xgboost import XGBClassifier
DS = sys.argv[1]
ds, caps, meta, F, y, tr, folds, X0 = inner_setup(DS)
def feats(c):
    return own_features(ds, c)
def winfeats(k, L):
    T = caps.shape[1]; starts = np.linspace(0, T - L, k).round().astype(int)
    W = np.stack([feats(caps[:, s:s+L]) for s in starts]); return np.hstack([W.mean(0), W.std(0)])
def ev(Xm, tag, seeds=(0, 1), make=None):
    t = time.time(); accs = []
    for sd in seeds:
        ok = []
        for s, a, b in folds:
            m = (make(sd) if make else ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=sd)).fit(Xm[a], y[a]); ok.append(m.predict(Xm[b]) == y[b])
        accs.append(float(np.mean(np.concatenate(ok))))
    print(DS, tag, np.round(accs, 4), round(float(np.mean(accs)), 4), f"{time.time()-t:.0f}s", flush=True)
ev(X0, "base")
for k, L in [(4, 108), (7, 108), (3, 216), (8, 54)]:
    ev(np.hstack([X0, winfeats(k, L)]), f"base+win k={k} L={L}")
xg = lambda sd: XGBClassifier(n_estimators=300, max_depth=4, learning_rate=0.1, subsample=0.8, colsample_bytree=0.8, tree_method="hist", n_jobs=1, random_state=sd)
ev(X0, "xgb base", seeds=(0,), make=xg)
ev(np.hstack([X0, winfeats(4, 108)]), "xgb base+win4", seeds=(0,), make=xg)
