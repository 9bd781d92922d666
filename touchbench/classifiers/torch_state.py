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


_PASS = object()  # a converter's answer for an object that is no tensor, module or holder of them


def encode_torch(obj: Any, memo: dict[int, Any] | None = None) -> Any:
    """A copy of ``obj``'s graph of containers and plain objects whose tensors and modules are data."""
    import torch

    def convert(o: Any, memo: dict[int, Any]) -> Any:
        if isinstance(o, torch.Tensor):
            return TensorArray(o.detach().cpu().numpy().copy(), isinstance(o, torch.nn.Parameter))
        if isinstance(o, torch.nn.Module):
            out = memo[id(o)] = ModuleState(type(o), {})
            out.attrs = {k: _walk(v, memo, convert) for k, v in vars(o).items()
                         if not k.startswith("_") or k in _MODULE_PARTS}
            return out
        if hasattr(o, "__dict__") and not isinstance(o, type) and _holds_torch(o, (torch.Tensor, torch.nn.Module)):
            out = memo[id(o)] = object.__new__(type(o))
            out.__dict__.update({k: _walk(v, memo, convert) for k, v in vars(o).items()})
            return out
        return _PASS

    return _walk(obj, {} if memo is None else memo, convert)


def decode_torch(obj: Any, memo: dict[int, Any] | None = None) -> Any:
    """The inverse of :func:`encode_torch`: tensors and modules again."""
    import torch

    def convert(o: Any, memo: dict[int, Any]) -> Any:
        if isinstance(o, TensorArray):
            t = torch.as_tensor(np.asarray(o.array))
            return torch.nn.Parameter(t) if o.parameter else t
        if isinstance(o, ModuleState):
            if not (isinstance(o.cls, type) and issubclass(o.cls, torch.nn.Module)):
                raise TypeError(f"{o.cls!r} is not a torch module class")
            out = memo[id(o)] = o.cls.__new__(o.cls)
            torch.nn.Module.__init__(out)
            for k, v in o.attrs.items():
                object.__setattr__(out, k, _walk(v, memo, convert))
            return out
        if hasattr(o, "__dict__") and not isinstance(o, type) and _holds_torch(o, (TensorArray, ModuleState)):
            memo[id(o)] = o
            o.__dict__.update({k: _walk(v, memo, convert) for k, v in vars(o).items()})
            return o
        return _PASS

    return _walk(obj, {} if memo is None else memo, convert)


def _walk(obj: Any, memo: dict[int, Any], convert: Any) -> Any:
    """``obj`` with ``convert`` applied through lists, tuples and dicts (each object once)."""
    if id(obj) in memo:
        return memo[id(obj)]
    out = convert(obj, memo)
    if out is _PASS:
        if isinstance(obj, (list, tuple)):
            out = type(obj)(_walk(v, memo, convert) for v in obj)
        elif isinstance(obj, dict):
            out = {k: _walk(v, memo, convert) for k, v in obj.items()}
        else:
            out = obj
    memo[id(obj)] = out
    return out


def _holds_torch(obj: Any, kinds: tuple[type, ...], depth: int = 0) -> bool:
    """Whether ``obj`` or what it holds, a few levels down, is one of ``kinds``."""
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
