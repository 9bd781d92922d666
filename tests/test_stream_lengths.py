"""The stream scheme's lengths checked against the data when a protocol is planned (``protocols
validate`` and ``run``), each refusal at its file, line and field. haart-sample: two subjects, each
with one 8-s capture (432 frames at 54 Hz) of ``notouch`` and of six gestures; values worked out by
hand from those lengths."""

from __future__ import annotations

import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.engine.planning import plan_run
from touchbench.protocols.loading import parse_protocol

# the protocol's first seven lines; what a case adds starts at line 8
BASE = """name: t
dataset: haart-sample
target: gesture
scheme:
  name: stream
  base: loso
  idle: notouch
{extra}methods: [touch-et-fast]
"""


def _plan(extra: str, tmp_path):
    return plan_run(parse_protocol(BASE.format(extra=extra), "p.yaml"), cache_root=tmp_path)


def _refused(extra: str, tmp_path) -> str:
    with pytest.raises(TouchbenchError) as e:
        _plan(extra, tmp_path)
    return str(e.value)


@pytest.mark.parametrize("extra, where, words", [
    # 0.009 s x 54 Hz = 0.486 frames, rounded to none (the recogniser used to make it one frame)
    ("  windows_s: [0.5, 0.009]\n", "p.yaml:8: scheme.windows_s[1]:", "0.009 s is 0 frames at 54 Hz"),
    ("  hop_s: 0.009\n", "p.yaml:8: scheme.hop_s:", "a window is at least one frame (0.0185 s)"),
    ("  train_on: streams\n  train_hop_s: 0.005\n", "p.yaml:9: scheme.train_hop_s:", "0 frames at 54 Hz"),
    # 8.01 s x 54 = 432.54 -> 433 frames, one more than the 432 of every notouch capture
    ("  gap_s: [1, 8.01]\n", "p.yaml:8: scheme.gap_s[1]:", "the shortest is 8 s (432 frames at 54 Hz)"),
    # gaps of exactly 1 s: a stream is 6 captures of 8 s and 7 gaps of 1 s = 55 s (2970 frames)
    ("  gap_s: [1, 1]\n  hop_s: 55\n", "p.yaml:9: scheme.hop_s:", "not shorter than the shortest stream"),
    ("  gap_s: [1, 1]\n  windows_s: [55, 60]\n", "p.yaml:9: scheme.windows_s[0]:", "(s01: 55 s)"),
])
def test_a_length_the_data_cannot_hold_is_refused_at_its_field(extra, where, words, tmp_path):
    msg = _refused(extra, tmp_path)
    assert msg.startswith(where) and words in msg, msg


@pytest.mark.parametrize("extra", [
    "  windows_s: [0.5, 0.01]\n",  # 0.54 frames: one
    "  gap_s: [1, 8]\n",  # 432 frames: the whole of the shortest notouch capture
    "  gap_s: [1, 1]\n  hop_s: 54.9\n  windows_s: [54.9]\n",  # 2965 frames, under the 2970 of each stream
])
def test_the_bounds_themselves_are_planned(extra, tmp_path):
    plan = _plan(extra, tmp_path)
    assert len(plan.tasks) == 2
