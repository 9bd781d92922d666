"""Results: atomic Parquet fragments per task merged into reports, the manifest, summaries."""

from .store import ResultStore
from .summary import check_expected, summarize

__all__ = ["ResultStore", "check_expected", "summarize"]
