"""Figures of leaderboards, one module per figure kind, in one registry (``FIGURES``).

Each module of this package but :mod:`.base` draws one kind and registers
it (see :mod:`.base` for the calling convention); `touchbench plot --kind`
offers the registered names. :func:`plot_table` draws every kind that
applies to a table; :func:`.cd.plot_cd_across` draws a critical difference
diagram across tables.
"""

from .base import FIGURES, FORMATS, MIN_FONT_PT, SIZES, FigureOptions, plot_table, slug, unique_stem

__all__ = ["FIGURES", "FORMATS", "MIN_FONT_PT", "SIZES", "FigureOptions", "plot_table", "slug", "unique_stem"]
