import numpy as np

def summary_series(X):
    """(N, T, H, W) -> (N, C, T) frame-level series for convolution models."""
    N, T, H, W = X.shape
    C = X.reshape(N, T, H * W)
    base = np.percentile(C, 5, axis=1)
    S = np.clip(C - base[:, None, :], 0, None)
    Ps = S.sum(2)
    yy, xx = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    yy = yy.ravel().astype(float); xx = xx.ravel().astype(float)
    w = S + 1e-9; ws = w.sum(2)
    cy = (w * yy).sum(2) / ws; cx = (w * xx).sum(2) / ws
    sy = np.sqrt(np.maximum((w * yy ** 2).sum(2) / ws - cy ** 2, 0))
    sx = np.sqrt(np.maximum((w * xx ** 2).sum(2) / ws - cx ** 2, 0))
    M = S.max(2)
    A = (S > np.maximum(0.2 * S.max(axis=(1, 2)), 3.0)[:, None, None]).sum(2).astype(float)
    mean_level = Ps.mean(1, keepdims=True) + 1e-9
    out = np.stack([np.log1p(Ps), Ps / mean_level, np.log1p(M), A, cy, cx, sy, sx,
                    np.gradient(cy, axis=1), np.gradient(cx, axis=1)], axis=1)
    return out

def cells_log(X):
    N, T, H, W = X.shape
    C = X.reshape(N, T, H * W)
    base = np.percentile(C, 5, axis=1)
    return np.log1p(np.clip(C - base[:, None, :], 0, None)).transpose(0, 2, 1)
