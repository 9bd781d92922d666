"""Inner-LOSO on F1+F2+F3 with gain augmentation (x0.5, x2): classifier variety and fusion."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier, RandomForestClassifier, HistGradientBoostingClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import QuantileTransformer, LabelEncoder
from sklearn.pipeline import make_pipeline
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
F = np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy"), np.load("/tmp/sota_F3.npy")])
aug = list(np.load("/tmp/sota_Fgain.npy"))
def ev(make, tag):
    acc = []; P = np.zeros((len(y), 7)); t = time.time()
    for sub, a, b in inner_loso(meta, tr):
        Xa = np.vstack([F[a]] + [G[a] for G in aug]); ya = np.concatenate([y[a]] * 3)
        m = make().fit(Xa, ya); P[b] = m.predict_proba(F[b]); acc.append((P[b].argmax(1) == y[b]).mean())
    print(tag, round(np.mean(acc), 4), np.round(acc, 2), round(time.time() - t), "s", flush=True); return P
Ps = {}
# Ps["hgb"] = ev(lambda: HistGradientBoostingClassifier(max_iter=200, learning_rate=0.1, max_leaf_nodes=15, max_features=0.3, random_state=0), "hgb")
Ps["logreg"] = ev(lambda: make_pipeline(QuantileTransformer(n_quantiles=200, output_distribution="normal"), LogisticRegression(C=0.02, max_iter=3000)), "logreg C=.02")
Ps["rf"] = ev(lambda: RandomForestClassifier(500, max_features="sqrt", n_jobs=1, random_state=0), "rf")
Ps["et"] = ev(lambda: ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0), "et")
np.savez("/tmp/sota_P11.npz", **Ps)
acc = lambda P: round((P[tr].argmax(1) == y[tr]).mean(), 4)
import itertools
for r in [2, 3, 4]:
    for c in itertools.combinations(Ps, r): print("fuse", c, acc(sum(Ps[k] for k in c)))
