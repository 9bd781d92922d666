"""Same predictions before and after: every shipped protocol run with two versions of touchbench, compared.

    python benchmarks/compare_runs.py --base f2fe39c                  # head: this checkout
    python benchmarks/compare_runs.py --base f2fe39c --head ../touchbench-other-checkout
    python benchmarks/compare_runs.py --base f2fe39c --head main --protocol tiny --protocol demo-haart
    python benchmarks/compare_runs.py --base f2fe39c --max-seconds 300 --out results/compare

What is measured. The protocols are the ``touchbench/protocols/*.yaml`` of
either side (not ``papers/``), and ``touch-haart`` restricted to ``--method
touch-et-fast`` (listed as ``touch-haart[touch-et-fast]``). ``--base REV``
(and ``--head REV`` when it is not a folder) is checked out with ``git
worktree add --detach`` into a temporary folder, removed at the end; the
default head is this checkout. Each run is ``touchbench run NAME --out DIR
--jobs 1 --no-progress`` in a subprocess with ``PYTHONPATH`` set to that
side's root, its own empty ``TOUCHBENCH_CACHE_DIR`` (no feature or dataset
cache is shared between sides or protocols: each time is a cold run, HAART
conversion included) and ``TOUCHBENCH_DATA_DIR`` set to the data this
checkout finds (``touchbench.core.paths.data_dir``).

First pass: every protocol on the base, timed, killed after
``--max-seconds`` (default 120) and then listed as skipped with the time it
ran. Second pass: the protocols that finished, on the head (limit
``3 x --max-seconds``).

Compared, per evaluation folder (a protocol with several evaluations
writes one subfolder each): the rows of ``predictions.parquet`` joined on
(repetition, fold, early_frames, capture_id, method). A method is its
(features, label) pair; task ids and labels may change between sides, so a
method present on both sides is matched to itself and the others are
matched by position of first appearance (plan order), and the label
mapping old -> new is printed. Per row: the predicted label and every
``proba_*`` column, exact equality (max |delta proba| printed); per task
(scores.parquet): status, ``accuracy``, ``macro_f1``, ``balanced_accuracy``,
exact. Printed: the timing table, then one line per evaluation (methods,
tasks, predictions compared / identical, max |delta proba|, verdict
``identical`` or ``differs``), the mean accuracy per method on both sides
where they differ, the label mappings. Exit status 0 when every compared
evaluation is identical, 1 otherwise.

``--out DIR`` keeps the results folders (``DIR/base/NAME``,
``DIR/head/NAME``); without it they live in a temporary folder under
``cache_dir() / "benchmarks" / "compare_runs"``, removed at the end.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from touchbench.core.paths import data_dir
from touchbench.results.store import PREDICTED, PROBA_PREFIX, read_results_table
from workdir import bench_dir

REPO = Path(__file__).resolve().parent.parent
RUN = "from touchbench.cli.main import cli; cli()"
#: protocols run with extra arguments: listed name -> (protocol, arguments)
RESTRICTED = {"touch-haart[touch-et-fast]": ("touch-haart", ["--method", "touch-et-fast"])}
ROW_KEYS = ["repetition", "fold", "early_frames", "capture_id"]
TASK_KEYS = ["repetition", "fold", "early_frames"]
SCORE_METRICS = ["accuracy", "macro_f1", "balanced_accuracy"]
METHOD = "_method"


@dataclass
class Outcome:
    """One run of one protocol on one side."""

    seconds: float
    status: str  # "ok", "timeout", "failed"
    tail: str = ""


@dataclass
class Comparison:
    """One evaluation folder compared."""

    name: str
    methods: int = 0
    tasks: int = 0
    compared: int = 0
    identical: int = 0
    max_dproba: float = 0.0
    problems: list[str] = field(default_factory=list)
    mapping: dict[str, str] = field(default_factory=dict)
    accuracy: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> str:
        return "identical" if not self.problems and self.compared == self.identical else "differs"


# ----------------------------------------------------------------- the two sides' code
@contextmanager
def checkout(rev: str, work: Path):
    """The code of git revision ``rev`` in a detached worktree under ``work``, removed on exit."""
    path = Path(tempfile.mkdtemp(prefix=f"src-{rev.replace('/', '_')}-", dir=work))
    path.rmdir()
    subprocess.run(["git", "-C", str(REPO), "worktree", "add", "--detach", str(path), rev], check=True,
                   capture_output=True, text=True)
    try:
        yield path
    finally:
        subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(path)], capture_output=True)
        shutil.rmtree(path, ignore_errors=True)
        subprocess.run(["git", "-C", str(REPO), "worktree", "prune"], capture_output=True)


def side_root(spec: str | None, work: Path, stack: ExitStack) -> Path:
    """The root of the code named by ``spec``: this checkout (None), a folder, or a git revision."""
    if spec is None:
        return REPO
    if Path(spec).is_dir():
        return Path(spec).resolve()
    return stack.enter_context(checkout(spec, work))


def shipped(root: Path) -> list[str]:
    return sorted(p.stem for p in (root / "touchbench" / "protocols").glob("*.yaml"))


# ----------------------------------------------------------------- running
def run_protocol(root: Path, name: str, out: Path, cache: Path, limit: float) -> Outcome:
    """``touchbench run`` of the listed protocol ``name`` with the code in ``root``, killed after ``limit`` s."""
    proto, extra = RESTRICTED.get(name, (name, []))
    for p in (out, cache):
        shutil.rmtree(p, ignore_errors=True)
        p.mkdir(parents=True)
    env = {**os.environ, "PYTHONPATH": str(root), "TOUCHBENCH_CACHE_DIR": str(cache),
           "TOUCHBENCH_DATA_DIR": str(data_dir())}
    cmd = [sys.executable, "-c", RUN, "run", proto, "--out", str(out), "--jobs", "1", "--no-progress", *extra]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=cache, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    try:
        text, _ = proc.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the run and any worker it started
        proc.communicate()
        return Outcome(time.perf_counter() - t0, "timeout")
    wall = time.perf_counter() - t0
    return Outcome(wall, "ok" if proc.returncode == 0 else "failed", text[-2000:])


def run_side(side: str, root: Path, names: list[str], work: Path, limit: float) -> dict[str, Outcome]:
    have = set(shipped(root)) | set(RESTRICTED)
    outcomes = {}
    for name in names:
        if RESTRICTED.get(name, (name,))[0] not in have:
            outcomes[name] = Outcome(0.0, "missing")
            continue
        o = outcomes[name] = run_protocol(root, name, work / side / name, work / "cache" / side / name, limit)
        print(f"{side} {name}: {o.status} in {o.seconds:.1f} s", flush=True)
        if o.status == "failed":
            print("  " + o.tail.strip().replace("\n", "\n  "), flush=True)
    return outcomes


# ----------------------------------------------------------------- comparing
def evaluation_folders(out: Path) -> dict[str, Path]:
    """Evaluation name (``-`` for a protocol with one) -> the folder holding its ``predictions.parquet``."""
    return {("-" if p.parent == out else str(p.parent.relative_to(out))): p.parent
            for p in sorted(out.rglob("predictions.parquet")) if "fragments" not in p.parts}


def method_keys(df: pd.DataFrame) -> pd.Series:
    return df["features"].astype(str) + " | " + df["classifier"].astype(str)


def pair_methods(old: list[str], new: list[str]) -> dict[str, str]:
    """old method -> new: the same name when both sides have it, the rest by position of first appearance."""
    pairs = {m: m for m in old if m in new}
    rest_new = [m for m in new if m not in pairs]
    for m, n in zip([m for m in old if m not in pairs], rest_new):
        pairs[m] = n
    return pairs


def keyed(df: pd.DataFrame, keys: list[str], rename: dict[str, str] | None = None) -> pd.DataFrame:
    """``df`` with a method column (renamed through ``rename``) and keys made comparable (NaN -> -1)."""
    df = df.copy()
    df[METHOD] = method_keys(df)
    if rename is not None:
        df[METHOD] = df[METHOD].map(rename).fillna("(unmatched) " + df[METHOD])
    for k in keys:
        if k in df.columns:
            df[k] = df[k].fillna(-1) if df[k].dtype.kind == "f" else df[k].astype(str)
        else:
            df[k] = -1
    return df


def same(a: pd.Series, b: pd.Series) -> np.ndarray:
    """Exact equality, NaN equal to NaN."""
    eq = (a == b).to_numpy()
    return eq | (a.isna().to_numpy() & b.isna().to_numpy())


def compare_predictions(c: Comparison, old: pd.DataFrame, new: pd.DataFrame) -> None:
    keys = [*ROW_KEYS, METHOD]
    for name, df in (("base", old), ("head", new)):
        if df.duplicated(keys).any():
            c.problems.append(f"{name}: repeated (repetition, fold, early_frames, capture, method) rows")
    m = old.merge(new, on=keys, how="outer", suffixes=("_old", "_new"), indicator=True)
    lonely = int((m["_merge"] != "both").sum())
    if lonely:
        c.problems.append(f"{lonely} prediction rows on one side only")
    m = m[m["_merge"] == "both"]
    ok = same(m[f"{PREDICTED}_old"], m[f"{PREDICTED}_new"])
    probas = sorted({col for col in (*old.columns, *new.columns) if col.startswith(PROBA_PREFIX)})
    for col in probas:
        if col not in old.columns or col not in new.columns:
            c.problems.append(f"{col} on one side only")
            continue
        a, b = m[f"{col}_old"].astype("float64"), m[f"{col}_new"].astype("float64")
        ok &= same(a, b)
        d = (a - b).abs().max()
        if pd.notna(d):
            c.max_dproba = max(c.max_dproba, float(d))
    c.compared, c.identical = len(m), int(ok.sum())


def compare_scores(c: Comparison, old: pd.DataFrame, new: pd.DataFrame) -> None:
    keys = [*TASK_KEYS, METHOD]
    m = old.merge(new, on=keys, how="outer", suffixes=("_old", "_new"), indicator=True)
    c.tasks = len(m)
    lonely = int((m["_merge"] != "both").sum())
    if lonely:
        c.problems.append(f"{lonely} tasks on one side only")
    m = m[m["_merge"] == "both"]
    for col in ["status", *SCORE_METRICS]:
        if f"{col}_old" not in m.columns or f"{col}_new" not in m.columns:
            c.problems.append(f"scores: {col} missing on a side")
            continue
        n = int((~same(m[f"{col}_old"], m[f"{col}_new"])).sum())
        if n:
            c.problems.append(f"{col} differs in {n} task(s)")
    acc = m.groupby(METHOD, sort=False)[["accuracy_old", "accuracy_new"]].mean()
    for method, row in acc.iterrows():
        if not same(pd.Series([row["accuracy_old"]]), pd.Series([row["accuracy_new"]]))[0]:
            c.accuracy.append(f"{method}: accuracy {100 * row['accuracy_old']:.2f} % -> "
                              f"{100 * row['accuracy_new']:.2f} %")


def compare_folder(name: str, old_dir: Path, new_dir: Path) -> Comparison:
    c = Comparison(name)
    po, pn = (read_results_table(d / "predictions.parquet") for d in (old_dir, new_dir))
    so, sn = (read_results_table(d / "scores.parquet") for d in (old_dir, new_dir))
    order_old = list(dict.fromkeys(method_keys(so)))
    order_new = list(dict.fromkeys(method_keys(sn)))
    pairs = pair_methods(order_old, order_new)
    c.methods = len(order_old)
    if len(order_old) != len(order_new):
        c.problems.append(f"{len(order_old)} methods on the base, {len(order_new)} on the head")
    c.mapping = {o: n for o, n in pairs.items() if o != n}
    compare_predictions(c, keyed(po, ROW_KEYS, pairs), keyed(pn, ROW_KEYS))
    compare_scores(c, keyed(so, TASK_KEYS, pairs), keyed(sn, TASK_KEYS))
    return c


def compare_protocol(name: str, old_out: Path, new_out: Path) -> list[Comparison]:
    old, new = evaluation_folders(old_out), evaluation_folders(new_out)
    out = []
    for ev in sorted(set(old) | set(new)):
        if ev not in old or ev not in new:
            c = Comparison(f"{name} / {ev}")
            c.problems.append(f"evaluation only on the {'base' if ev in old else 'head'}")
            out.append(c)
            continue
        out.append(compare_folder(f"{name} / {ev}", old[ev], new[ev]))
    return out


# ----------------------------------------------------------------- printing
def print_times(base: dict[str, Outcome], head: dict[str, Outcome], limit: float) -> None:
    print(f"\n{'protocol':34} {'base s':>8} {'head s':>8}  status (limit {limit:.0f} s on the base)")
    for name, o in base.items():
        h = head.get(name)
        status = {"timeout": f"skipped: over {limit:.0f} s", "failed": "failed on the base",
                  "missing": "not in the base"}.get(o.status, "")
        if h is not None and h.status != "ok":
            status = f"head {h.status}"
        head_s = f"{h.seconds:8.1f}" if h is not None and h.status != "missing" else f"{'-':>8}"
        print(f"{name:34} {o.seconds:8.1f} {head_s}  {status}")


def print_comparisons(comps: list[Comparison]) -> None:
    print(f"\n{'protocol / evaluation':44} {'methods':>7} {'tasks':>6} {'compared':>9} {'identical':>9} "
          f"{'max|dp|':>9}  verdict")
    for c in comps:
        print(f"{c.name:44} {c.methods:7d} {c.tasks:6d} {c.compared:9d} {c.identical:9d} {c.max_dproba:9.2g}  "
              f"{c.verdict}")
    for c in comps:
        notes = [*c.problems, *c.accuracy, *(f"label: {o} -> {n}" for o, n in c.mapping.items())]
        for note in notes:
            print(f"  {c.name}: {note}")


# ----------------------------------------------------------------- main
def parse_args(argv=None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="git revision of the 'before' side")
    ap.add_argument("--head", default=None,
                    help="a folder or git revision of the 'after' side [default: this checkout]")
    ap.add_argument("--protocol", action="append", default=[], metavar="NAME",
                    help="only these protocols (repeatable; touch-haart[touch-et-fast] is one) [default: all]")
    ap.add_argument("--max-seconds", type=float, default=120.0, help="skip a protocol slower than this on the base")
    ap.add_argument("--out", default=None, help="keep the results folders here")
    return ap.parse_args(argv)


def compare_all(args: argparse.Namespace, work: Path, stack: ExitStack) -> int:
    stack.callback(shutil.rmtree, work / "cache", ignore_errors=True)
    base_root = side_root(args.base, work, stack)
    head_root = side_root(args.head, work, stack)
    names = args.protocol or [*sorted(set(shipped(base_root)) | set(shipped(head_root))), *RESTRICTED]
    print(f"base {args.base} ({base_root}), head {args.head or 'this checkout'} ({head_root}), "
          f"data {data_dir()}, load average {os.getloadavg()[0]:.1f}", flush=True)
    base = run_side("base", base_root, names, work, args.max_seconds)
    done = [n for n, o in base.items() if o.status == "ok"]
    head = run_side("head", head_root, done, work, 3 * args.max_seconds)
    print_times(base, head, args.max_seconds)
    comps = [c for n in done if head[n].status == "ok"
             for c in compare_protocol(n, work / "base" / n, work / "head" / n)]
    print_comparisons(comps)
    failed = [n for n in done if head[n].status != "ok"] + [n for n, o in base.items() if o.status == "failed"]
    ok = not failed and all(c.verdict == "identical" for c in comps)
    print(f"\n{len(comps)} evaluation(s) of {len(done)} protocol(s) compared: "
          f"{'all identical' if ok else 'DIFFERENCES'}; skipped (over {args.max_seconds:.0f} s on the base): "
          f"{', '.join(n for n, o in base.items() if o.status == 'timeout') or 'none'}")
    return 0 if ok else 1


def main(argv=None) -> int:
    args = parse_args(argv)
    with ExitStack() as stack:
        if args.out:
            work = Path(args.out).resolve()
            work.mkdir(parents=True, exist_ok=True)
        else:
            work = Path(tempfile.mkdtemp(prefix="run-", dir=bench_dir(__file__)))
            stack.callback(shutil.rmtree, work, ignore_errors=True)
        return compare_all(args, work, stack)


if __name__ == "__main__":
    sys.exit(main())
