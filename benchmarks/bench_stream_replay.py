"""Replay speed of a stream evaluation on one core: frames per CPU second, times real time, and the
CPU time of each decision (p50, p99), with the load the machine was under.

    python benchmarks/bench_stream_replay.py                       # touch-et-fast on real HAART
    python benchmarks/bench_stream_replay.py --method touch-et --repeats 5
    python benchmarks/bench_stream_replay.py --dataset haart-sample --per-stream 2 --repeats 1   # seconds

What is timed is what a task of the ``stream`` scheme does after training
(``touchbench.engine.live``): the test subject's spliced stream (its
captures in a seeded random order between 1-3 s stretches of its
``notouch`` captures) pushed one frame at a time through the recogniser
``touchbench stream`` runs (windows 0.5 s + 1 s, hop 0.1 s), deciding
with each rule: the evaluation's replay (the windows due at every hop
classified in batches; a rule's CPU is its decisions' share, what a replay
with that rule alone spends: frames per CPU second and times real time are
the stream's frames and seconds over it), and live (the stream's first 100
decisions made again one frame at a time, as ``touchbench stream`` makes
them: the CPU of a decision, p50 and p99, and the times real time a
decision every hop at the median allows). The
method is trained once on windows of the other subjects' captures (not
timed). One core: the process is pinned to one CPU and BLAS/OpenMP limited
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

RULES = [{"name": "max", "threshold": 0.5}, {"name": "majority", "n": 5}, {"name": "hmm", "switch": 0.05},
         {"name": "gate", "idle": "notouch"}]


def pin_one_core() -> int:
    cpus = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpus[-1]})
    return cpus[-1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="haart")
    ap.add_argument("--method", default="touch-et-fast")
    ap.add_argument("--test-subject", default=None, help="the subject replayed [default: the first]")
    ap.add_argument("--per-stream", type=int, default=None, help="gestures in the stream [default: all]")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    core = pin_one_core()

    from touchbench.catalog import load_dataset
    from touchbench.core.threads import single_thread
    from touchbench.methods import METHODS
    from touchbench.methods.fitting import fit_method
    from touchbench.streams.replay import LiveSpec, replay, training_samples
    from touchbench.streams.rules import make_rule
    from touchbench.streams.timeline import rest_value, spliced_streams, stream_frames

    ds = load_dataset(args.dataset)
    meta = ds.meta.reset_index(drop=True)
    y = meta["gesture"].astype(str).to_numpy()
    subjects = meta["subject"].astype(str).to_numpy()
    test = args.test_subject or sorted(set(subjects))[0]
    rate = ds.sensor.frame_rate
    stream = spliced_streams(meta, np.asarray(ds.n_frames), np.flatnonzero(subjects == test), "gesture", "notouch",
                             (int(round(1 * rate)), int(round(3 * rate))), np.random.default_rng(0),
                             per_stream=args.per_stream)[0]
    spec = LiveSpec(streams=(stream,), idle="notouch", windows_s=(0.5, 1.0), hop_s=0.1, train_on="windows",
                    train_hop_s=None, rules=(), none_label="none")
    train = np.flatnonzero(subjects != test)
    caps = [ds.captures[i] for i in train]
    X, yy, gg = training_samples(caps, y[train], subjects[train], spec, rate)
    spec_m = METHODS.create(args.method)
    with single_thread():
        fitted = fit_method(spec_m, 0, X, yy, gg, sensor=ds.sensor)
    frames, _ = stream_frames(ds.captures, y, stream, "notouch", rest_value(ds.sensor))
    seconds = len(frames) / rate
    load0 = os.getloadavg()[0]
    print(f"{args.method} on {args.dataset}: {test}'s spliced stream, {len(frames)} frames ({seconds:.0f} s at "
          f"{rate:g} Hz), windows 0.5 + 1 s, hop 0.1 s; core {core}, {args.repeats} replays per rule")
    classes = [str(c) for c in fitted.classes]
    per_rule: list[list] = [[] for _ in RULES]
    for _ in range(args.repeats):
        rules = [make_rule(r).fit(caps, y[train], ds.sensor) for r in RULES]
        with single_thread():
            for k, rp in enumerate(replay(frames, fitted.window_proba, classes, ds.sensor, spec, rules)):
                per_rule[k].append(rp)
    print(f"{'rule':10s} {'frames/CPU s':>13s} {'x real time':>12s}   live: {'x real time':>11s} "
          f"{'CPU/decision p50':>17s} {'p99':>8s}")
    for r, runs in zip(RULES, per_rule):
        cpu = statistics.median(float(rp.decision_cpu_ms.sum()) / 1000.0 for rp in runs)
        live = np.concatenate([rp.live_cpu_ms for rp in runs])
        live_x = spec.hop_s * 1000.0 / float(np.median(live))  # a decision every hop, each at the median CPU
        print(f"{r['name']:10s} {len(frames) / cpu:13.0f} {seconds / cpu:12.1f}   live: {live_x:11.1f} "
              f"{np.percentile(live, 50):14.2f} ms {np.percentile(live, 99):5.2f} ms")
    print(f"load average (1 min) {load0:.2f} before, {os.getloadavg()[0]:.2f} after, on {os.cpu_count()} CPUs")


if __name__ == "__main__":
    main()
