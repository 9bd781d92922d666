"""The leaderboard's verdicts on the same results, under two versions of touchbench.

    python benchmarks/compare_verdicts.py --base f2fe39c results/runs/example-haart-loso results/runs/socialtouch-loso

For each results folder, ``touchbench leaderboard --json`` is run with the
base revision's code (checked out with ``git worktree add --detach`` into a
temporary folder, removed afterwards; or a folder holding another checkout) and with this checkout's, each in a
subprocess with ``PYTHONPATH`` set to that side's root. Per table and method
(matched by features and label), printed: the test and its unit count on
each side, p after Holm's correction on each side, and whether the method
"differs from the best" at the table's alpha; then the methods whose verdict
changed. Exit status 0.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from compare_runs import side_root  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def _leaderboard(code_root: Path, results: Path) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=str(code_root))
    cmd = [sys.executable, "-c", "from touchbench.cli.main import cli; cli()", "leaderboard", str(results), "--json"]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=tempfile.gettempdir())
    return json.loads(out.stdout)["tables"]


def _verdicts(tables: list[dict]) -> dict[tuple[str, str, str], dict]:
    out = {}
    for t in tables:
        for r in t["rows"]:
            differs = r.get("differs", r.get("significant"))
            out[(t.get("title") or t.get("dataset", "?"), r["features"], r["classifier"])] = {
                "test": f"{r.get('test')} n={r.get('n_pairs')}", "p": r.get("p_holm"), "differs": bool(differs),
                "rank": r.get("rank")}
    return out


def _p(v) -> str:
    return "-" if v is None or v != v else f"{v:.3g}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", required=True, help="git revision (or checkout folder) of the older code")
    ap.add_argument("results", nargs="+", type=Path)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp, contextlib.ExitStack() as stack:
        base = side_root(args.base, Path(tmp), stack)
        changed = []
        for res in (p.resolve() for p in args.results):
            old, new = _verdicts(_leaderboard(base, res)), _verdicts(_leaderboard(ROOT, res))
            print(f"\n{res}")
            print(f"  {'method':40s} {'base test':24s} {'p':>8s} {'head test':24s} {'p':>8s}  verdict")
            for key in new:
                o, n = old.get(key, {}), new[key]
                verdict = ("differs" if n["differs"] else "-") + ("" if o.get("differs") == n["differs"] else
                                                                    f" (was {'differs' if o.get('differs') else '-'})")
                print(f"  {key[1] + ' / ' + key[2]:40.40s} {o.get('test', '?'):24.24s} {_p(o.get('p')):>8s} "
                      f"{n['test']:24.24s} {_p(n['p']):>8s}  {verdict}")
                if o and o.get("differs") != n["differs"]:
                    changed.append(f"{res.name}: {key[1]} / {key[2]}")
        print(f"\nverdicts changed: {len(changed)}")
        for c in changed:
            print(f"  {c}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
