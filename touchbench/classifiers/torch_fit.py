"""Training a PyTorch network the same way for every deep classifier.

PyTorch is imported lazily (``import_torch``), so the rest of touchbench
works without it. Shared by the CNN of Al-mashhadani et al. 2021
(``cnn.py``) and InceptionTime (``inception.py``):

- ``Threads``: torch's thread count and deterministic mode for a block,
  restored afterwards.
- ``validation_split``: the captures held out for early stopping, drawn
  only from the training data (whole ``groups`` when given, else a
  stratified share of every class).
- ``train``: mini-batch Adam over the rows in an order drawn from a numpy
  generator, keeping the weights of the epoch with the lowest monitored
  loss (the validation loss when a validation set is given, with early
  stopping after ``patience`` epochs without improvement; else the
  training loss, as Keras' ``ModelCheckpoint(monitor="loss")``), with an
  optional halving of the learning rate on a plateau of that loss (Keras'
  ``ReduceLROnPlateau``). Given a ``score`` (a function of the network, e.g.
  its accuracy on some labelled rows), the epoch with the highest score is
  kept instead (the first of equal ones), and ``patience`` counts epochs
  without a higher one: the leakage audit's early stopping on the test
  subject (``cnn`` with ``test_set``).

On the CPU a given seed and thread count give bit-identical weights.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass
from numbers import Integral

import numpy as np
from sklearn.utils._param_validation import Interval, Options

from ..core.errors import TouchbenchError

INSTALL_HINT = "pip install 'touchbench[deep]'  (or: pip install torch)"


def import_torch(who: str):
    """Import PyTorch or raise a TouchbenchError naming ``who`` and the install command."""
    try:
        import torch
    except ImportError as e:
        raise TouchbenchError(f"the {who!r} classifier needs PyTorch, which is not installed: {INSTALL_HINT}") from e
    return torch


#: the declared domain of a torch classifier's ``n_jobs`` (:class:`Threads`): -1 or None for every core, else at least 1
TORCH_JOBS = [Interval(Integral, 1, None, closed="left"), Options(Integral, {-1}), None]


class Threads:
    """Set torch's thread count and deterministic mode for a block, then restore."""

    def __init__(self, torch, n_jobs):
        self.torch = torch
        self.n = (os.cpu_count() or 1) if n_jobs in (None, -1) else max(int(n_jobs), 1)

    def __enter__(self):
        t = self.torch
        self.prev_threads = t.get_num_threads()
        self.prev_det = t.are_deterministic_algorithms_enabled()
        t.set_num_threads(self.n)
        t.use_deterministic_algorithms(True)
        return self

    def __exit__(self, *exc):
        self.torch.set_num_threads(self.prev_threads)
        self.torch.use_deterministic_algorithms(self.prev_det)
        return False


def validation_split(yi: np.ndarray, groups, rng: np.random.Generator, fraction: float | None):
    """``(fit rows, validation rows, validation groups or None)`` of ``len(yi)`` training captures.

    With ``groups`` (e.g. subjects) of at least two values, whole groups are
    held out (``round(fraction * groups)``, at least one, never all);
    otherwise ``round(fraction * members)`` of every class, keeping at least
    one training capture per class. ``fraction`` 0 or None, or fewer than 4
    captures: no validation rows.
    """
    n = len(yi)
    rows = np.arange(n)
    frac = fraction or 0.0
    if frac <= 0 or n < 4:
        return rows, rows[:0], None
    if groups is not None:
        g = np.asarray(groups)
        if len(g) != n:
            raise ValueError(f"groups has {len(g)} entries for {n} captures")
        uniq = np.unique(g)
        if len(uniq) >= 2:
            n_val = min(max(1, int(round(frac * len(uniq)))), len(uniq) - 1)
            val_groups = rng.permutation(uniq)[:n_val]
            val = np.isin(g, val_groups)
            return rows[~val], rows[val], sorted(val_groups.tolist())
    val = []
    for c in np.unique(yi):
        members = rng.permutation(rows[yi == c])
        k = int(round(frac * len(members)))
        if len(members) - k >= 1 and k >= 1:
            val.extend(members[:k].tolist())
    if not val:
        return rows, rows[:0], None
    val = np.sort(np.asarray(val))
    return np.setdiff1d(rows, val), val, None


@dataclass
class Plateau:
    """Halve (``factor``) the learning rate after ``patience`` epochs without a lower monitored loss, down to ``min_lr``."""

    factor: float = 0.5
    patience: int = 50
    min_lr: float = 1e-4


def train(torch, net, opt, xt, yt, rng: np.random.Generator, *, max_epochs: int, batch_size: int,
          xv=None, yv=None, patience: int | None = None, plateau: Plateau | None = None, verbose: int = 0,
          score=None):
    """Train ``net`` in place (see the module docstring); returns ``(history, best_epoch)``.

    ``history`` holds one ``{"epoch", "train_loss"[, "val_loss"][, "score"], "lr"}`` per
    epoch. The best weights are restored before returning.
    """
    loss_fn = torch.nn.CrossEntropyLoss()
    validate = xv is not None and len(xv) > 0
    scheduler = None
    if plateau is not None:
        scheduler = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, mode="min", factor=plateau.factor,
                                                               patience=plateau.patience, min_lr=plateau.min_lr)
    best_loss, best_state, best_epoch, stale = np.inf, None, 0, 0
    history = []
    bs = max(int(batch_size), 1)
    for epoch in range(1, int(max_epochs) + 1):
        net.train()
        perm = torch.from_numpy(rng.permutation(len(yt))).to(xt.device)
        total = 0.0
        for start in range(0, len(perm), bs):
            b = perm[start:start + bs]
            opt.zero_grad()
            loss = loss_fn(net(xt[b]), yt[b])
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(b)
        rec = {"epoch": epoch, "train_loss": total / max(len(yt), 1), "lr": float(opt.param_groups[0]["lr"])}
        monitored = rec["train_loss"]
        if validate:
            net.eval()
            with torch.no_grad():
                monitored = rec["val_loss"] = float(loss_fn(net(xv), yv))
        if score is not None:
            net.eval()
            rec["score"] = float(score(net))
            monitored = -rec["score"]  # the highest score is the lowest monitored value
        if validate or plateau is not None or score is not None:
            if monitored < best_loss:
                best_loss, best_epoch, stale = monitored, epoch, 0
                best_state = copy.deepcopy(net.state_dict())
            else:
                stale += 1
        if scheduler is not None:
            scheduler.step(monitored)
        history.append(rec)
        if verbose:
            print(rec, flush=True)
        if (validate or score is not None) and patience is not None and stale >= int(patience):
            break
    if best_state is not None:
        net.load_state_dict(best_state)
    else:
        best_epoch = len(history)
    net.eval()
    return history, best_epoch


def softmax_batches(torch, net, x, n_classes: int, batch: int = 1024) -> np.ndarray:
    """``net``'s softmax over ``x`` in batches, float64 ``(n, n_classes)``."""
    out = []
    with torch.no_grad():
        for start in range(0, len(x), batch):
            out.append(torch.softmax(net(x[start:start + batch]), dim=1).double().numpy())
    return np.concatenate(out) if out else np.zeros((0, n_classes))
