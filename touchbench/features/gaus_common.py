"""What the five Gaus et al. (2015, section 3.2) feature sets share:
the per-dataset presets, and how they scale to another sensor.

Section 3.2: "Parameters tuning is used to optimize their discriminative
power to the different recording settings used for the two dataset but not
between surfaces within the HAART dataset." So each set that the paper
tunes takes ``preset="haart"`` or ``preset="cost"`` (Tables 3 and 4 and
section 3.2.2), and every preset value can be overridden by an explicit
parameter (``None`` means "the preset's value").

Which values (``preset=None``, the default):

- a sensor with a preset's recording setting (HAART's: 8 x 8 cells, 54 Hz,
  values 0..1023, the HAART readers' sensor; CoST's: 8 x 8, 135 Hz,
  0..1023) gets that preset, as published;
- any other grid sensor gets **HAART's values scaled to it** by one rule,
  :class:`Setting`: a value counted in cells (``sd``'s histogram edges:
  Table 4's "bin widths and edges ... set to fit all instances" of an 8 x 8
  grid) is multiplied by ``cells / 64``, the sensor's cells over the
  preset's, so each bin covers the same fraction of the grid and the
  output keeps its length; a value in raw sensor units (``bmh``'s offset
  "maximum - 5", ``smmhh``'s motion threshold) is multiplied by the
  sensor's value range over the preset's (1023), i.e. kept as the same
  fraction of full scale. Frame counts (``smmhh``'s skips 2..6 and run
  lengths) are not scaled: the paper used the same skips at 54 Hz (HAART)
  and 135 Hz (CoST), so they are frames, not seconds. HAART's values are
  the base because its conditions are relative to each capture (minimum,
  median, maximum; section 3.2.1, Table 3), while CoST's add fixed
  thresholds of 100 found "by an analysis of the data" of that sensor;
- a channel sensor (``sensor.channels``: values of different quantities
  side by side, e.g. Flagg's x, y, pressure and fur) is refused: its
  channels are not cells of a pressure surface, so counting cells at a
  pressure level, a high-pressure shape or pooled pixels have no meaning
  there, and no scaling makes them one. Naming a preset or giving the
  values still uses them anyway;
- without a sensor (plain use from Python), a preset or the values must be
  given.

A named preset is always used as published (no scaling): that is how the
paper protocols reproduce the tables, and how a user asks for the paper's
numbers on another sensor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..datasets.cost import COST_SENSOR
from ..datasets.haart import HAART_SENSOR
from .base import FeatureInputError, SensorNeededError

#: the recording setting of each preset: a sensor with the same grid, frame
#: rate and value range gets that preset
PRESET_SENSORS = {"haart": HAART_SENSOR, "cost": COST_SENSOR}
#: the preset whose values are scaled to a sensor of neither recording setting
SCALED_BASE = "haart"

GAUS_PAPER = "Gaus et al. 2015 (ICMI), section 3.2"


@dataclass(frozen=True)
class Setting:
    """The preset whose values a set uses, and the factors that scale them to the sensor.

    ``cells`` multiplies values counted in grid cells, ``units`` values in
    raw sensor units; both are 1 for a preset used as published.
    """

    preset: str
    cells: float = 1.0
    units: float = 1.0

    @property
    def scaled(self) -> bool:
        return self.cells != 1.0 or self.units != 1.0


def _recording_setting(sensor: Any) -> tuple:
    return (tuple(sensor.grid), float(sensor.frame_rate), tuple(sensor.value_range))


def _span(value_range: Any) -> float:
    lo, hi = value_range
    return float(hi) - float(lo)


def setting_for(owner: str, preset: str | None, sensor: Any, values: str) -> Setting:
    """The values to use: ``preset`` as published if named, else the sensor's preset, else HAART's scaled.

    ``values`` names the parameters that replace a preset (for the message).
    Raises :class:`SensorNeededError` without a sensor and
    :class:`FeatureInputError` for a channel sensor (module docstring).
    """
    if preset is not None:
        return Setting(preset)
    if sensor is None:
        raise SensorNeededError(
            f"{owner}: the paper tunes its parameters per recording setting and no sensor was given: "
            f"pass sensor=SensorSpec(...) (its values are then HAART's scaled to it), set preset to 'haart' or 'cost', "
            f"or give {values}")
    for name, known in PRESET_SENSORS.items():
        if _recording_setting(sensor) == _recording_setting(known):
            return Setting(name)
    if sensor.channels is not None:
        raise FeatureInputError(
            f"{owner}: sensor {sensor.describe()} is a channel sensor ({', '.join(sensor.channels)}): its channels are "
            "not cells of a pressure surface, so the paper's cell counts, pressure shapes and pooled pixels have no "
            f"meaning on it and are not scaled; set preset to 'haart' or 'cost' to use their values anyway, or give {values}")
    base = PRESET_SENSORS[SCALED_BASE]
    return Setting(SCALED_BASE, cells=sensor.n_cells / base.n_cells,
                   units=_span(sensor.value_range) / _span(base.value_range))


def lookup(owner: str, table: dict[str, dict[str, Any]], setting: Setting, key: str) -> Any:
    """``table[setting.preset][key]``, unscaled; an unknown preset is one FeatureInputError."""
    if setting.preset not in table:
        raise FeatureInputError(f"{owner}: unknown preset {setting.preset!r} (known: {', '.join(sorted(table))})")
    return table[setting.preset][key]


def resolve_units(owner: str, preset: str | None, table: dict[str, dict[str, Any]], key: str, explicit: Any,
                  sensor: Any = None, values: str = "the values") -> Any:
    """``explicit`` if given, else the preset's value in raw sensor units, scaled by the setting's ``units``
    (a sequence is scaled value by value)."""
    if explicit is not None:
        return explicit
    setting = setting_for(owner, preset, sensor, values)
    value = lookup(owner, table, setting, key)
    if value is None or setting.units == 1.0:
        return value
    if isinstance(value, (list, tuple)):
        return type(value)(float(v) * setting.units for v in value)
    return float(value) * setting.units
