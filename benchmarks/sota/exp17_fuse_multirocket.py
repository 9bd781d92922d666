"""Inner CV (challenge training subjects only): ET on the package sets fused with MultiRocket (exp 17).

MultiRocket as aeon's classifier builds it (transform, StandardScaler(with_mean=False),
RidgeClassifierCV(alphas=logspace(-3, 3, 10))); its ridge scores -> softmax at
temperature tau -> probability average with the ET's, weight w on MultiRocket.
"""
import time
import numpy as np
from aeon.transformations.collection.convolution_based import MultiRocket
from sklearn.ensemble import ExtraTreesClassifier
from sklearn.linear_model import RidgeClassifierCV
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from common import OWN_SETS, cached_inner
from touchbench.catalog import load_dataset

DS = "haart-challenge"
ds = load_dataset(DS)
S = np.ascontiguousarray(np.stack(ds.captures).reshape(len(ds.captures), -1, 64).transpose(0, 2, 1), dtype=np.float64)
meta, F, y, tr, folds = cached_inner(DS)
X0 = np.hstack([F[n] for n in OWN_SETS])
P_et = np.zeros((len(y), 7)); Z_mr = np.zeros((len(y), 7))
for s, a, b in folds:
    t = time.time()
    P_et[b] = ExtraTreesClassifier(500, max_features=0.3, n_jobs=1, random_state=0).fit(X0[a], y[a]).predict_proba(X0[b])
    pipe = make_pipeline(MultiRocket(n_kernels=10000, n_jobs=1, random_state=0), StandardScaler(with_mean=False),
                         RidgeClassifierCV(alphas=np.logspace(-3, 3, 10))).fit(S[a], y[a])
    Z_mr[b] = pipe.decision_function(S[b])
    print(s, "et", round(float(np.mean(P_et[b].argmax(1) == y[b])), 3), "mr", round(float(np.mean(Z_mr[b].argmax(1) == y[b])), 3), f"{time.time()-t:.0f}s", flush=True)
acc = lambda P: round(float(np.mean(P[tr].argmax(1) == y[tr])), 4)
print("ET", acc(P_et), "MultiRocket", acc(Z_mr))
for tau in (0.1, 0.3, 1.0):
    Z = Z_mr / tau; Q = np.exp(Z - Z.max(1, keepdims=True)); Q /= Q.sum(1, keepdims=True)
    for w in (0.25, 0.5):
        print(f"fusion tau={tau} w={w}", acc((1 - w) * P_et + w * Q))
