"""What a profile of ``touchbench papers reproduce`` costs, from a sample of its tasks.

    python benchmarks/bench_papers_profile.py --out results/papers-full --profile full --jobs 2
    python benchmarks/bench_papers_profile.py --out results/papers-full --protocol gaus-table5-haart   # one

The full profile (1000-tree forests, 500 boosting iterations, 100-fold
cross-validation, up to 100 CNN epochs) takes too long on two cores to be
run whole for a measurement. Run it for a while (each protocol for a slot;
``papers reproduce --only NAME``, stopped with ``timeout``: the engine keeps
every finished task), then this script plans every protocol under the
profile (the engine's own planning: the same tasks the run would make),
reads the finished tasks' scores under ``OUT/<profile>/<protocol>/`` and
prints, per protocol and method:

- the tasks planned and finished;
- the median compute time of a finished task (``fit_seconds`` +
  ``predict_seconds`` + ``feature_fit_seconds``, as the scores record them;
  feature extraction is left out: the feature cache is shared with the quick
  profile, whose REPORT.md gives its run time);
- the estimate: every finished task at its own time, every other one at its
  method's median, the sum divided by ``--jobs``.

A method none of whose tasks finished has no median: its row says so and
the estimate is a lower bound (each unfinished task counted at the longest
time any task of the protocol was given, ``--slot`` seconds).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from touchbench.engine.planning import plan_run  # noqa: E402
from touchbench.papers.profiles import PROFILES, apply_profile, paper_protocols  # noqa: E402
from touchbench.protocols.loading import load_protocol  # noqa: E402
from touchbench.results.store import ResultStore  # noqa: E402

COST = ["fit_seconds", "predict_seconds", "feature_fit_seconds"]


def finished_tasks(folder: Path) -> pd.DataFrame:
    """Every finished task's id and compute seconds (the results folder's task fragments)."""
    s = ResultStore(folder).read_scores()
    s = s[s["status"] == "ok"]
    return pd.DataFrame({"task_id": s["task_id"], "seconds": s[COST].astype(float).fillna(0.0).sum(axis=1)})


def protocol_rows(path: Path, profile: str, out: Path, slot: float) -> list[dict]:
    """One row per method of the protocol under the profile: planned, finished, median, estimate."""
    proto, _ = apply_profile(load_protocol(path), PROFILES[profile])
    plan = plan_run(proto)
    planned = pd.DataFrame({"task_id": [t.task_id for t in plan.tasks],
                            "method": [f"{t.method.features_label} / {t.method.label}" for t in plan.tasks]})
    done = planned.merge(finished_tasks(out / profile / proto.name), on="task_id", how="left")
    rows = []
    for method, g in done.groupby("method", sort=False):
        med = g["seconds"].median()  # NaN when no task of the method finished
        fill = med if pd.notna(med) else slot
        rows.append({"protocol": proto.name, "method": method, "planned": len(g),
                     "finished": int(g["seconds"].notna().sum()), "median_s": med,
                     "estimate_s": float(g["seconds"].fillna(fill).sum()), "lower_bound": pd.isna(med)})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="the --out of papers reproduce")
    ap.add_argument("--profile", default="full", choices=sorted(PROFILES))
    ap.add_argument("--jobs", type=int, default=2, help="tasks run in parallel")
    ap.add_argument("--slot", type=float, default=0.0,
                    help="seconds each protocol was run for: the least an unfinished task of a method "
                         "with no finished task is counted at")
    ap.add_argument("--protocol", action="append", metavar="NAME",
                    help="only this paper protocol (repeatable; default: every one)")
    args = ap.parse_args()
    paths = [p for p in paper_protocols() if not args.protocol or p.stem in args.protocol]
    if args.protocol and len(paths) != len(set(args.protocol)):
        ap.error(f"no paper protocol {sorted(set(args.protocol) - {p.stem for p in paths})}")
    rows = [r for p in paths for r in protocol_rows(p, args.profile, args.out, args.slot)]
    table = pd.DataFrame(rows)
    pd.set_option("display.width", 200)
    pd.set_option("display.max_rows", 500)
    print(table.to_string(index=False, float_format=lambda x: f"{x:.2f}"))
    per = table.groupby("protocol", sort=False).agg(planned=("planned", "sum"), finished=("finished", "sum"),
                                                    estimate_s=("estimate_s", "sum"),
                                                    lower_bound=("lower_bound", "any"))
    per["estimate_h"] = per["estimate_s"] / args.jobs / 3600
    print()
    print(per.to_string(float_format=lambda x: f"{x:.2f}"))
    total = per["estimate_h"].sum()
    bound = "at least " if per["lower_bound"].any() else ""
    print(f"\n{args.profile} profile, {args.jobs} jobs: {bound}{total:.1f} h of task compute time "
          f"({int(per['finished'].sum())} of {int(per['planned'].sum())} tasks measured)")


if __name__ == "__main__":
    main()
