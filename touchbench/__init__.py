"""touchbench: benchmarking social touch gesture recognition."""

__version__ = "0.1.0"
