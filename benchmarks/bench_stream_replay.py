"""Replay speed of a stream evaluation on one core: frames per CPU second, times real time, and the
CPU time of each decision (p50, p99), with the load the machine was under.

    python benchmarks/bench_stream_replay.py                       # touch-et-fast on real HAART
    python benchmarks/bench_stream_replay.py --method touch-et --repeats 5
    python benchmarks/bench_stream_replay.py --dataset inflatable-skin --method live   # every shipped live
                                                                   # method on the 19 x 27 skin
    python benchmarks/bench_stream_replay.py --dataset haart-sample --per-stream 2 --repeats 1   # seconds

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
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402

import numpy as np  # noqa: E402

#: the shipped live methods (``--method live``)
LIVE = ["touch-live-fast", "touch-live", "touch-et-fast", "touch-et"]


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="haart")
    ap.add_argument("--method", default="touch-et-fast", help="a method, or 'live': every shipped live method")
    ap.add_argument("--test-subject", default=None, help="the subject replayed [default: the first]")
    ap.add_argument("--per-stream", type=int, default=None, help="gestures in a spliced stream [default: all]")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
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
    for method in (LIVE if args.method == "live" else [args.method]):
        time_method(method, ds, y, subjects, test, spec, frames, args.repeats)
    print(f"load average (1 min) {load0:.2f} before, {os.getloadavg()[0]:.2f} after, on {os.cpu_count()} CPUs")


def time_method(method, ds, y, subjects, test, spec, frames, repeats) -> None:
    """Train ``method`` on the other subjects (not timed), then replay ``frames`` with every rule."""
    from touchbench.core.threads import single_thread
    from touchbench.engine.live import with_idle
    from touchbench.methods import METHODS
    from touchbench.methods.fitting import fit_method
    from touchbench.streams.replay import replay, training_samples
    from touchbench.streams.rules import make_rule

    rate, train = ds.sensor.frame_rate, np.flatnonzero(subjects != test)
    caps = [ds.captures[i] for i in train]
    X, yy, gg = training_samples(caps, y[train], subjects[train], spec, rate)
    with single_thread():
        fitted = fit_method(with_idle(METHODS.create(method), spec.idle), 0, X, yy, gg, sensor=ds.sensor)
    declared = rules(spec.idle)
    per_rule: list[list] = [[] for _ in declared]
    for _ in range(repeats):
        fitted_rules = [make_rule(r).fit(caps, y[train], ds.sensor) for r in declared]
        with single_thread():
            for k, rp in enumerate(replay(frames, fitted.window_proba, [str(c) for c in fitted.classes], ds.sensor,
                                          spec, fitted_rules)):
                per_rule[k].append(rp)
    print(f"{method}\n  {'rule':10s} {'frames/CPU s':>13s} {'x real time':>12s}   live: {'x real time':>11s} "
          f"{'CPU/decision p50':>17s} {'p99':>8s}")
    seconds = len(frames) / rate
    for r, runs in zip(declared, per_rule):
        cpu = statistics.median(float(rp.decision_cpu_ms.sum()) / 1000.0 for rp in runs)
        live = np.concatenate([rp.live_cpu_ms for rp in runs])
        live_x = spec.hop_s * 1000.0 / float(np.median(live))  # a decision every hop, each at the median CPU
        print(f"  {r['name']:10s} {len(frames) / cpu:13.0f} {seconds / cpu:12.1f}   live: {live_x:11.1f} "
              f"{np.percentile(live, 50):14.2f} ms {np.percentile(live, 99):5.2f} ms")


if __name__ == "__main__":
    main()
