"""Write the small example files of docs/data-formats.md (run from anywhere; seeded, so the files
are the same on every run): ``python docs/formats/make_examples.py``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent


def my_skin(rng: np.random.Generator) -> pd.DataFrame:
    """A 6 x 6 skin at about 20 Hz, values 0..255: 3 people x (pat, stroke) x 4 captures of 1.5 s,
    one row per frame, a time column in ms with the jitter and a dropped frame a real logger has."""
    rows = []
    for person in ("p1", "p2", "p3"):
        for gesture, hz in (("pat", 4.0), ("stroke", 1.0)):
            for rep in range(4):
                cells = rng.uniform(size=(6, 6)) > 0.5          # the part of the skin the hand covers
                t_ms, n = 0, 0
                while n < 30:
                    touch = 0.5 + 0.5 * np.sin(2 * np.pi * hz * t_ms / 1000.0)   # a pat is faster than a stroke
                    frame = rng.uniform(0, 10, (6, 6)) + 200 * touch * cells
                    rows.append({"take": f"{person}-{gesture}-{rep}", "person": person, "gesture": gesture,
                                 "time_ms": t_ms,
                                 **{f"r{r}c{c}": int(v) for (r, c), v in np.ndenumerate(np.clip(frame, 0, 255))}})
                    t_ms += 50 + int(rng.integers(-3, 4)) + (50 if rng.uniform() < 0.03 else 0)
                    n += 1
    return pd.DataFrame(rows)


def skin_sessions(rng: np.random.Generator) -> pd.DataFrame:
    """Continuous sessions labelled frame by frame, for a stream evaluation: the 6 x 6 skin at 20 Hz,
    3 people, each one recording of 12 gestures (pat, stroke, press in turn, each 2-4 s) with 2-4 s
    of rest (``idle``) before each and after the last; a ``label`` column per frame."""
    rows = []
    kinds = {"pat": 4.0, "stroke": 1.0, "press": 0.0}
    for person in ("p1", "p2", "p3"):
        f = 0
        plan = [("idle", rng.uniform(2, 4))]
        for k in range(12):
            plan += [(("pat", "stroke", "press")[k % 3], rng.uniform(2, 4)), ("idle", rng.uniform(2, 4))]
        for label, seconds in plan:
            cells = rng.uniform(size=(6, 6)) > 0.5
            for i in range(int(round(seconds * 20))):
                touch = 0.0 if label == "idle" else (1.0 if label == "press" else
                                                     0.5 + 0.5 * np.sin(2 * np.pi * kinds[label] * i / 20))
                frame = rng.uniform(0, 10, (6, 6)) + 200 * touch * cells
                rows.append({"session": f"{person}-s1", "person": person, "frame": f, "label": label,
                             **{f"r{r}c{c}": int(v) for (r, c), v in np.ndenumerate(np.clip(frame, 0, 255))}})
                f += 1
    return pd.DataFrame(rows)


def cells_long() -> pd.DataFrame:
    """A true long table: one 2 x 2 capture of three frames, a row per cell, rows in any order."""
    rows = [{"capture_id": "c1", "subject": "ann", "gesture": "poke", "frame": f, "row": r, "col": c,
             "value": 100 * f + 10 * r + c} for f in (0, 1, 2) for r in (0, 1) for c in (0, 1)]
    return pd.DataFrame(rows).iloc[[5, 0, 11, 1, 2, 3, 4, 6, 7, 8, 9, 10]]


def raw_recording() -> str:
    """Three frames in the HAART organisers' raw format: ten lines of ten values each (raw ADC,
    higher = less pressure), a press in the middle of the grid in the second frame."""
    lines = []
    for f in range(3):
        for r in range(10):
            lines.append(",".join(str(1023 - (300 if f == 1 and 3 <= r <= 6 and 3 <= c <= 6 else 0))
                                  for c in range(10)))
    return "\n".join(lines) + "\n"


def cost() -> pd.DataFrame:
    """The CoST release layout: one capture (subject 1, variant 2 "normal", gesture 4 "pat") of three frames."""
    return pd.DataFrame([{"subject": 1, "variant": 2, "gesture": 4, "frame": f + 1,
                          **{f"ch{i + 1}": (f * 64 + i) % 1024 for i in range(64)}} for f in range(3)])


def main() -> None:
    rng = np.random.default_rng(0)
    my_skin(rng).to_csv(HERE / "my-skin.csv", index=False)
    cells_long().to_csv(HERE / "cells-long.csv", index=False)
    study = HERE / "study" / "150301-21"
    study.mkdir(parents=True, exist_ok=True)
    (study / "150301-21nonefurpat.csv").write_text(raw_recording())
    cost().to_csv(HERE / "cost-tiny.csv", index=False)
    # shipped with the package: the protocol stream-table reads it
    skin_sessions(np.random.default_rng(1)).to_csv(HERE.parent.parent / "touchbench" / "data" / "skin-sessions.csv.gz",
                                                   index=False, compression={"method": "gzip", "mtime": 0})


if __name__ == "__main__":
    main()
