"""Inner-LOSO: ET(500) per paper feature set; decision-level fusion with ours."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.preprocessing import LabelEncoder
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
def ev(F, tag, mf="sqrt"):
    acc = []; P = np.zeros((len(y), 7))
    for sub, a, b in inner_loso(meta, tr):
        m = ExtraTreesClassifier(500, max_features=mf, n_jobs=1, random_state=0).fit(F[a], y[a])
        P[b] = m.predict_proba(F[b]); acc.append((P[b].argmax(1) == y[b]).mean())
    print(tag, round(np.mean(acc), 4), np.round(acc, 2), flush=True); return P
Ps = {}
for name in ["msd", "sd", "bmh", "flagg-stats", "zhou-basic", "zhou-wavelet", "smmhh", "lbptop"]:
    Ps[name] = ev(np.load(f"/tmp/sota_paper_{name}.npy"), name)
Ps["ours"] = ev(np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy")]), "ours(F1+F2)", 0.3)
np.savez("/tmp/sota_P10.npz", **Ps)
acc = lambda P: round((P[tr].argmax(1) == y[tr]).mean(), 4)
order = sorted(Ps, key=lambda k: -acc(Ps[k])); print("order", order)
for k in range(2, len(order) + 1):
    print("fuse top", k, order[:k], acc(sum(Ps[c] for c in order[:k])))
