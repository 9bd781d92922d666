"""Inner-LOSO (7 training subjects): MiniRocket features + ridge, alone and fused with ET."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.linear_model import RidgeClassifierCV
from sklearn.preprocessing import StandardScaler, LabelEncoder
from sklearn.pipeline import make_pipeline
from sklearn.ensemble import ExtraTreesClassifier
from scipy.special import softmax
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
F = np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy")])
def run(make, Z, score="proba"):
    P = np.zeros((len(y), 7)); acc = []
    for sub, a, b in inner_loso(meta, tr):
        m = make().fit(Z[a], y[a])
        P[b] = m.predict_proba(Z[b]) if score == "proba" else softmax(m.decision_function(Z[b]) * 5, 1)
        acc.append((P[b].argmax(1) == y[b]).mean())
    return P, round(np.mean(acc), 4), np.round(acc, 2)
res = {}
ridge = lambda: make_pipeline(StandardScaler(), RidgeClassifierCV(alphas=np.logspace(-1, 4, 12)))
for k in ["cells_raw", "cells_log", "summary"]:
    R = np.load(f"/tmp/sota_R_{k}.npy").astype(np.float64)
    t = time.time(); P, acc, per = run(ridge, R, "dec"); res[k] = P; print(k, acc, per, round(time.time() - t), flush=True)
Pet, acc, per = run(lambda: ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0), F); res["et"] = Pet; print("et", acc, per)
np.savez("/tmp/sota_P7.npz", **res)
def acc(P): return round((P[tr].argmax(1) == y[tr]).mean(), 4)
for combo in [("et", "cells_raw"), ("et", "cells_log"), ("et", "summary"), ("et", "cells_log", "summary"), ("cells_log", "summary"), ("et", "cells_raw", "cells_log", "summary")]:
    print(combo, acc(sum(res[c] for c in combo)))
