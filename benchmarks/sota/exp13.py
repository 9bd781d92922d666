"""Inner-LOSO on the package features: XGBoost, feature selection inside the fold, ET size/seeds, fast subsets."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.preprocessing import LabelEncoder
from xgboost import XGBClassifier
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
names = ["touch-rhythm", "cell-rhythm", "contact-motion"]
blocks = {n: np.load(f"/tmp/sota_pkg_{n}.npy") for n in names}
F0 = np.hstack([blocks[n] for n in names])
def ev(make, F, tag, select=None):
    acc = []; t = time.time()
    for sub, a, b in inner_loso(meta, tr):
        cols = slice(None)
        if select:  # importance ranking from a forest fitted on the fold's training rows only
            imp = ExtraTreesClassifier(200, max_features=0.3, n_jobs=1, random_state=1).fit(F[a], y[a]).feature_importances_
            cols = np.argsort(-imp)[:select]
        m = make().fit(F[a][:, cols], y[a]); acc.append((m.predict(F[b][:, cols]) == y[b]).mean())
    print(tag, round(np.mean(acc), 4), np.round(acc, 2), round(time.time() - t), "s", flush=True)
et = lambda n=500, mf=0.3, s=0: (lambda: ExtraTreesClassifier(n, max_features=mf, n_jobs=1, random_state=s))
ev(et(500, 0.3, 1), F0, "ET500 mf.3 seed1")
ev(et(500, "sqrt"), F0, "ET500 sqrt")
ev(et(100, 0.3), F0, "ET100 mf.3")
ev(et(500, 0.3), F0, "ET500 select top 100", select=100)
ev(et(500, 0.3), F0, "ET500 select top 200", select=200)
for n in names:
    ev(et(100, 0.3), blocks[n], f"ET100 {n}")
ev(et(100, 0.3), np.hstack([blocks["cell-rhythm"], blocks["contact-motion"]]), "ET100 cell+contact")
ev(lambda: XGBClassifier(n_estimators=200, max_depth=3, learning_rate=0.1, subsample=0.8, colsample_bytree=0.3, n_jobs=1, random_state=0, tree_method="hist"), F0, "XGB 200 d3")
