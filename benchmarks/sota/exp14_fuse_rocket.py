"""Inner-LOSO: fuse ET (package features) with MiniRocket-on-summary-series + logistic regression (probabilities)."""
import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import StandardScaler, LabelEncoder
from sklearn.pipeline import make_pipeline
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
F0 = np.hstack([np.load(f"/tmp/sota_pkg_{n}.npy") for n in ["touch-rhythm", "cell-rhythm", "contact-motion"]])
R = np.load("/tmp/sota_R_summary.npy").astype(np.float64)
Pe = np.zeros((len(y), 7)); Pr = np.zeros((len(y), 7)); t = time.time()
for sub, a, b in inner_loso(meta, tr):
    Pe[b] = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(F0[a], y[a]).predict_proba(F0[b])
    Pr[b] = make_pipeline(StandardScaler(), LogisticRegression(C=1e-3, max_iter=500)).fit(R[a], y[a]).predict_proba(R[b])
acc = lambda P: round((P[tr].argmax(1) == y[tr]).mean(), 4)
print("et", acc(Pe), "rocket-summary logreg", acc(Pr), round(time.time() - t), "s")
for w in [0.2, 0.35, 0.5]:
    print("fuse w_rocket", w, acc((1 - w) * Pe + w * Pr))
