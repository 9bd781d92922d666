"""Adapters: bring another study's captures to the sensor a model was trained on.

A cross-dataset evaluation trains on one dataset and tests on another. When
the two sensors differ (a larger grid, another frame rate, another ADC
range), the test data is refused unless the protocol declares how to bring
it to the training sensor; each declared step is applied in order and
recorded in the run's notes, and whatever still differs afterwards is
refused, naming both sensors.

Steps (a list of one-key mappings, YAML ``adapters: [{crop: {top: 1, left: 1}},
{resample: linear}, {rescale: linear}]``):

- ``crop: {top: R, left: C}``: keep the training grid's ``H x W`` cells
  starting at row ``R``, column ``C`` (a window that does not fit is
  refused);
- ``resample: linear``: linear interpolation of every cell in time from the
  data's frame rate to the training one (``scipy.interpolate.interp1d``),
  ``round(T * target / source)`` frames (at least one); recorded frame times
  are dropped (the new frames are evenly spaced);
- ``rescale: linear``: the data's value range mapped linearly onto the
  training range, the polarity turned when it differs (float64 values).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.interpolate import interp1d

from ..core.errors import TouchbenchError
from .model import RECORDED_TIME_COLUMN, TIME_COLUMN, SensorSpec, TouchDataset, sensor_differences

__all__ = ["ADAPTERS", "AdapterError", "adapt"]

ADAPTERS = ("crop", "resample", "rescale")


class AdapterError(TouchbenchError):
    """An adapter that cannot be applied, or a sensor that still differs after the adapters."""


def _crop(ds: TouchDataset, to: SensorSpec, arg: Any, where: str) -> tuple[TouchDataset, str]:
    if not isinstance(arg, dict) or set(arg) - {"top", "left"}:
        raise AdapterError(f"{where}: crop takes {{top: ROW, left: COLUMN}}, got {arg!r}")
    top, left = int(arg.get("top", 0)), int(arg.get("left", 0))
    (h, w), (H, W) = to.grid, ds.sensor.grid
    if top < 0 or left < 0 or top + h > H or left + w > W:
        raise AdapterError(f"{where}: a {h} x {w} window at row {top}, column {left} does not fit the data's {H} x {W} grid")
    caps = [c[:, top:top + h, left:left + w] for c in ds.captures]
    sensor = SensorSpec(ds.sensor.name, (h, w), ds.sensor.frame_rate, ds.sensor.value_range,
                        ds.sensor.higher_is_more_pressure)
    return (TouchDataset(ds.name, caps, ds.meta, sensor, provenance=ds.provenance),
            f"cropped {H} x {W} to {h} x {w} at row {top}, column {left}")


def _resample(ds: TouchDataset, to: SensorSpec, arg: Any, where: str) -> tuple[TouchDataset, str]:
    if arg not in ("linear", True):
        raise AdapterError(f"{where}: resample takes 'linear', got {arg!r}")
    src, dst = float(ds.sensor.frame_rate), float(to.frame_rate)
    caps = []
    for c in ds.captures:
        t = c.shape[0]
        n = max(1, int(round(t * dst / src)))
        if t == 1:
            caps.append(np.repeat(np.asarray(c, dtype=np.float64), n, axis=0))
            continue
        f = interp1d(np.arange(t) / src, np.asarray(c, dtype=np.float64), axis=0, kind="linear",
                     bounds_error=False, fill_value=(c[0], c[-1]), assume_sorted=True)
        caps.append(f(np.arange(n) / dst))
    meta = ds.meta.drop(columns=[k for k in (TIME_COLUMN, RECORDED_TIME_COLUMN) if k in ds.meta.columns])
    sensor = SensorSpec(ds.sensor.name, ds.sensor.grid, dst, ds.sensor.value_range, ds.sensor.higher_is_more_pressure,
                        ds.sensor.channels)
    return (TouchDataset(ds.name, caps, meta, sensor, provenance=ds.provenance),
            f"resampled from {src:g} Hz to {dst:g} Hz (linear)")


def _rescale(ds: TouchDataset, to: SensorSpec, arg: Any, where: str) -> tuple[TouchDataset, str]:
    if arg not in ("linear", True):
        raise AdapterError(f"{where}: rescale takes 'linear', got {arg!r}")
    lo, hi = ds.sensor.value_range
    tlo, thi = to.value_range
    flip = ds.sensor.higher_is_more_pressure != to.higher_is_more_pressure
    scale = (thi - tlo) / (hi - lo)
    caps = [(thi - (np.asarray(c, dtype=np.float64) - lo) * scale) if flip
            else (tlo + (np.asarray(c, dtype=np.float64) - lo) * scale) for c in ds.captures]
    sensor = SensorSpec(ds.sensor.name, ds.sensor.grid, ds.sensor.frame_rate, to.value_range,
                        to.higher_is_more_pressure, ds.sensor.channels)
    return (TouchDataset(ds.name, caps, ds.meta, sensor, provenance=ds.provenance),
            f"values rescaled from {lo:g}..{hi:g} to {tlo:g}..{thi:g}" + (" (polarity turned)" if flip else ""))


_STEPS = {"crop": _crop, "resample": _resample, "rescale": _rescale}


def adapt(ds: TouchDataset, to: SensorSpec, steps: list[dict[str, Any]], where: str = "adapters"
          ) -> tuple[TouchDataset, list[str]]:
    """``ds`` brought to sensor ``to`` by ``steps`` (in order), and one note per step; a sensor
    that still differs after them is refused, naming both sensors and what differs."""
    notes = []
    for i, step in enumerate(steps):
        at = f"{where}[{i}]"
        if not isinstance(step, dict) or len(step) != 1 or next(iter(step)) not in _STEPS:
            raise AdapterError(f"{at}: an adapter is one of {', '.join(ADAPTERS)} with its argument "
                               f"(e.g. {{resample: linear}}), got {step!r}")
        (name, arg), = step.items()
        ds, note = _STEPS[name](ds, to, arg, at)
        notes.append(f"test data {note}")
    diffs = sensor_differences(to, ds.sensor, ("training", "test"))
    if diffs:
        raise AdapterError(f"the test data's sensor {ds.sensor.describe()} differs from the training sensor "
                           f"{to.describe()} ({'; '.join(diffs)}): declare adapters "
                           f"({', '.join(ADAPTERS)}) to bring it to the training sensor")
    final = TouchDataset(ds.name, ds.captures, ds.meta, SensorSpec(to.name, to.grid, to.frame_rate, to.value_range,
                                                                 to.higher_is_more_pressure, to.channels),
                         provenance=ds.provenance)
    return final, notes
