import time, sys, numpy as np
from common import data, challenge_split
from aeon.classification.convolution_based import MiniRocketClassifier
name = sys.argv[1] if len(sys.argv) > 1 else "haart"
ds, X, meta = data(name)
tr, te = challenge_split(meta)
y = meta.gesture.to_numpy()
Xs = X.reshape(len(X), X.shape[1], 64).transpose(0, 2, 1)  # (N, 64, T)
t0 = time.time()
clf = MiniRocketClassifier(random_state=0, n_jobs=1)
clf.fit(Xs[tr], y[tr]); t1 = time.time()
p = clf.predict(Xs[te]); t2 = time.time()
print(name, "acc", (p == y[te]).mean(), "fit", t1 - t0, "pred/capture ms", 1000 * (t2 - t1) / len(te))
