"""touchbench's version: the bottom layer holds it, so every layer may read it."""

__version__ = "0.1.0"
