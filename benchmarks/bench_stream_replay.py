"""Replay speed of a stream evaluation on one core: frames per CPU second, times real time, and the
CPU time of each decision (p50, p99), with the load the machine was under.

    python benchmarks/bench_stream_replay.py                       # touch-et-fast on real HAART
    python benchmarks/bench_stream_replay.py --method touch-et --repeats 5
    python benchmarks/bench_stream_replay.py --dataset inflatable-skin --method live   # every shipped live
                                                                   # method on the 19 x 27 skin
    python benchmarks/bench_stream_replay.py --dataset haart-sample --per-stream 2 --repeats 1   # seconds
    python benchmarks/bench_stream_replay.py --dataset inflatable-skin --method touch-et --baseline ../base
                                                                   # before / after, side by side

What is timed is what a task of the ``stream`` scheme does after training
(``touchbench.engine.live``): the test subject's spliced stream (its
captures in a seeded random order between 1-3 s stretches of its
``notouch`` captures), or, for a dataset of recordings labelled frame by
frame (``inflatable-skin``: its idle class ``idle``), the test subject's
longest recording as it was recorded, pushed one frame at a time through the recogniser
``touchbench stream`` runs (windows 0.5 s + 1 s, hop 0.1 s), deciding
with each rule: the evaluation's replay (the windows due at every hop
classified in batches; a rule's CPU is its decisions' share, what a replay
with that rule alone spends: frames per CPU second and times real time are
the stream's frames and seconds over it), and live (the stream's first 100
decisions made again one frame at a time, as ``touchbench stream`` makes
them: the CPU of a decision, p50 and p99, and the times real time a
decision every hop at the median allows). The
method is trained once on windows of the other subjects' captures (not
timed; the stream evaluations may train on windows of streams instead, which
changes the samples, not the size of the model). ``--method live`` times
every shipped live method (:data:`LIVE`) in one run, side by side. One core: the process is pinned to one CPU and BLAS/OpenMP limited
to one thread before numpy is imported. Medians over ``--repeats`` replays
of the same stream; the load average is read before and after.

Then, per method, the CPU of a live decision's parts: each feature set's
transform of the decision's windows and the classifier on their features,
for the same first decisions (each set on its own, so sets that share work
inside the method, such as the touch sets' pressure, count it each). For
``touch-et`` and ``touch-et-fast`` the live p99 is printed beside its target
(3 ms and 1.5 ms of CPU on the 19 x 27 skin, the ``max`` rule).

``--baseline DIR``: a checkout of touchbench (``git worktree add ../base
REV``) timed beside this one: each of ``--repeats`` rounds runs this script
once per side in a fresh process (``PYTHONPATH`` set to the side's checkout,
the same data), alternating which goes first so both see the same load;
printed per method and rule: both sides' live p50 and p99 (over every
round's decisions), their ratio, the replay's frames per CPU second, and
whether the two sides made the same decisions.
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

#: the shipped live methods (``--method live``)
LIVE = ["touch-live-fast", "touch-live", "touch-et-fast", "touch-et"]
#: CPU ms of one live decision at p99 (``max`` rule) each method should stay within on the 19 x 27 skin
TARGET_P99 = {"touch-et": 3.0, "touch-et-fast": 1.5}
#: the decisions whose parts are timed (the live sample's size)
PARTS_SAMPLE = 100


def rules(idle: str) -> list[dict]:
    return [{"name": "max", "threshold": 0.5}, {"name": "majority", "n": 5}, {"name": "hmm", "switch": 0.05},
            {"name": "gate", "idle": idle}, {"name": "touch", "idle": idle}]


def pin_one_core() -> int:
    cpus = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpus[-1]})
    return cpus[-1]


def test_stream(ds, y, subjects, test, per_stream):
    """The stream replayed: the test subject's longest recording (recorded data) or its spliced stream."""
    from touchbench.streams.timeline import recorded_streams, spliced_streams

    meta, rows = ds.meta.reset_index(drop=True), np.flatnonzero(subjects == test)
    if "recording" in meta.columns and "start_frame" in meta.columns:
        streams = recorded_streams(meta, np.asarray(ds.n_frames), rows)
        return max(streams, key=lambda s: s.n_frames), "idle", "recording"
    rate = ds.sensor.frame_rate
    return spliced_streams(meta, np.asarray(ds.n_frames), rows, "gesture", "notouch",
                           (int(round(1 * rate)), int(round(3 * rate))), np.random.default_rng(0),
                           per_stream=per_stream)[0], "notouch", "spliced stream"


def known_rules(declared: list[dict]) -> list[dict]:
    """The rules this checkout has (an older one may lack some): the others are said and left out."""
    from touchbench.core.errors import UnknownNameError
    from touchbench.streams.rules import make_rule

    out = []
    for r in declared:
        try:
            make_rule(r)
        except UnknownNameError:
            print(f"rule {r['name']!r}: not in this checkout ({os.path.dirname(os.path.dirname(sys.modules['touchbench'].__file__))}), left out")
            continue
        out.append(r)
    return out


def parse_args() -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="haart")
    ap.add_argument("--method", default="touch-et-fast", help="a method, or 'live': every shipped live method")
    ap.add_argument("--test-subject", default=None, help="the subject replayed [default: the first]")
    ap.add_argument("--per-stream", type=int, default=None, help="gestures in a spliced stream [default: all]")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline", help="a checkout timed beside this one, in alternating processes")
    ap.add_argument("--json", help=argparse.SUPPRESS)  # a side's figures, for --baseline
    return ap.parse_args()


def main() -> None:
    args = parse_args()
    if args.baseline:
        side_by_side(args)
        return
    core = pin_one_core()

    from touchbench.catalog import load_dataset
    from touchbench.streams.replay import LiveSpec
    from touchbench.streams.timeline import rest_value, stream_frames

    ds = load_dataset(args.dataset)
    y = ds.meta["gesture"].astype(str).to_numpy()
    subjects = ds.meta["subject"].astype(str).to_numpy()
    test = args.test_subject or sorted(set(subjects))[0]
    stream, idle, what = test_stream(ds, y, subjects, test, args.per_stream)
    spec = LiveSpec(streams=(stream,), idle=idle, windows_s=(0.5, 1.0), hop_s=0.1, train_on="windows",
                    train_hop_s=None, rules=(), none_label="none")
    frames, _ = stream_frames(ds.captures, y, stream, idle, rest_value(ds.sensor))
    rate, grid = ds.sensor.frame_rate, "x".join(map(str, ds.sensor.grid))
    print(f"{args.dataset} ({grid} cells): {test}'s {what}, {len(frames)} frames ({len(frames) / rate:.0f} s at "
          f"{rate:g} Hz), windows 0.5 + 1 s, hop 0.1 s; core {core}, {args.repeats} replays per rule")
    load0 = os.getloadavg()[0]
    out = {}
    for method in (LIVE if args.method == "live" else [args.method]):
        out[method] = time_method(method, ds, y, subjects, test, spec, frames, args.repeats)
        print_method(method, out[method], ds.sensor.grid)
    print(f"load average (1 min) {load0:.2f} before, {os.getloadavg()[0]:.2f} after, on {os.cpu_count()} CPUs")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"methods": out, "load": [load0, os.getloadavg()[0]], "grid": list(ds.sensor.grid)}, f)


def _with_idle(spec, idle):
    """The stream's idle class given to an estimator that takes one (a checkout without the step: as is)."""
    try:
        from touchbench.engine.live import with_idle
    except ImportError:
        return spec
    return with_idle(spec, idle)


def time_method(method, ds, y, subjects, test, spec, frames, repeats) -> dict:
    """Train ``method`` on the other subjects (not timed), then replay ``frames`` with every rule; the
    figures of each rule, the decisions' digest and the live decisions' parts."""
    from touchbench.core.threads import single_thread
    from touchbench.methods import METHODS
    from touchbench.methods.fitting import fit_method
    from touchbench.streams.replay import replay, training_samples
    from touchbench.streams.rules import make_rule

    rate, train = ds.sensor.frame_rate, np.flatnonzero(subjects != test)
    caps = [ds.captures[i] for i in train]
    X, yy, gg = training_samples(caps, y[train], subjects[train], spec, rate)
    with single_thread():
        fitted = fit_method(_with_idle(METHODS.create(method), spec.idle), 0, X, yy, gg, sensor=ds.sensor)
    declared = known_rules(rules(spec.idle))
    per_rule: list[list] = [[] for _ in declared]
    for _ in range(repeats):
        fitted_rules = [make_rule(r).fit(caps, y[train], ds.sensor) for r in declared]
        with single_thread():
            for k, rp in enumerate(replay(frames, fitted.window_proba, [str(c) for c in fitted.classes], ds.sensor,
                                          spec, fitted_rules)):
                per_rule[k].append(rp)
    seconds = len(frames) / rate
    result = {"rules": {}, "parts": live_parts(fitted, frames, spec, rate)}
    for r, runs in zip(declared, per_rule):
        cpu = statistics.median(float(rp.decision_cpu_ms.sum()) / 1000.0 for rp in runs)
        labels = "\n".join(str(d.label) for d in runs[0].decisions).encode()
        result["rules"][r["name"]] = {"frames_per_cpu_s": len(frames) / cpu, "x_real": seconds / cpu,
                                      "live_ms": np.concatenate([rp.live_cpu_ms for rp in runs]).tolist(),
                                      "decisions": hashlib.sha256(labels).hexdigest()[:16]}
    return result


def _set_name(fs) -> str:
    return str(getattr(fs, "name", None) or type(fs).__name__)


def live_parts(fitted, frames, spec, rate) -> dict:
    """CPU ms per decision of each feature set (on the decision's windows, alone) and of the classifier
    on their features, over the first :data:`PARTS_SAMPLE` decisions: median and p99."""
    from touchbench.datasets.windows import seconds_to_frames

    lengths = sorted({seconds_to_frames(w, rate) for w in spec.windows_s})
    hop = seconds_to_frames(spec.hop_s, rate)
    due = list(range(lengths[0], len(frames) + 1, hop))[:PARTS_SAMPLE]
    sets = list(getattr(fitted, "sets", None) or [])
    per: dict[str, list[float]] = {_set_name(fs): [] for fs in sets}
    per["classifier"] = []
    for s in due:
        windows = [frames[s - L:s] for L in lengths if s >= L]
        feats = []
        for fs in sets:
            c0 = time.thread_time_ns()
            feats.append(np.asarray(fs.transform(windows), dtype=np.float64))
            per[_set_name(fs)].append((time.thread_time_ns() - c0) / 1e6)
        c0 = time.thread_time_ns()
        fitted.proba_rows(np.hstack(feats) if feats else windows)
        per["classifier"].append((time.thread_time_ns() - c0) / 1e6)
    return {k: [float(np.median(v)), float(np.percentile(v, 99))] for k, v in per.items() if v}


def print_method(method: str, res: dict, grid) -> None:
    print(f"{method}\n  {'rule':10s} {'frames/CPU s':>13s} {'x real time':>12s}   live: {'x real time':>11s} "
          f"{'CPU/decision p50':>17s} {'p99':>8s}")
    for name, r in res["rules"].items():
        live = np.asarray(r["live_ms"])
        live_x = 100.0 / float(np.median(live))  # a decision every 0.1 s hop, each at the median CPU
        print(f"  {name:10s} {r['frames_per_cpu_s']:13.0f} {r['x_real']:12.1f}   live: {live_x:11.1f} "
              f"{np.percentile(live, 50):14.2f} ms {np.percentile(live, 99):5.2f} ms")
    parts = ", ".join(f"{k} {m:.2f} / {p:.2f}" for k, (m, p) in res["parts"].items())
    print(f"  a live decision's parts, CPU ms p50 / p99 (each set alone on the decision's windows): {parts}")
    print_target(method, np.asarray(res["rules"]["max"]["live_ms"]), grid)


def print_target(method: str, live_ms: np.ndarray, grid) -> None:
    if method not in TARGET_P99:
        return
    p99, target = float(np.percentile(live_ms, 99)), TARGET_P99[method]
    where = "" if tuple(grid) == (19, 27) else " (the target is for the 19 x 27 skin; these data differ)"
    print(f"  target: a live decision (max rule) at most {target:g} ms of CPU at p99: {p99:.2f} ms, "
          f"{'met' if p99 <= target else 'missed'}{where}")


def side_by_side(args: argparse.Namespace) -> None:
    """Each round: this script once per side in a fresh process, alternating the order; then the table."""
    import tempfile

    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    sides = {"this": here, "baseline": os.path.abspath(args.baseline)}
    got: dict[str, list[dict]] = {k: [] for k in sides}
    with tempfile.TemporaryDirectory() as tmp:
        for rnd in range(args.repeats):
            for side in (list(sides) if rnd % 2 == 0 else list(sides)[::-1]):
                path = os.path.join(tmp, f"{side}-{rnd}.json")
                cmd = [sys.executable, os.path.abspath(__file__), "--dataset", args.dataset, "--method", args.method,
                       "--repeats", "1", "--json", path]
                cmd += [] if args.test_subject is None else ["--test-subject", args.test_subject]
                cmd += [] if args.per_stream is None else ["--per-stream", str(args.per_stream)]
                env = {**os.environ, "PYTHONPATH": sides[side]}
                subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
                with open(path, encoding="utf-8") as f:
                    got[side].append(json.load(f))
    print(f"{args.dataset}, {args.repeats} rounds, sides alternating; this: {here}, baseline: {sides['baseline']}")
    for method in got["this"][0]["methods"]:
        print_pair(method, [g["methods"][method] for g in got["this"]],
                   [g["methods"][method] for g in got["baseline"]], got["this"][0]["grid"])
    loads = [g["load"][0] for side in got.values() for g in side]
    print(f"load average (1 min) before each side's run: {min(loads):.2f} to {max(loads):.2f}, on {os.cpu_count()} CPUs")


def print_pair(method: str, new: list[dict], old: list[dict], grid) -> None:
    print(f"{method}\n  {'rule':10s} {'p50 this':>9s} {'p99 this':>9s} {'p50 base':>9s} {'p99 base':>9s} "
          f"{'p99 x':>6s} {'frames/CPU s this':>18s} {'base':>7s}  same decisions")
    for name in [n for n in new[0]["rules"] if n in old[0]["rules"]]:
        a = np.concatenate([r["rules"][name]["live_ms"] for r in new])
        b = np.concatenate([r["rules"][name]["live_ms"] for r in old])
        fa = statistics.median(r["rules"][name]["frames_per_cpu_s"] for r in new)
        fb = statistics.median(r["rules"][name]["frames_per_cpu_s"] for r in old)
        same = {r["rules"][name]["decisions"] for r in new + old}
        print(f"  {name:10s} {np.percentile(a, 50):9.2f} {np.percentile(a, 99):9.2f} {np.percentile(b, 50):9.2f} "
              f"{np.percentile(b, 99):9.2f} {np.percentile(b, 99) / np.percentile(a, 99):6.2f} {fa:18.0f} {fb:7.0f}  "
              f"{'yes' if len(same) == 1 else 'NO'}")
    for side, runs in (("this", new), ("base", old)):
        parts = ", ".join(f"{k} {m:.2f} / {p:.2f}" for k, (m, p) in runs[0]["parts"].items())
        print(f"  a live decision's parts, CPU ms p50 / p99, {side} (first round): {parts}")
    print_target(method, np.concatenate([r["rules"]["max"]["live_ms"] for r in new]), grid)


if __name__ == "__main__":
    main()
