"""CNN speed probe + one inner validation split (train 5 training subjects, validate on s03+s10... chosen fixed)."""
import sys, time, numpy as np
from common import data, challenge_split
from cnn import prep, train, predict_proba
from sklearn.preprocessing import LabelEncoder
ds, X, meta = data("haart"); y = LabelEncoder().fit_transform(meta.gesture); tr, te = challenge_split(meta)
Xp = prep(X); subj = meta.subject.to_numpy()
val_subj = ["s04", "s10"]  # fixed inner validation subjects (training subjects only)
a = tr[~np.isin(subj[tr], val_subj)]; b = tr[np.isin(subj[tr], val_subj)]
epochs = int(sys.argv[1]) if len(sys.argv) > 1 else 30
t = time.time(); net = train(Xp[a], y[a], epochs=epochs, verbose=True, Xval=Xp[b], yval=y[b])
print("train time", time.time() - t)
print("val acc", (predict_proba(net, Xp[b]).argmax(1) == y[b]).mean(), "tta", (predict_proba(net, Xp[b], tta=True).argmax(1) == y[b]).mean())
