"""Fitted PyTorch state as numpy arrays, so that a fitted estimator saves as data.

A model file (:mod:`touchbench.deploy.safe_format`) holds numbers, strings
and objects of listed types only: no PyTorch tensor. The estimators that hold
torch state turn it into numpy arrays when they are saved (``__getstate__``)
and back when they are read (``__setstate__``):

- a network of our own (the CNN, InceptionTime) saves its weights
  (:func:`weights_as_arrays`) and is built again from its parameters, then
  given them (:func:`load_weights`);
- an aeon model that holds tensors (MultiRocket-Hydra, QUANT) saves a copy of
  its object graph whose tensors are :class:`TensorArray` and whose torch
  modules are :class:`ModuleState` (:func:`encode_torch`); :func:`decode_torch`
  makes tensors and modules of them again. A module is rebuilt as its class
  with torch's own empty module set up (``nn.Module.__init__``), then given
  its attributes: no method of the class runs.

Pickling (the run engine's workers, older model files) goes through the same
methods and gives back the same estimator.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["ModuleState", "TensorArray", "decode_torch", "encode_torch", "load_weights", "weights_as_arrays"]


def weights_as_arrays(net: Any) -> dict[str, np.ndarray]:
    """A network's ``state_dict`` as numpy arrays (copies, on the CPU)."""
    return {k: v.detach().cpu().numpy().copy() for k, v in net.state_dict().items()}


def load_weights(torch: Any, net: Any, weights: dict[str, Any]) -> Any:
    """Give ``net`` the ``weights`` (numpy arrays or tensors, by name) and return it in evaluation mode."""
    net.load_state_dict({k: torch.as_tensor(np.asarray(v)) if not isinstance(v, torch.Tensor) else v
                         for k, v in weights.items()})
    return net.eval()


class TensorArray:
    """A torch tensor as a numpy array (``parameter``: it was an ``nn.Parameter``)."""

    def __init__(self, array: np.ndarray, parameter: bool = False):
        self.array = array
        self.parameter = parameter


class ModuleState:
    """A torch module as its class and its attributes (torch's own bookkeeping left out)."""

    def __init__(self, cls: type, attrs: dict[str, Any]):
        self.cls = cls
        self.attrs = attrs


_MODULE_PARTS = ("_parameters", "_buffers", "_modules", "training")


def encode_torch(obj: Any, memo: dict[int, Any] | None = None) -> Any:
    """A copy of ``obj``'s graph of containers and plain objects whose tensors and modules are data."""
    memo = {} if memo is None else memo
    if id(obj) in memo:
        return memo[id(obj)]
    import torch

    out: Any
    if isinstance(obj, torch.Tensor):
        out = TensorArray(obj.detach().cpu().numpy().copy(), isinstance(obj, torch.nn.Parameter))
    elif isinstance(obj, torch.nn.Module):
        attrs = {k: v for k, v in vars(obj).items() if not k.startswith("_") or k in _MODULE_PARTS}
        out = ModuleState(type(obj), {})
        memo[id(obj)] = out
        out.attrs = {k: encode_torch(v, memo) for k, v in attrs.items()}
        return out
    elif isinstance(obj, (list, tuple)):
        out = type(obj)(encode_torch(v, memo) for v in obj)
    elif isinstance(obj, dict):
        out = {k: encode_torch(v, memo) for k, v in obj.items()}
    elif hasattr(obj, "__dict__") and not isinstance(obj, type) and _holds_torch(obj):
        out = object.__new__(type(obj))
        memo[id(obj)] = out
        out.__dict__.update({k: encode_torch(v, memo) for k, v in vars(obj).items()})
        return out
    else:
        out = obj
    memo[id(obj)] = out
    return out


def decode_torch(obj: Any, memo: dict[int, Any] | None = None) -> Any:
    """The inverse of :func:`encode_torch`: tensors and modules again."""
    memo = {} if memo is None else memo
    if id(obj) in memo:
        return memo[id(obj)]
    import torch

    out: Any
    if isinstance(obj, TensorArray):
        t = torch.as_tensor(np.asarray(obj.array))
        out = torch.nn.Parameter(t) if obj.parameter else t
    elif isinstance(obj, ModuleState):
        if not (isinstance(obj.cls, type) and issubclass(obj.cls, torch.nn.Module)):
            raise TypeError(f"{obj.cls!r} is not a torch module class")
        out = obj.cls.__new__(obj.cls)
        torch.nn.Module.__init__(out)
        memo[id(obj)] = out
        for k, v in obj.attrs.items():
            object.__setattr__(out, k, decode_torch(v, memo))
        return out
    elif isinstance(obj, (list, tuple)):
        out = type(obj)(decode_torch(v, memo) for v in obj)
    elif isinstance(obj, dict):
        out = {k: decode_torch(v, memo) for k, v in obj.items()}
    elif hasattr(obj, "__dict__") and not isinstance(obj, type) and _holds_torch(obj, (TensorArray, ModuleState)):
        memo[id(obj)] = obj
        obj.__dict__.update({k: decode_torch(v, memo) for k, v in vars(obj).items()})
        return obj
    else:
        out = obj
    memo[id(obj)] = out
    return out


def _holds_torch(obj: Any, kinds: tuple[type, ...] | None = None, depth: int = 0) -> bool:
    """Whether ``obj``'s attributes hold (``kinds``: by default torch tensors and modules), a few levels down."""
    if kinds is None:
        import torch

        kinds = (torch.Tensor, torch.nn.Module)
    if isinstance(obj, kinds):
        return True
    if depth > 6:
        return False
    if isinstance(obj, dict):
        values = list(obj.values())
    elif isinstance(obj, (list, tuple)):
        values = list(obj)
    elif hasattr(obj, "__dict__") and not isinstance(obj, type):
        values = list(vars(obj).values())
    else:
        return False
    return any(_holds_torch(v, kinds, depth + 1) for v in values)
