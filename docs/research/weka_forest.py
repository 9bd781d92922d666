"""Weka 3.6's own RandomForest on touchbench's Gaus feature sets (docs/research/weka-forest.md).

The data, feature sets and folds of touchbench/protocols/papers/gaus-table5-haart.yaml (HAART's
challenge training captures, 10 stratified folds, seed 0): for each feature set and fold, the
features touchbench computes are written as ARFF (train and test), Weka's
``weka.classifiers.trees.RandomForest`` runs on them with Gaus et al.'s parameters (1000 trees,
Weka's default int(log2 M) + 1 features per split, unlimited depth), and its accuracy is printed
beside touchbench's forest (``gaus-rf``) on the same folds and the paper's Table 5.

Not part of touchbench and not run by its tests: it needs Weka 3.6 (Debian's ``weka`` package puts it
at /usr/share/java/weka.jar) and Java. Run from the repository root:

    python docs/research/weka_forest.py --out results/research/weka-forest
    python docs/research/weka_forest.py --arff-only --sets sd --out /tmp/arff   # only the ARFF files
"""

from __future__ import annotations

import argparse
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

PROTOCOL = "gaus-table5-haart"
PAPER_RF = {"sd": 36.17, "bmh": 22.67, "msd": 54.82, "smmhh": 65.66, "lbptop": 53.01}  # Table 5, Training, RF
WEKA_JAR = "/usr/share/java/weka.jar"
_CORRECT = re.compile(r"Correctly Classified Instances\s+(\d+)\s+([\d.]+)\s*%")


def _arff_name(s: str) -> str:
    """A nominal value or a name as ARFF writes it: quoted when it has anything but letters, digits, - _ ."""
    return s if re.fullmatch(r"[A-Za-z0-9_.-]+", s) else "'" + s.replace("\\", "\\\\").replace("'", "\\'") + "'"


def write_arff(path: Path, relation: str, x: np.ndarray, y: list[str], classes: list[str]) -> Path:
    """``x`` (captures x features, float64; NaN written as Weka's missing value ``?``) with the class
    ``y`` (one of ``classes``) as an ARFF file."""
    x = np.asarray(x, dtype=np.float64)
    lines = [f"@relation {_arff_name(relation)}", ""]
    lines += [f"@attribute f{i} numeric" for i in range(x.shape[1])]
    lines += ["@attribute class {" + ",".join(_arff_name(c) for c in classes) + "}", "", "@data"]
    for row, label in zip(x, y):
        values = ["?" if not math.isfinite(v) else repr(float(v)) for v in row]
        lines.append(",".join(values + [_arff_name(label)]))
    path.write_text("\n".join(lines) + "\n")
    return path


def weka_accuracy(jar: str, train: Path, test: Path, trees: int, seed: int = 1) -> float:
    """Weka's RandomForest trained on ``train``, its accuracy (%) on ``test``."""
    cmd = ["java", "-Xmx4g", "-cp", jar, "weka.classifiers.trees.RandomForest",
           "-I", str(trees), "-K", "0", "-S", str(seed), "-t", str(train), "-T", str(test), "-o"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    tail = out.split("=== Error on test data ===", 1)
    m = _CORRECT.search(tail[1] if len(tail) == 2 else out)
    if m is None:
        raise RuntimeError(f"no test accuracy in Weka's output:\n{out[-2000:]}")
    return float(m.group(2))


def fold_features(sets: list[str]):
    """For each feature set: per fold, (train X, train y, test X, test y), from the protocol's data and folds."""
    from touchbench import load_protocol, make_feature_set
    from touchbench.engine.planning import prepare_evaluation
    from touchbench.protocols.library import PAPERS_DIR

    proto = load_protocol(PAPERS_DIR / f"{PROTOCOL}.yaml")
    prepared = prepare_evaluation(proto)
    ds = prepared.dataset
    y = ds.meta[proto.target].astype(str).to_numpy()
    for name in sets:
        folds = []
        for fold in prepared.folds[0]:
            fs = make_feature_set(name, {}, sensor=ds.sensor)
            train = [ds.captures[i] for i in fold.train]
            fs.fit(train, y[fold.train])
            x_train = np.asarray(fs.transform(train), dtype=np.float64)
            x_test = np.asarray(fs.transform([ds.captures[i] for i in fold.test]), dtype=np.float64)
            folds.append((fold.name, x_train, y[fold.train], x_test, y[fold.test]))
        yield name, sorted(set(y)), folds


def touchbench_accuracy(x_train, y_train, x_test, y_test, trees: int, seed: int) -> float:
    from touchbench import make_classifier

    clf = make_classifier("gaus-rf", random_state=seed, n_estimators=trees)
    clf.fit(x_train, y_train)
    return 100.0 * float(np.mean(clf.predict(x_test) == y_test))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True, help="where the ARFF files go (one folder per set)")
    ap.add_argument("--sets", default="sd,bmh,msd,lbptop", help="feature sets, comma separated")
    ap.add_argument("--trees", type=int, default=1000, help="trees of both forests (Gaus et al.: 1000)")
    ap.add_argument("--weka", default=WEKA_JAR, help="Weka 3.6's jar")
    ap.add_argument("--arff-only", action="store_true", help="write the ARFF files, run no classifier")
    ap.add_argument("--no-touchbench", action="store_true", help="run Weka only")
    args = ap.parse_args(argv)
    if not args.arff_only and not Path(args.weka).is_file():
        print(f"no Weka jar at {args.weka} (Debian: apt-get install weka), or pass --arff-only", file=sys.stderr)
        return 2
    print("| set | folds | Weka RandomForest % | touchbench gaus-rf % | paper (Table 5, RF) % |")
    print("|---|---|---|---|---|")
    for name, classes, folds in fold_features(args.sets.split(",")):
        folder = args.out / name
        folder.mkdir(parents=True, exist_ok=True)
        weka, ours = [], []
        for i, (fold, x_train, y_train, x_test, y_test) in enumerate(folds):
            train = write_arff(folder / f"fold{i:02d}-train.arff", f"{PROTOCOL}-{name}-{fold}-train", x_train,
                               list(y_train), classes)
            test = write_arff(folder / f"fold{i:02d}-test.arff", f"{PROTOCOL}-{name}-{fold}-test", x_test,
                              list(y_test), classes)
            if not args.arff_only:
                weka.append(weka_accuracy(args.weka, train, test, args.trees))
            if not (args.arff_only or args.no_touchbench):
                ours.append(touchbench_accuracy(x_train, y_train, x_test, y_test, args.trees, seed=i))
        fmt = (lambda v: f"{np.mean(v):.1f}" if v else "—")
        print(f"| {name} | {len(folds)} | {fmt(weka)} | {fmt(ours)} | {PAPER_RF.get(name, '—')} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
