"""Small frame-encoder + temporal-CNN for HAART, with sensor-respecting augmentation."""
from __future__ import annotations
import time, numpy as np, torch, torch.nn as nn, torch.nn.functional as Fn

torch.set_num_threads(1)

def prep(X):
    """(N, T, 8, 8) raw -> float32 log1p of baseline-subtracted pressure."""
    N, T, H, W = X.shape
    base = np.percentile(X.reshape(N, T, -1), 5, axis=1).reshape(N, 1, H, W)
    return np.log1p(np.clip(X - base, 0, None)).astype(np.float32)

class Net(nn.Module):
    def __init__(self, n_classes=7, c2=8, ct=48, p_drop=0.3):
        super().__init__()
        self.enc = nn.Sequential(nn.Conv2d(1, c2, 3, padding=1), nn.ReLU())
        self.tcn = nn.Sequential(
            nn.Conv1d(2 * c2 + 2, ct, 7, padding=3), nn.BatchNorm1d(ct), nn.ReLU(), nn.MaxPool1d(2),
            nn.Conv1d(ct, ct, 5, padding=2), nn.BatchNorm1d(ct), nn.ReLU(), nn.MaxPool1d(2),
            nn.Conv1d(ct, ct, 5, padding=2), nn.BatchNorm1d(ct), nn.ReLU())
        self.drop = nn.Dropout(p_drop)
        self.head = nn.Linear(2 * ct, n_classes)
    def forward(self, x):  # x (B, T, H, W)
        B, T, H, W = x.shape
        z = self.enc(x.reshape(B * T, 1, H, W))
        z = torch.cat([z.amax((2, 3)), z.mean((2, 3))], 1).reshape(B, T, -1)
        tot = torch.stack([x.mean((2, 3)), x.amax((2, 3))], 2)
        z = torch.cat([z, tot], 2).transpose(1, 2)
        z = self.tcn(z)
        z = torch.cat([z.mean(2), z.amax(2)], 1)
        return self.head(self.drop(z))

def augment(xb, rng, crop=384, shift=True, warp=True, gain=True, flips=True):
    """xb: (B, T, H, W) float32 log-pressure numpy; returns augmented (B, crop', H, W)."""
    B, T, H, W = xb.shape
    out = []
    for x in xb:
        if warp:
            f = rng.uniform(0.8, 1.25); n = int(round(min(T, crop * f)))
            s = rng.integers(0, T - n + 1); seg = x[s:s + n]
            idx = np.linspace(0, n - 1, crop); i0 = np.floor(idx).astype(int); i1 = np.minimum(i0 + 1, n - 1); a = (idx - i0)[:, None, None]
            x = (1 - a) * seg[i0] + a * seg[i1]
        else:
            s = rng.integers(0, T - crop + 1); x = x[s:s + crop]
        if flips:
            if rng.random() < 0.5: x = x[:, ::-1]
            if rng.random() < 0.5: x = x[:, :, ::-1]
            if rng.random() < 0.5: x = x.transpose(0, 2, 1)
        if shift:
            dy, dx = rng.integers(-2, 3, size=2)
            x = np.roll(x, (dy, dx), axis=(1, 2))
            if dy > 0: x[:, :dy] = 0
            elif dy < 0: x[:, dy:] = 0
            if dx > 0: x[:, :, :dx] = 0
            elif dx < 0: x[:, :, dx:] = 0
        if gain:
            x = x + np.float32(rng.normal(0, 0.3))  # log-domain gain ~ multiplicative pressure gain
            x = np.clip(x, 0, None) * (x > 0.0)
        out.append(np.ascontiguousarray(x))
    return np.stack(out).astype(np.float32)

def train(Xp, y, epochs=40, seed=0, bs=32, lr=3e-3, aug=None, verbose=False, Xval=None, yval=None):
    aug = aug or {}
    torch.manual_seed(seed); rng = np.random.default_rng(seed)
    net = Net(); opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-2)
    steps = epochs * int(np.ceil(len(y) / bs)); sch = torch.optim.lr_scheduler.OneCycleLR(opt, lr, total_steps=steps)
    yt = torch.as_tensor(y)
    for ep in range(epochs):
        net.train(); perm = rng.permutation(len(y)); t0 = time.time(); L = 0
        for k in range(0, len(y), bs):
            b = perm[k:k + bs]
            xb = torch.from_numpy(augment(Xp[b], rng, **aug))
            loss = Fn.cross_entropy(net(xb), yt[b], label_smoothing=0.1)
            opt.zero_grad(); loss.backward(); opt.step(); sch.step(); L += loss.item() * len(b)
        if verbose:
            msg = f"ep {ep} loss {L / len(y):.3f} {time.time() - t0:.1f}s"
            if Xval is not None and (ep % 5 == 4 or ep == epochs - 1):
                msg += f" val {(predict_proba(net, Xval).argmax(1) == yval).mean():.3f}"
            print(msg, flush=True)
    return net

@torch.no_grad()
def predict_proba(net, Xp, tta=False):
    net.eval(); P = []
    for k in range(0, len(Xp), 64):
        xb = torch.from_numpy(np.ascontiguousarray(Xp[k:k + 64]))
        p = Fn.softmax(net(xb), 1)
        if tta:
            p = p + Fn.softmax(net(xb.flip(2)), 1) + Fn.softmax(net(xb.flip(3)), 1) + Fn.softmax(net(xb.flip(2, 3)), 1)
            p = p / 4
        P.append(p.numpy())
    return np.vstack(P)
