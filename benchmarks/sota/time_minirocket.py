import time, numpy as np
from common import data, challenge_split
from aeon.classification.convolution_based import MiniRocketClassifier
ds, X, meta = data("haart"); tr, te = challenge_split(meta); y = meta.gesture.to_numpy()
Xs = np.ascontiguousarray(X.reshape(len(X), 432, 64).transpose(0, 2, 1))
clf = MiniRocketClassifier(random_state=0, n_jobs=1).fit(Xs[tr[:200]], y[tr[:200]])
clf.predict(Xs[te[:1]])
ts = []
for i in range(10):
    t = time.perf_counter(); clf.predict(Xs[te[i:i + 1]]); ts.append(time.perf_counter() - t)
print("minirocket single-capture ms median", np.median(ts) * 1e3)
t = time.perf_counter(); clf.predict(Xs[te]); print("batch ms/capture", (time.perf_counter() - t) / len(te) * 1e3)
