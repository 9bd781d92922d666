"""Every shipped reference result is a run of its protocol as the package ships it today.

A reference (``leaderboard --reference NAME``) is compared row by row with a user's run of the same
protocol; it misleads without a word when the protocol it was saved from has since changed (a
method or an evaluation added), when today's defaults run the protocol differently (the challenge
split's five seeds where the reference has one), or when it lacks a column the user's run has (CPU
latency, without which the Pareto front falls back to wall-clock time). The check reads the
protocol text the reference's manifest saved with today's code and compares what it runs (its
content hash: every setting with its default, comments and descriptions left out) with the shipped
protocol's, then the seeds and repetitions the reference ran with the ones the protocol asks for
today. A field added since with a default that changes nothing (a flag that is off) is not a
difference: the saved text read today gets it too.

The references listed in ``STALE`` are known to be out of date and each takes hours on two cores
to regenerate (``make reference-results REFERENCES=NAME``); each is a strict expected failure, so
regenerating one without taking it off the list fails too.
"""

from __future__ import annotations

import json

import pandas as pd
import pytest

from touchbench.protocols.library import find_protocol
from touchbench.protocols.loading import load_protocol, parse_protocol
from touchbench.reports.reference import find_reference, shipped_names

#: reference name -> why it is stale and what regenerates it.
STALE = {
    "touch-all": "saved with 16 of its 18 methods (not touch-et-quiet, touch-et-quiet-win) and 7 of its "
                 "11 evaluations; `make reference-results REFERENCES=touch-all`: about 8 hours of tasks "
                 "on two cores",
}


def _cases() -> list:
    cases = []
    for name in shipped_names():
        marks = [pytest.mark.xfail(strict=True, reason=STALE[name])] if name in STALE else []
        cases.append(pytest.param(name, marks=marks, id=name))
    return cases


def test_the_stale_list_names_shipped_references():
    assert set(STALE) <= set(shipped_names())


def _check_evaluation(name: str, folder, now, path) -> None:
    where = f"{name}/{folder.name}"
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    saved = manifest["protocol"]
    then = {p.evaluation or "": p for p in parse_protocol(saved["text"], path).evaluation_protocols()}
    assert then[now.evaluation or ""].content_hash == now.content_hash, f"{where}: the protocol has changed since"
    assert (saved["seed"], saved["repetitions"]) == (now.seed, now.repetitions), (
        f"{where}: saved with seed {saved['seed']} x {saved['repetitions']} repetitions, the protocol "
        f"asks for {now.seed} x {now.repetitions}")
    scores = pd.read_parquet(folder / "scores.parquet")
    assert scores["repetition"].nunique() == now.repetitions, f"{where}: not every repetition was run"
    captures = scores[scores["latency_ms"].notna()]  # stream tasks report their latency apart
    assert captures.empty or captures["latency_cpu_ms"].notna().all(), (
        f"{where}: no CPU latency (saved before it was measured)")


@pytest.mark.parametrize("name", _cases())
def test_a_shipped_reference_is_a_run_of_its_shipped_protocol(name):
    ref = find_reference(name)
    path = find_protocol(ref.index["protocol"])
    protocol = load_protocol(path)
    now = {p.evaluation or "": p for p in protocol.evaluation_protocols()}
    saved = {e["evaluation"]: ref.path / e["folder"] for e in ref.evaluations()}
    assert sorted(saved) == sorted(now), f"{name}: saved evaluations {sorted(saved)}, the protocol has {sorted(now)}"
    for evaluation, folder in saved.items():
        _check_evaluation(name, folder, now[evaluation], path)
