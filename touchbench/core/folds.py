"""What a scheme attaches to its folds beyond the train/test indices: the interface the engine reads.

A fold (:class:`touchbench.protocols.schemes.base.Fold`) carries its scheme's extras (the ``early``
scheme's crop, a data curve's point, a stream fold's settings and streams), each an instance of a
:class:`FoldExtra` subclass that its scheme owns. The engine asks a fold through the fold's methods and
these only, never by a scheme's field names; a kind of task that needs its extra whole (a stream
fold's replays) asks the fold for the extra of its type (``Fold.extra``). The class lives here, below every layer
that defines an extra (the stream settings are the ``streams`` layer's).
"""

from __future__ import annotations

from typing import Any

__all__ = ["FoldExtra"]


class FoldExtra:
    """The default: nothing added to the task identity."""

    def identity(self) -> dict[str, Any]:
        """What the fold's results depend on beyond its indices, entries of its tasks' identities."""
        return {}
