import numpy as np, pandas as pd
from common import data
ds, X, meta = data("haart")
tot = X.reshape(len(X), 432, 64)
meta = meta.copy()
meta["mean"] = tot.mean(axis=(1,2)); meta["p5cell"] = np.percentile(tot, 5, axis=1).mean(1)
meta["std_t"] = tot.sum(2).std(1); meta["max"] = tot.max(axis=(1,2))
pd.set_option("display.width", 200)
print(meta.groupby(["substrate","cover"])[["mean","p5cell","std_t","max"]].mean().round(1))
print(meta.groupby("gesture")[["mean","p5cell","std_t","max"]].mean().round(1))
print(meta.groupby("subject")[["mean","p5cell","std_t","max"]].mean().round(1))
print(meta.groupby(["subject","split"]).size().unstack())
