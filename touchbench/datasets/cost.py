"""The Corpus of Social Touch (CoST) release file ``CoST.csv``.

Format as ../shared/docs/cost-format.md records it (Jung et al.; used by
Gaus et al. 2015, section 2): header ``subject, variant, gesture,
frame, ch1..ch64`` (names may carry leading spaces); one row per frame; a
capture is a run of rows with the same subject, variant and gesture whose
frame counter climbs from 1; the same key occurs six times in a row (the
repetitions). 8 x 8 at 135 Hz, values 0..1023, higher = more pressure.

Channel order: the 64 values are reshaped to 8 x 8 row-major, transposed,
and flipped top-to-bottom, as one public MATLAB reader does (the only
documented mapping; stated in cost-format.md). Captures keep their own length
(10 to ~1750 frames); lost captures are simply absent, so a key may have
fewer than six repetitions. Subjects become ``s01``..``s31``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..core.errors import DataError
from .formats import register_format
from .model import SensorSpec, TouchDataset
from .tables import find_column, numeric, read_table, runs

COST_SENSOR = SensorSpec(name="cost", grid=(8, 8), frame_rate=135.0, value_range=(0.0, 1023.0))
VARIANTS = {1: "gentle", 2: "normal", 3: "rough"}
GESTURES = {
    1: "grab", 2: "hit", 3: "massage", 4: "pat", 5: "pinch", 6: "poke", 7: "press",
    8: "rub", 9: "scratch", 10: "slap", 11: "squeeze", 12: "stroke", 13: "tap", 14: "tickle",
}


def channels_to_grid(values: np.ndarray) -> np.ndarray:
    """``(T, 64)`` channel values -> ``(T, 8, 8)`` frames (cost-format.md)."""
    return values.reshape(-1, 8, 8).transpose(0, 2, 1)[:, ::-1, :]


def read_cost_csv(path: str | Path, name: str = "cost") -> TouchDataset:
    path = Path(path)
    df = read_table(path)
    cols = {k: find_column(df, (k,), path, k) for k in ("subject", "variant", "gesture", "frame")}
    chans = [find_column(df, (f"ch{i}",), path, f"ch{i}") for i in range(1, 65)]
    codes = numeric(df, [cols["subject"], cols["variant"], cols["gesture"]], path, lo=1, integer=True).astype(np.int64)
    for j, (label, table) in enumerate((("variant", VARIANTS), ("gesture", GESTURES)), start=1):
        bad = ~np.isin(codes[:, j], list(table))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise DataError(f"unknown {label} code {codes[i, j]} (known: {sorted(table)})", path, i + 2)
    frame = numeric(df, [cols["frame"]], path, lo=1, integer=True)[:, 0]
    values = numeric(df, chans, path, lo=0, hi=1023, integer=True)
    bounds = runs(pd.DataFrame(codes), frame, path, "frame")
    captures, rows, rep = [], [], {}
    for a, b in bounds:
        subj, var, ges = (int(x) for x in codes[a])
        key = (subj, var, ges)
        rep[key] = rep.get(key, 0) + 1
        subject, variant, gesture = f"s{subj:02d}", VARIANTS[var], GESTURES[ges]
        captures.append(np.ascontiguousarray(channels_to_grid(values[a:b])).astype(np.uint16))
        rows.append({
            "capture_id": f"{subject}-{variant}-{gesture}-{rep[key]}", "subject": subject, "gesture": gesture,
            "variant": variant, "repetition": rep[key], "split": "none",
        })
    return TouchDataset(name, captures, pd.DataFrame(rows), COST_SENSOR)


register_format("cost-csv", "the Corpus of Social Touch release file CoST.csv (8 x 8 at 135 Hz)", read_cost_csv)
