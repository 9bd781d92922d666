"""Small introspection helpers: does a callable take a given parameter?"""

from __future__ import annotations

import inspect
from typing import Any

__all__ = ["accepts", "sensor_problem", "with_accepted"]


def accepts(fn: Any, name: str) -> bool:
    """Whether ``fn`` (a function, class or bound method) takes a parameter ``name``."""
    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


def with_accepted(fn: Any, params: dict[str, Any], **extra: Any) -> dict[str, Any]:
    """``params`` plus each ``extra`` value that is not None and that ``fn`` takes.

    The one rule by which the engine hands a component what it knows about
    the data (the dataset's sensor): a feature set or classifier that takes
    ``sensor`` gets it, one that does not is built as before.
    """
    out = dict(params)
    for name, value in extra.items():
        if value is not None and accepts(fn, name):
            out[name] = value
    return out


def sensor_problem(component: Any, sensor: Any, min_frames: int | None = None) -> str | None:
    """Why ``component`` (a feature set or estimator) cannot serve ``sensor``, or None.

    Asks the component's ``check_sensor(sensor, min_frames=...)`` when it has
    one (``min_frames``: the shortest capture it will see); a component
    without one serves every sensor.
    """
    check = getattr(component, "check_sensor", None)
    return check(sensor, min_frames=min_frames) if callable(check) else None
