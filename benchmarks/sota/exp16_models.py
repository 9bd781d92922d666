"""Inner leave-one-training-subject-out CV on the challenge's 7 training subjects only."""
import numpy as np, pandas as pd, time, sys
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier, HistGradientBoostingClassifier
from common import OWN_SETS, cached_inner
from xgboost import XGBClassifier
DS = sys.argv[1] if len(sys.argv) > 1 else "haart"
meta, F, y, tr, folds = cached_inner(DS)
OURS = OWN_SETS
def X(names): return np.hstack([F[n] for n in names])
def proba(make, Xm):
    P = np.zeros((len(y), 7))
    for s, a, b in folds:
        P[b] = make().fit(Xm[a], y[a]).predict_proba(Xm[b])
    return P
def acc(P):
    per = [np.mean(P[b].argmax(1) == y[b]) for s, a, b in folds]
    return round(float(np.mean(np.concatenate([P[b].argmax(1) == y[b] for s,a,b in folds]))), 4), np.round(per, 2)
et = lambda n=500, mf=0.3, s=0: (lambda: ExtraTreesClassifier(n, max_features=mf, n_jobs=2, random_state=s))
xgb = lambda **kw: (lambda: XGBClassifier(**{**dict(n_estimators=300, max_depth=4, learning_rate=0.1, subsample=0.8, colsample_bytree=0.8, tree_method="hist", n_jobs=2, random_state=0), **kw}))
res = {}
def run(tag, make, names):
    t = time.time(); P = proba(make, X(names)); res[tag] = P
    print(DS, tag, *acc(P), f"{time.time()-t:.0f}s", flush=True)
run("et", et(), OURS)
run("xgb", xgb(), OURS)
run("xgb-cs0.3", xgb(colsample_bytree=0.3), OURS)
run("hgb", lambda: HistGradientBoostingClassifier(max_iter=300, learning_rate=0.1, random_state=0), OURS)
print(DS, "et+xgb", *acc(res["et"] + res["xgb"]))
print(DS, "et+xgb+hgb", *acc(res["et"] + res["xgb"] + res["hgb"]))
run("et+wav", et(), OURS + ["zhou-wavelet"])
run("xgb+wav", xgb(), OURS + ["zhou-wavelet"])
print(DS, "et+xgb (+wav)", *acc(res["et+wav"] + res["xgb+wav"]))
run("rf", lambda: RandomForestClassifier(500, max_features=0.3, n_jobs=2, random_state=0), OURS)
print(DS, "et+xgb+rf", *acc(res["et"] + res["xgb"] + res["rf"]))
np.savez(f"/tmp/exp/inner-{DS}.npz", **res)
