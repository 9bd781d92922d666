"""The pooled within-class covariance of a feature matrix and its condition number (float64).

LDA (Zhou et al. 2017's "Linear Discriminant", MATLAB ``fitcdiscr`` with a
full pooled covariance; ``zhou-lda``) inverts the pooled within-class
covariance ``S = sum_k sum_{i in k} (x_i - m_k)(x_i - m_k)^T / (n - K)``.
Its 2-norm condition number ``s_max / s_min`` (singular values) says how
far from singular that inverse is: about ``1e16`` and above, float64 cannot
tell the matrix from a singular one.

Limits: a matrix with a zero singular value (exactly singular, e.g. a
column constant within every class) has condition number ``inf``; so does
the zero matrix (numpy's ``linalg.cond`` gives NaN there: every direction
has zero spread, which is singular). With no more rows than classes
(``n <= K``) the divisor ``n - K`` is taken as 1 (the condition number does
not depend on it).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["condition_number", "pooled_within_class_covariance"]


def pooled_within_class_covariance(X, y) -> np.ndarray:
    """``S`` (module docstring) of the rows ``X`` (n x p) with labels ``y``, in float64."""
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2 or X.shape[0] == 0 or X.shape[1] == 0:
        raise ValueError(f"need a non-empty 2-d feature matrix, got shape {X.shape}")
    y = np.asarray(y)
    if y.shape != (X.shape[0],):
        raise ValueError(f"need one label per row: {X.shape[0]} rows, labels of shape {y.shape}")
    classes, codes = np.unique(y, return_inverse=True)
    means = np.zeros((len(classes), X.shape[1]))
    np.add.at(means, codes, X)
    means /= np.bincount(codes)[:, None]
    centred = X - means[codes]
    return centred.T @ centred / max(X.shape[0] - len(classes), 1)


def condition_number(C) -> float:
    """The 2-norm condition number of the square matrix ``C``: ``inf`` when it is singular (module
    docstring), else the ratio of its largest to its smallest singular value."""
    C = np.asarray(C, dtype=np.float64)
    if C.ndim != 2 or C.shape[0] != C.shape[1] or C.shape[0] == 0:
        raise ValueError(f"need a non-empty square matrix, got shape {C.shape}")
    s = np.linalg.svd(C, compute_uv=False)
    return math.inf if s[-1] == 0.0 else float(s[0] / s[-1])
