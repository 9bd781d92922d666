"""Registered file formats: the files touchbench reads and writes datasets as.

An entry is a :class:`FileFormat`, declared once in the module that holds
its reader (``challenge_csv.py``, ``cost.py``, ``generic.py``,
``model.py``) with :func:`register_format`. ``touchbench data convert``,
``data export``, ``predict --format`` and ``stream --format`` take their
choices and their reader or writer from here; ``touchbench data formats``
lists them. Adding a format is adding a module that registers it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from ..core.errors import TouchbenchError
from ..core.introspect import accepts
from ..core.registry import Registry
from ..core.suggest import did_you_mean

__all__ = ["FORMATS", "FileFormat", "FormatOption", "OptionValueError", "check_frame_rate", "check_value_range", "parse_frame_rate",
           "parse_grid", "parse_value_range", "register_format"]

# Filled by every module of touchbench.datasets (imported on first use of the registry).
FORMATS: Registry = Registry("file format", package="touchbench.datasets")


@dataclass(frozen=True)
class FormatOption:
    """A setting the file cannot tell the reader, given on the command line as ``--NAME``.

    ``name`` is the reader's keyword (``frame_rate`` is ``--frame-rate``);
    ``parse`` turns the command-line text into its value and raises
    ``ValueError`` with the expected form when it cannot. A ``required``
    option must be given to ``data convert``; ``predict`` and ``stream`` take
    it from the model's sensor instead.
    """

    name: str
    help: str
    parse: Callable[[str], Any] = str
    metavar: str | None = None
    required: bool = False

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    @property
    def usage(self) -> str:
        return f"{self.flag} {self.metavar}" if self.metavar else self.flag


@dataclass(frozen=True)
class FileFormat:
    """A file format: its reader, its writer if any, and the options the reader takes.

    ``reader(path, name=..., **options)`` returns a
    :class:`touchbench.datasets.model.TouchDataset`; a reader that also takes
    ``like`` (a :class:`touchbench.datasets.model.SensorSpec`) fills what the
    file does not say from that sensor (``predict``: the model's).
    ``writer(dataset, out_dir)`` writes into a folder and returns the files.
    ``reads`` is ``"file"``, ``"folder"`` or ``"file or folder"``; ``replay``
    says whether ``stream`` can replay its captures frame by frame.
    """

    name: str
    description: str
    reader: Callable[..., Any]
    writer: Callable[[Any, Path], list[Path]] | None = None
    options: tuple[FormatOption, ...] = ()
    reads: str = "file"
    replay: bool = True

    def missing(self, values: dict[str, Any]) -> list[FormatOption]:
        """The required options that ``values`` lacks (``None`` counts as missing)."""
        return [o for o in self.options if o.required and values.get(o.name) is None]

    def option_problems(self, values: dict[str, Any]) -> dict[str, str]:
        """``option -> why`` for each of ``values`` (a protocol's ``options``, or Python's) that is not
        an option of the reader or not a value of it: a text or a number is read as the command line
        reads it (``0..255``, ``19x24``, ``54``), a boolean never; a list is left to the reader."""
        return self._read_options(values)[1]

    def _read_options(self, values: dict[str, Any]) -> tuple[dict[str, Any], dict[str, str]]:
        """``values`` as the reader takes them (text and numbers through their option's ``parse``),
        and ``option -> why`` for each that cannot be (:meth:`option_problems`)."""
        known = {o.name: o for o in self.options}
        read: dict[str, Any] = {}
        problems: dict[str, str] = {}
        for k, v in values.items():
            o = known.get(k)
            if o is None:
                problems[k] = (f"the {self.name} format takes no option {k!r}{did_you_mean(k, list(known))} "
                               f"(it takes: {', '.join(sorted(known)) or 'none'})")
            elif isinstance(v, bool):
                problems[k] = f"{o.flag} takes {o.metavar or 'a value'}, not a boolean"
            elif isinstance(v, (str, int, float)):
                try:
                    read[k] = o.parse(str(v))
                except ValueError as e:
                    problems[k] = str(e)
            else:
                read[k] = v
        return read, problems

    def read(self, path: str | Path, *, name: str | None = None, like: Any = None, **options: Any) -> Any:
        """Read ``path``; ``None`` options are left to the reader's defaults (or ``like``); a text or
        number option is read as the command line reads it (:meth:`option_problems`)."""
        kw, problems = self._read_options({k: v for k, v in options.items() if v is not None})
        if problems:
            raise OptionValueError(next(iter(problems.values())))
        if like is not None and accepts(self.reader, "like"):
            kw["like"] = like
        elif self.missing(kw):
            need = " and ".join(o.name for o in self.missing(kw))
            raise TouchbenchError(f"the {self.name} format needs {need}")
        if name is not None:
            kw["name"] = name
        return self.reader(path, **kw)

    def write(self, ds: Any, out_dir: str | Path) -> list[Path]:
        """Write ``ds`` into the folder ``out_dir``; the files written."""
        if self.writer is None:
            writable = ", ".join(e.name for e in FORMATS.entries() if e.obj.writer is not None)
            raise TouchbenchError(f"touchbench reads the {self.name} format but does not write it "
                                  f"(formats it writes: {writable})")
        return self.writer(ds, Path(out_dir))


def register_format(name: str, description: str, reader: Callable[..., Any], **fields: Any) -> FileFormat:
    """Declare a file format (the fields of :class:`FileFormat`) and register it."""
    fmt = FileFormat(name, description, reader, **fields)
    FORMATS.register(name, description=description)(fmt)
    return fmt


def parse_grid(text: str) -> tuple[int, int]:
    """``"HxW"`` (rows x columns, e.g. ``19x24``) -> ``(H, W)``: the one grid syntax of every option
    (``H,W`` is read too, as earlier versions wrote it)."""
    parts = str(text).strip().lower().replace(",", "x").split("x")
    try:
        h, w = (int(x) for x in parts)
    except ValueError:
        raise ValueError(f"expected HxW (rows x columns) such as 19x24, got {text!r}") from None
    if h < 1 or w < 1:
        raise ValueError(f"grid sides must be at least 1, got {text!r}")
    return h, w


class OptionValueError(TouchbenchError, ValueError):
    """A reader option's value that cannot be used, naming the option: a user-facing error from
    Python, and the ``ValueError`` a command-line option's ``parse`` raises."""


def check_frame_rate(rate: Any, option: str = "--frame-rate") -> float:
    """``rate`` as frames per second: a finite number above 0, or an error naming ``option``. The one
    check of a frame rate that every reader's option goes through (given as text or from Python)."""
    try:
        value = float(rate)
    except (TypeError, ValueError):
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise OptionValueError(f"{option} must be a finite number of frames per second above 0, got {rate!r}")
    return value


def check_value_range(lo: Any, hi: Any, option: str = "--value-range") -> tuple[float, float]:
    """``(lo, hi)`` as floats: both finite and ``lo < hi``, or an error naming ``option``. The one check
    of a value range that every reader's option goes through."""
    try:
        pair = (float(lo), float(hi))
    except (TypeError, ValueError):
        pair = (math.nan, math.nan)
    if not all(math.isfinite(v) for v in pair):
        raise OptionValueError(f"{option} must be two finite numbers LO..HI, got {lo!r}..{hi!r}")
    if not pair[0] < pair[1]:
        raise OptionValueError(f"{option}: the range's low end must be below its high end, got {lo!r}..{hi!r}")
    return pair


def parse_frame_rate(text: str) -> float:
    """Frames per second: a finite number above 0."""
    try:
        float(text)
    except ValueError:
        raise ValueError(f"expected frames per second, got {text!r}") from None
    return check_frame_rate(text)


#: a value range as written: two numbers, each with a digit before any dot (so ``0...255`` is no
#: range, rather than 0..0.255), between ``..`` or ``,``
_NUMBER = r"([-+]?(?:\d+(?:\.\d+)?(?:[eE][-+]?\d+)?|inf|infinity|nan))"  # inf, nan: refused as not finite
_RANGE = re.compile(rf"\s*{_NUMBER}\s*(?:\.\.|,)\s*{_NUMBER}\s*", re.IGNORECASE)
#: a value range of which the data use less than this share is refused (:func:`check_range_used`)
RANGE_USED_AT_LEAST = 1e-6


def parse_value_range(text: str, option: str = "--value-range") -> tuple[float, float]:
    """``"LO..HI"`` (or ``LO,HI``) -> ``(lo, hi)``: finite, ``lo < hi`` (an error naming ``option``);
    anything else (``0...255``, ``.5..1``) is refused (the command line names the option)."""
    m = _RANGE.fullmatch(str(text))
    if m is None:
        raise OptionValueError(f"expected LO..HI such as 0..4095 or -1.5..1.5 (two numbers, each with a digit "
                               f"before any dot, between '..'), got {text!r}")
    return check_value_range(float(m.group(1)), float(m.group(2)), option)


def check_range_used(data_lo: float, data_hi: float, value_range: tuple[float, float],
                     option: str = "--value-range") -> None:
    """Refuse a value range of which the data's values use a vanishing part (under
    :data:`RANGE_USED_AT_LEAST` of it): features scaled by the range would be constant. Data of
    one value throughout are not refused here (nothing tells their range)."""
    lo, hi = value_range
    used = (data_hi - data_lo) / (hi - lo)
    if 0 < used < RANGE_USED_AT_LEAST:
        raise OptionValueError(
            f"{option} {lo:g}..{hi:g}: the data's values span only {data_lo:g}..{data_hi:g}, {used:.2g} of that "
            "range, so the features scaled by it would be constant: give the sensor's own range (or leave "
            f"{option} out to infer it)")
