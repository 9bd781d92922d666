"""The one error type users see: a message that names the file, line or field."""

from __future__ import annotations

from pathlib import Path


class TouchbenchError(Exception):
    """A user-facing error. The CLI prints ``str(err)`` and exits with status 2."""


class DataError(TouchbenchError):
    """Bad input data: names the file and, where known, the line."""

    def __init__(self, message: str, path: str | Path | None = None, line: int | None = None):
        self.path = None if path is None else str(path)
        self.line = line
        where = ""
        if self.path is not None:
            where = self.path + (f":{line}" if line is not None else "") + ": "
        super().__init__(where + message)


class UnknownNameError(TouchbenchError, KeyError):
    """A name that no registry holds, with the nearest names as suggestions."""

    def __str__(self) -> str:  # KeyError would repr() the message
        return str(self.args[0])


class RegistrationError(TouchbenchError, ValueError):
    """An entry a registry refuses: a name registered twice, a tag declared twice."""
