import time, numpy as np
from common import data, challenge_split, inner_loso
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.metrics import confusion_matrix
ds, X, meta = data("haart"); y = meta.gesture.to_numpy()
F = np.load("/tmp/sota_F1.npy"); tr, te = challenge_split(meta)
pred = np.empty(len(y), dtype=object); imp = 0
for sub, a, b in inner_loso(meta, tr):
    m = ExtraTreesClassifier(500, n_jobs=2, random_state=0).fit(F[a], y[a]); pred[b] = m.predict(F[b]); imp = imp + m.feature_importances_
labs = sorted(set(y)); print(labs)
print(confusion_matrix(y[tr], pred[tr].astype(str), labels=labs))
from feats import touch_dynamics
_, names = touch_dynamics(X[:2])
o = np.argsort(-imp)[:40]; print([names[i] for i in o])
# per substrate/cover accuracy
import pandas as pd
mm = meta.iloc[tr].copy(); mm["ok"] = pred[tr] == y[tr]
print(mm.groupby("cover").ok.mean(), mm.groupby("substrate").ok.mean())
