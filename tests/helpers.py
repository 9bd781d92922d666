"""Small builders shared by tests (not fixtures: plain functions)."""

from __future__ import annotations

import gzip
import re
import time
from pathlib import Path
from typing import Callable, TypeVar

import numpy as np
import pandas as pd
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from touchbench.datasets.haart import HAART_SENSOR
from touchbench.datasets.model import SensorSpec, TouchDataset
from touchbench.features.base import make_feature_set

T = TypeVar("T")

#: parameters a feature set needs stated (it has no default): raw-window's window, HAART's
STATED = {"raw-window": {"frames": 432, "shorter": "pad"}}


def make_set(name, sensor=HAART_SENSOR, **params):
    """The registered set ``name`` as the engine builds it on ``sensor`` (HAART's by default:
    the values these tests were worked out for), with the parameters it needs stated."""
    return make_feature_set(name, {**STATED.get(name, {}), **params}, sensor)


def make_dataset(n_subjects=3, gestures=("pat", "stroke"), reps=2, frames=20, grid=(4, 4), dtype=np.uint16, seed=0,
                 name="toy", **extra_cols) -> TouchDataset:
    rng = np.random.default_rng(seed)
    caps, rows = [], []
    for s in range(n_subjects):
        for g in gestures:
            for r in range(reps):
                t = frames if np.isscalar(frames) else int(rng.integers(*frames))
                caps.append(rng.integers(0, 1024, size=(t, *grid)).astype(dtype))
                rows.append({"capture_id": f"s{s:02d}-{g}-{r}", "subject": f"s{s:02d}", "gesture": g, "repetition": r})
    meta = pd.DataFrame(rows)
    for k, v in extra_cols.items():
        meta[k] = v
    return TouchDataset(name, caps, meta, SensorSpec("toy", grid, 50.0))


def write_recording(path: Path, lines: list[str], gz: bool = False) -> Path:
    text = "\n".join(lines) + "\n"
    if gz:
        path = path.with_name(path.name + ".gz")
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path


def random_recording(seed: int, n_lines: int = 5400) -> list[str]:
    rng = np.random.default_rng(seed)
    a = rng.integers(0, 1024, size=(n_lines, 10))
    return [",".join(str(v) for v in row) for row in a]


def captures_strategy(min_n=1, max_n=4, max_frames=40):
    """Hypothesis: a batch of 1..4 uint16 captures of one random grid (1..5 x 1..5), each 1..max_frames frames."""
    @st.composite
    def make(draw):
        h = draw(st.integers(1, 5))
        w = draw(st.integers(1, 5))
        n = draw(st.integers(min_n, max_n))
        caps = []
        for _ in range(n):
            t = draw(st.integers(1, max_frames))
            caps.append(draw(arrays(np.uint16, (t, h, w), elements=st.integers(0, 1023))))
        return caps
    return make()


README = Path(__file__).resolve().parent.parent / "README.md"


def readme_section(title: str) -> str:
    """The README's ``## title`` section, up to the next ``## `` heading."""
    text = README.read_text(encoding="utf-8")
    start = text.index(f"## {title}")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else None]


def code_blocks(text: str, lang: str) -> list[str]:
    """The fenced ``lang`` code blocks of ``text``, in order."""
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.DOTALL)


def fake_loso(subjects, gestures=("pat", "rub", "stroke"), reps: int = 2):
    """Captures (``capture_id``, ``subject``, ``gesture``) and their leave-one-subject-out folds for
    :func:`touchbench.reports.testing.write_fake_run`, and ``wrong(counts)``: the first ``counts[i]``
    captures of fold i predicted wrongly."""
    caps = pd.DataFrame([(f"{s}-{g}-{r}", s, g) for s in subjects for g in gestures for r in range(reps)],
                        columns=["capture_id", "subject", "gesture"])
    folds = {f"subject={s}": caps[caps["subject"] == s]["capture_id"].tolist() for s in subjects}

    def wrong(counts):
        return {f: ids[:c] for (f, ids), c in zip(folds.items(), counts)}

    return caps, folds, wrong


def slow_fast_rows(n_per_class=12, frames=40, seed=0):
    """Two classes of 2 x 2 captures flattened as raw-window rows: a slow and a fast oscillation
    (periods 16 and 4 frames), random phase and gain per cell, a little noise."""
    rng = np.random.default_rng(seed)
    X, y = [], []
    t = np.arange(frames)
    for label, period in (("slow", 16.0), ("fast", 4.0)):
        for _ in range(n_per_class):
            cap = np.empty((frames, 2, 2))
            for c in range(4):
                cap[:, c // 2, c % 2] = rng.uniform(5, 20) * np.sin(2 * np.pi * t / period + rng.uniform(0, 6.3))
            X.append((cap + rng.normal(0, 0.5, cap.shape)).reshape(-1))
            y.append(label)
    return np.array(X), np.array(y)


#: the bound on a test's wait for another process (a subprocess to end, a file to appear): only a hang
#: reaches it, never a slow or busy machine, so it is generous
SUBPROCESS_HANG_S = 30 * 60


def wait_for(probe: Callable[[], T | None], what: str, timeout: float = SUBPROCESS_HANG_S, interval: float = 0.05) -> T:
    """Call ``probe`` until it returns a true value and return that; fail the test,
    naming ``what``, when ``timeout`` seconds pass first. For tests that wait on another process
    (a file it writes, a state it reaches): a loaded machine (parallel tests) only makes them wait longer."""
    deadline = time.monotonic() + timeout
    while True:
        value = probe()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"waited {timeout:g} s for {what}")
        time.sleep(interval)


def read_int(path: Path) -> int | None:
    """The integer ``path`` holds, or ``None`` while it is missing or does not hold one yet."""
    try:
        return int(path.read_text())
    except (FileNotFoundError, ValueError):
        return None


def run_loso_method(tmp_path: Path, method_yaml: str, n_subjects: int = 4):
    """Run, through the engine, a protocol evaluating one method (``method_yaml``: its ``methods:``
    entry, indented as a list item) by leaving one subject out on a small random dataset of the
    test-only components' sensor (``n_subjects`` subjects, 2 captures per gesture)."""
    from touchbench.engine import run_protocol
    from touchbench.engine.testing import random_dataset

    data = tmp_path / "d.parquet"
    random_dataset(subjects=[f"s{i + 1}" for i in range(n_subjects)], per_cell=2).to_parquet(data)
    p = tmp_path / "one-method.yaml"
    p.write_text(f"name: one-method\ndataset: {data}\nscheme: loso\nmethods:\n{method_yaml}")
    return run_protocol(p, out=tmp_path / "results", progress=False)


def synthetic_captures(seed: int, t: int, grid: tuple[int, int], dtype, top: float = 255.0) -> list[np.ndarray]:
    """Captures of values in 0..top: moving blobs (saturating at top), sparse taps, noise, fractions
    for float dtypes; a constant one and an empty one."""
    rng = np.random.default_rng(seed)
    h, w = grid
    yy, xx = np.mgrid[0:h, 0:w]
    caps = []
    for k in range(4):
        cy = h / 2 + (h / 3) * np.sin(np.arange(t) * (0.3 + 0.2 * k))
        cx = w / 2 + (w / 3) * np.cos(np.arange(t) * (0.2 + 0.1 * k))
        blob = 1.2 * top * np.exp(-((yy[None] - cy[:, None, None]) ** 2 + (xx[None] - cx[:, None, None]) ** 2) / 3.0)
        taps = (rng.random((t, h, w)) < 0.05) * rng.uniform(0, top, (t, h, w))
        c = blob * (rng.random(t) < 0.7)[:, None, None] + taps + rng.uniform(0, 4, (t, h, w))
        caps.append(c if np.dtype(dtype).kind == "f" else np.floor(c))
    caps += [np.full((t, h, w), top / 3), np.zeros((t, h, w))]
    return [np.clip(c, 0, top).astype(dtype) for c in caps]


def compiled_and_numpy(name: str, caps, sensor, monkeypatch, **params) -> tuple[np.ndarray, np.ndarray]:
    """Feature set ``name``'s rows of ``caps`` by its compiled loops and by its numpy path
    (:data:`touchbench.core.compiled.COMPILED` False), of the same shape."""
    from touchbench.core import compiled
    from touchbench.features.base import FEATURES

    fast = FEATURES.create(name, sensor=sensor, **params).fit(caps).transform(caps)
    with monkeypatch.context() as m:
        m.setattr(compiled, "COMPILED", False)
        plain = FEATURES.create(name, sensor=sensor, **params).fit(caps).transform(caps)
    assert fast.shape == plain.shape
    return fast, plain
