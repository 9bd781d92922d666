"""Protocols: the YAML schema (``schema``) and the evaluation schemes (``splits``)."""

from .schemes import SPLITTERS, Crop, Fold, SplitError, Splitter, make_splitter

__all__ = ["SPLITTERS", "Crop", "Fold", "SplitError", "Splitter", "make_splitter"]
