"""The figures of docs/research/study-transfer.md: HAART against the design half of the organisers' second study.

    python docs/research/study_transfer.py haart-to-study --method touch-et-quiet --seeds 5
    python docs/research/study_transfer.py haart-to-study --method touch-et-quiet --params '{"gate": false}'
    python docs/research/study_transfer.py loso-with-haart --method touch-et-quiet --seeds 1
    python docs/research/study_transfer.py haart-loso --method touch-et-quiet --folds 10
    python docs/research/study_transfer.py socialtouch-loso --method touch-et-quiet
    python docs/research/study_transfer.py levels
    python docs/research/study_transfer.py windows --method touch-et-fast

- ``haart-to-study``: trained on all of HAART (the registered ``haart``: 830 captures, the middle 8 s of
  each 10-s recording), tested on the study's recordings, their first 20 s (``haart-raw``, window
  ``whole``, ``recording_seconds=20``: 217 of 224 last 20 s or more); one line per seed, then the mean,
  the sample standard deviation and the range over seeds, and the recall of ``notouch``.
- ``loso-with-haart``: each of the study's participants left out in turn, trained on HAART plus the
  study's other participants (the HAART subjects kept as subjects of their own), tested on the one left
  out; the accuracy pooled over the folds (every capture tested once) and the recall of ``notouch``.
- ``haart-loso``: leave one HAART subject out, the first ``--folds`` subjects (s01, s02...); the mean
  over folds of each fold's accuracy.
- ``socialtouch-loso``: the same on the registered ``socialtouch`` (its three subjects).
- ``levels``: the notouch captures' level, per-cell noise and peak above baseline, per dataset and condition.
- ``windows``: the method (default touch-et-quiet; give ``--method touch-et-fast``) trained on HAART, tested
  on three windows of the study's recordings.

Everything is fitted through ``touchbench.methods.FeaturePipeline`` (the fit path of the run engine's
tasks), one thread; seeds are 0, 1, ... The study folder is ``--study`` (default the shared data).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import json  # noqa: E402

from collections import Counter  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from touchbench.catalog import load_dataset  # noqa: E402
from touchbench.datasets.haart_raw import read_haart_raw  # noqa: E402
from touchbench.methods import FeaturePipeline, method_spec  # noqa: E402

STUDY = "/work/shared/data/icmi15-study2/raw"
PATTERN = (r"(?P<study>\d+)-(?P<participant>\d+)(?P<cover>cover|none)(?P<motion>dynamic|static)"
           r"(?P<gesture>constant|notouch|pat|rub|scratch|stroke|tickle)")


def _fit(args, seed, caps, y, groups, sensor):
    spec = method_spec(args.method, **json.loads(args.params))
    return FeaturePipeline(spec, random_state=seed, sensor=sensor).fit(caps, y, groups=groups)


def _line(label, pred, y):
    acc = float(np.mean(pred == y) * 100)
    nt = float(np.mean(pred[y == "notouch"] == "notouch") * 100)
    print(f"{label}: accuracy {acc:.1f} %, notouch recall {nt:.0f} %", flush=True)
    return acc, nt


def haart_to_study(args, haart, study):
    accs, nts = [], []
    for seed in range(args.seeds):
        m = _fit(args, seed, haart.captures, haart.meta.gesture.values, haart.meta.subject.values, haart.sensor)
        a, n = _line(f"seed {seed}", m.predict(study.captures), study.meta.gesture.values)
        accs.append(a)
        nts.append(n)
    sd = float(np.std(accs, ddof=1)) if len(accs) > 1 else 0.0
    print(f"{args.method} {args.params}: HAART -> study {np.mean(accs):.1f} +- {sd:.1f} "
          f"(range {min(accs):.1f}..{max(accs):.1f}, {len(accs)} seeds), notouch recall {np.mean(nts):.0f} %")


def loso_with_haart(args, haart, study):
    ys = study.meta.gesture.values
    for seed in range(args.seeds):
        pred = np.empty(len(ys), dtype=object)
        for person in sorted(set(study.meta.subject)):
            test = (study.meta.subject == person).to_numpy()
            caps = list(haart.captures) + [c for c, t in zip(study.captures, test) if not t]
            y = np.concatenate([haart.meta.gesture.values, ys[~test]])
            g = np.concatenate([haart.meta.subject.values, study.meta.subject.values[~test]])
            m = _fit(args, seed, caps, y, g, haart.sensor)
            pred[test] = m.predict([c for c, t in zip(study.captures, test) if t])
            _line(f"seed {seed} {person} out", pred[test], ys[test])
        _line(f"{args.method} {args.params} seed {seed}: LOSO over the study with HAART, pooled", pred, ys)


def loso(args, haart, _study):
    if args.mode == "socialtouch-loso":
        haart = load_dataset("socialtouch")
    y, subj = haart.meta.gesture.values, haart.meta.subject.values
    accs = []
    for person in sorted(set(subj))[:args.folds]:
        test = subj == person
        m = _fit(args, 0, [c for c, t in zip(haart.captures, test) if not t], y[~test], subj[~test], haart.sensor)
        accs.append(_line(f"{person} out", m.predict([c for c, t in zip(haart.captures, test) if t]), y[test])[0])
    print(f"{args.method} {args.params}: {haart.name} LOSO, {len(accs)} folds, mean {np.mean(accs):.2f}")


def levels(args, haart, study):
    """Median over the notouch captures of: the frame level (mean over cells), each cell's sd over the
    frames (median over cells), the largest pressure above each cell's 5 % baseline (95th percentile
    over frames), per dataset and condition; the study read whole (first 20 s) and as HAART's window."""
    mid = [c[54:486] for c in study.captures]
    for label, caps, meta, cond in (("HAART", haart.captures, haart.meta, "cover"),
                                    ("study, first 20 s", study.captures, study.meta, ["cover", "motion"]),
                                    ("study, frames 55..486", mid, study.meta, ["cover", "motion"])):
        rows = []
        for c, (_, r) in zip(caps, meta.iterrows()):
            if r.gesture != "notouch":
                continue
            x = np.asarray(c, dtype=np.float64).reshape(len(c), -1)
            k = int(0.05 * (len(x) - 1))
            p = x - np.partition(x, k, axis=0)[k]
            rows.append({"cond": "/".join(str(r[k_]) for k_ in np.atleast_1d(cond)), "level": np.median(x.mean(1)),
                         "cell_sd": np.median(x.std(0)), "peak95": np.percentile(p.max(1), 95)})
        t = pd.DataFrame(rows)
        print(f"{label}: all {t[['level', 'cell_sd', 'peak95']].median().round(2).to_dict()} (n={len(t)})")
        print(t.groupby("cond")[["level", "cell_sd", "peak95"]].median().round(2).to_string())


def windows(args, haart, study):
    """The method trained on HAART, tested on the study's first 20 s, on HAART's window of its first
    10 s (frames 55..486) and the same window of its second 10 s: accuracy, notouch recall and what
    notouch is called, seed 0."""
    y = study.meta.gesture.values
    m = _fit(args, 0, haart.captures, haart.meta.gesture.values, haart.meta.subject.values, haart.sensor)
    for label, caps in (("first 20 s", study.captures), ("frames 55..486", [c[54:486] for c in study.captures]),
                        ("frames 595..1026", [c[594:1026] if len(c) >= 1026 else c[54:486] for c in study.captures])):
        pred = m.predict(caps)
        _line(label, pred, y)
        print("   notouch called:", dict(Counter(pred[y == "notouch"].tolist())))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=["haart-to-study", "loso-with-haart", "haart-loso", "socialtouch-loso", "levels",
                                      "windows"])
    ap.add_argument("--method", default="touch-et-quiet")
    ap.add_argument("--params", default="{}", help="JSON: parameters given to the method")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--folds", type=int, default=10)
    ap.add_argument("--study", default=STUDY)
    args = ap.parse_args()
    haart = load_dataset("haart")
    study = None if args.mode.endswith("-loso") else read_haart_raw(
        args.study, pattern=PATTERN, recording_window="whole", recording_seconds=20)
    {"haart-to-study": haart_to_study, "loso-with-haart": loso_with_haart, "haart-loso": loso,
     "socialtouch-loso": loso, "levels": levels, "windows": windows}[args.mode](
        args, haart, study)


if __name__ == "__main__":
    main()
