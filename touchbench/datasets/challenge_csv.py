"""The Social Touch Challenge 2015 release format for HAART.

As ../shared/data/haart/README.md describes the organisers' R scripts:

- ``training.csv``: ParticipantID, Substrate, Cover, Gesture, cell1..cell64;
  432 rows per capture (578 captures);
- ``testWITHLABELS.csv``: the same with Sequence (a frame counter within the
  capture) after Gesture (251 captures).

Strings are quoted (R's ``write.table``). Copies in circulation carry headers
such as ``ParticipantNo, "Substrate", ...``: the reader strips spaces and
quotes and accepts either participant column name, and lower-cases the
label values. Cells are the 8 x 8 frame in row-major order. ParticipantID is
``P<n>`` for training and ``T<n>`` for test participants; touchbench's
subject is ``s<nn>``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa

from ..core.errors import DataError
from .formats import register_format
from .haart import HAART_SENSOR, N_FRAMES
from .model import TouchDataset
from .tables import find_column, numeric, read_table, runs, write_csv_atomic

TRAIN_FILE = "training.csv"
TEST_FILE = "testWITHLABELS.csv"
CELLS = [f"cell{i}" for i in range(1, 65)]
PARTICIPANT_NAMES = ("ParticipantID", "ParticipantNo", "Participant")


def export_challenge_csv(ds: TouchDataset, out_dir: str | Path) -> list[Path]:
    """Write ``training.csv`` and ``testWITHLABELS.csv`` for ``ds``'s splits."""
    out_dir = Path(out_dir)
    if ds.sensor.grid != (8, 8):
        raise DataError(f"the challenge format holds 8 x 8 frames; dataset {ds.name!r} has {ds.sensor.grid}")
    for col in ("split", "substrate", "cover"):
        if col not in ds.meta.columns:
            raise DataError(f"dataset {ds.name!r} has no {col!r} column; the challenge format needs it")
    files = []
    for split, fname in (("train", TRAIN_FILE), ("test", TEST_FILE)):
        idx = np.flatnonzero(ds.meta["split"].to_numpy() == split)
        meta = ds.meta.iloc[idx]
        n = np.array([ds.captures[i].shape[0] for i in idx], dtype=np.int64)
        if "challenge_label" in meta.columns:
            labels = meta["challenge_label"].astype(str).to_numpy()
        else:
            prefix = "P" if split == "train" else "T"
            labels = np.array([prefix + str(int(str(s).lstrip("s"))) for s in meta["subject"]])
        cols: dict[str, object] = {
            "ParticipantID": np.repeat(labels, n),
            "Substrate": np.repeat(meta["substrate"].astype(str).to_numpy(), n),
            "Cover": np.repeat(meta["cover"].astype(str).to_numpy(), n),
            "Gesture": np.repeat(meta["gesture"].astype(str).to_numpy(), n),
        }
        if split == "test":
            cols["Sequence"] = np.concatenate([np.arange(1, k + 1) for k in n]) if len(n) else np.zeros(0, np.int64)
        cells = (np.concatenate([ds.captures[i].reshape(ds.captures[i].shape[0], -1) for i in idx]).astype(np.int64)
                 if len(idx) else np.zeros((0, 64), np.int64))
        cols.update({name: cells[:, j] for j, name in enumerate(CELLS)})
        files.append((out_dir / fname, pa.table(cols)))
    write_csv_atomic(files)
    return [p for p, _ in files]


def _read_one(path: Path, split: str) -> tuple[list[np.ndarray], pd.DataFrame]:
    df = read_table(path, allow_empty=True)  # a part with no captures (as export writes it): none
    if df.empty:
        return [], pd.DataFrame(columns=["capture_id", "subject", "substrate", "cover", "gesture", "split",
                                         "challenge_label"])
    pid = find_column(df, PARTICIPANT_NAMES, path, "participant")
    sub = find_column(df, ("Substrate",), path, "substrate")
    cov = find_column(df, ("Cover",), path, "cover")
    ges = find_column(df, ("Gesture",), path, "gesture")
    cells = [find_column(df, (c,), path, c) for c in CELLS]
    keys = pd.DataFrame({k: df[c].astype(str).str.strip().str.strip("\"'").str.lower() for k, c in
                         (("pid", pid), ("substrate", sub), ("cover", cov), ("gesture", ges))})
    seq_names = [c for c in df.columns if c.lower() == "sequence"]
    counter = numeric(df, seq_names, path, integer=True)[:, 0] if seq_names else None
    values = numeric(df, cells, path, lo=0, hi=1023, integer=True)
    bounds = runs(keys, counter, path, "Sequence")
    if counter is None:  # training.csv has no counter: runs of one key are 432-row captures
        split_bounds = []
        for a, b in bounds:
            if (b - a) % N_FRAMES:
                start = a + (b - a) // N_FRAMES * N_FRAMES
                raise DataError(f"a capture ends after {b - start} rows (lines {start + 2}-{b + 1}); each capture of "
                                f"this file has {N_FRAMES} rows", path, b + 1)
            split_bounds += [(s, s + N_FRAMES) for s in range(a, b, N_FRAMES)]
        bounds = split_bounds
    captures, rows = [], []
    for a, b in bounds:
        label = keys["pid"].iloc[a].upper()
        if not label[1:].isdigit():
            raise DataError(f"participant {label!r} is not of the form P<n> or T<n>", path, a + 2)
        subject = f"s{int(label[1:]):02d}"
        s, c, g = keys["substrate"].iloc[a], keys["cover"].iloc[a], keys["gesture"].iloc[a]
        captures.append(values[a:b].reshape(b - a, 8, 8).astype(np.uint16))
        rows.append({"capture_id": f"{subject}-{s}-{c}-{g}", "subject": subject, "substrate": s, "cover": c,
                     "gesture": g, "split": split, "challenge_label": label})
    return captures, pd.DataFrame(rows)


def read_challenge_csv(path: str | Path, name: str = "haart-challenge") -> TouchDataset:
    """Load released challenge files: a folder holding either or both files,
    or one file (``training.csv`` is read as train, any other as test)."""
    path = Path(path)
    if path.is_dir():
        found = [(path / f, s) for f, s in ((TRAIN_FILE, "train"), (TEST_FILE, "test")) if (path / f).is_file()]
        if not found:
            raise DataError(f"neither {TRAIN_FILE} nor {TEST_FILE} found", path)
    else:
        found = [(path, "train" if path.name == TRAIN_FILE else "test")]
    captures, metas = [], []
    for f, split in found:
        c, m = _read_one(f, split)
        captures += c
        metas.append(m)
    if not captures:
        raise DataError("no captures: every file found has a header and no rows", path)
    meta = pd.concat([m for m in metas if len(m)], ignore_index=True)
    return TouchDataset(name, captures, meta, HAART_SENSOR)


register_format(
    "challenge-csv", "the Social Touch Challenge 2015 release: training.csv and testWITHLABELS.csv (8 x 8 HAART)",
    read_challenge_csv, writer=export_challenge_csv, reads="file or folder",
)
