"""The one error type users see: a message that names the file, line or field."""

from __future__ import annotations

import errno
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


class WriteError(TouchbenchError, OSError):
    """A file touchbench could not write (permissions, a read-only or full disk, a folder where
    the file should be), naming the file, what could not be done (``action``, "cannot write" by
    default) and why; the writer left nothing half-written."""

    _REASONS = {
        "EACCES": "permission denied: the folder is not writable for you (choose another output folder)",
        "EPERM": "permission denied: the folder is not writable for you (choose another output folder)",
        "EROFS": "the file system is read-only (choose another output folder)",
        "ENOSPC": "no space left on the device (free some space and run again; finished work is kept)",
        "EDQUOT": "disk quota exceeded (free some space and run again; finished work is kept)",
        "EISDIR": "it is a folder, not a file (rename or remove that folder)",
    }

    def __init__(self, path: str | Path, error: OSError, action: str = "cannot write"):
        self.path = str(path)
        name = errno.errorcode.get(error.errno or 0, "")
        reason = self._REASONS.get(name) or error.strerror or str(error)
        TouchbenchError.__init__(self, f"{self.path}: {action}: {reason}")
