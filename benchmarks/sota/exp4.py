import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier, HistGradientBoostingClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import QuantileTransformer, StandardScaler, LabelEncoder
from sklearn.pipeline import make_pipeline
from xgboost import XGBClassifier
ds, X, meta = data("haart"); y = meta.gesture.to_numpy(); le = LabelEncoder().fit(y); yi = le.transform(y)
F = np.hstack([np.load("/tmp/sota_F1.npy"), np.load("/tmp/sota_F2.npy")]); tr, te = challenge_split(meta)
def innercv(make, F):
    acc = []; P = np.zeros((len(y), 7))
    for sub, a, b in inner_loso(meta, tr):
        m = make().fit(F[a], yi[a]); P[b] = m.predict_proba(F[b]); acc.append((P[b].argmax(1) == yi[b]).mean())
    return round(np.mean(acc), 4), np.round(acc, 2), P
models = {
 "ET1000_sqrt": lambda: ExtraTreesClassifier(1000, n_jobs=2, random_state=0),
 "ET500_mf0.3": lambda: ExtraTreesClassifier(500, max_features=0.3, n_jobs=2, random_state=0),
 "logreg_q": lambda: make_pipeline(QuantileTransformer(n_quantiles=200, output_distribution="normal"), LogisticRegression(C=0.05, max_iter=2000)),
 "xgb": lambda: XGBClassifier(n_estimators=300, max_depth=4, learning_rate=0.05, subsample=0.8, colsample_bytree=0.3, n_jobs=2, random_state=0),
 "hgb": lambda: HistGradientBoostingClassifier(max_iter=300, learning_rate=0.05, max_leaf_nodes=15, random_state=0),
}
Ps = {}
for k, mk in models.items():
    t = time.time(); acc, per, P = innercv(mk, F); Ps[k] = P; print(k, acc, per, round(time.time() - t, 1), flush=True)
np.save("/tmp/sota_P4.npy", np.stack([Ps[k] for k in models]))
for combo in [("ET1000_sqrt", "logreg_q"), ("ET1000_sqrt", "xgb"), ("ET1000_sqrt", "logreg_q", "xgb"), tuple(models)]:
    P = sum(Ps[k] for k in combo); print(combo, round((P[tr].argmax(1) == yi[tr]).mean(), 4))
