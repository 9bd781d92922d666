"""What the five Gaus et al. (2015, section 3.2) feature sets share:
the per-dataset presets.

Section 3.2: "Parameters tuning is used to optimize their discriminative
power to the different recording settings used for the two dataset but not
between surfaces within the HAART dataset." So each set that the paper
tunes takes ``preset="haart"`` or ``preset="cost"`` (Tables 3 and 4 and
section 3.2.2), and every preset value can be overridden by an explicit
parameter (``None`` means "the preset's value").

Which preset (``preset=None``, the default): the paper's rule is "one
setting per recording setting", so the preset is the one whose recording
setting the sensor has: HAART's (8 x 8 cells, 54 Hz, values 0..1023, the
HAART readers' sensor) gives ``"haart"``, CoST's (8 x 8, 135 Hz, 0..1023)
gives ``"cost"``. The paper gives no values for any other sensor, so none
is picked for it: the set refuses, saying to name a preset (to use its
values anyway) or to give the values. Without a sensor (plain use from
Python) a preset or the values must be given.
"""

from __future__ import annotations

from typing import Any

from ..datasets.cost import COST_SENSOR
from ..datasets.haart import HAART_SENSOR
from .base import FeatureInputError, SensorNeededError

#: the recording setting of each preset: a sensor with the same grid, frame
#: rate and value range gets that preset
PRESET_SENSORS = {"haart": HAART_SENSOR, "cost": COST_SENSOR}


def _setting(sensor: Any) -> tuple:
    return (tuple(sensor.grid), float(sensor.frame_rate), tuple(sensor.value_range))


def preset_for(owner: str, preset: str | None, sensor: Any, values: str) -> str:
    """The preset to use: ``preset`` if named, else the one whose recording setting ``sensor`` has.

    ``values`` names the parameters that replace a preset (for the message).
    Raises FeatureInputError when there is no sensor or it matches no preset.
    """
    if preset is not None:
        return preset
    if sensor is not None:
        for name, known in PRESET_SENSORS.items():
            if _setting(sensor) == _setting(known):
                return name
    known = "; ".join(f"{n}: {s.grid[0]} x {s.grid[1]} at {s.frame_rate:g} Hz, values {s.value_range[0]:g}..{s.value_range[1]:g}"
                      for n, s in PRESET_SENSORS.items())
    what = f"sensor {sensor.describe()} has neither recording setting" if sensor is not None else "no sensor was given"
    raise (FeatureInputError if sensor is not None else SensorNeededError)(
        f"{owner}: the paper tunes its parameters per recording setting ({known}) and {what}: "
        f"set preset to 'haart' or 'cost' to use their values anyway, or give {values}"
    )

GAUS_PAPER = "Gaus et al. 2015 (ICMI), section 3.2"


def resolve(owner: str, preset: str | None, table: dict[str, dict[str, Any]], key: str, explicit: Any,
            sensor: Any = None, values: str = "the values") -> Any:
    """``explicit`` if given, else ``table[preset][key]`` with the preset from :func:`preset_for`;
    unknown preset -> FeatureInputError."""
    if explicit is not None:
        return explicit
    preset = preset_for(owner, preset, sensor, values)
    if preset not in table:
        raise FeatureInputError(f"{owner}: unknown preset {preset!r} (known: {', '.join(sorted(table))})")
    return table[preset][key]
