"""No test depends on how fast the machine is: a test that waits for another process, thread or
file (a subprocess's timeout, a join, a poll's deadline, a watchdog) is bounded by
``helpers.SUBPROCESS_HANG_S``, a bound only a hang reaches, never by a number of seconds of its own
that a slow or busy machine can run past."""

from __future__ import annotations

import re
from pathlib import Path

from helpers import SUBPROCESS_HANG_S

TESTS = Path(__file__).resolve().parent
# a waiting call given a number of seconds as a literal
FIXED_WAIT = re.compile(r"(?:\btimeout=|\bwait=|\.join\(|\.wait\(|\.get\(timeout=|dump_traceback_later\()\s*(\d+(?:\.\d+)?)")


def fixed_waits(text: str) -> list[str]:
    return [m.group(0) for m in FIXED_WAIT.finditer(text) if float(m.group(1)) < SUBPROCESS_HANG_S]


def test_the_check_finds_a_fixed_wait():
    assert fixed_waits("subprocess.run(cmd, capture_output=True, timeout=120)") == ["timeout=120"]
    assert fixed_waits("p.join(60)\nassert held.wait(60)\nrun(wait=30)") == [".join(60", ".wait(60", "wait=30"]
    assert fixed_waits("faulthandler.dump_traceback_later(600, exit=True)") == ["dump_traceback_later(600"]
    assert fixed_waits("subprocess.run(cmd, timeout=SUBPROCESS_HANG_S)\np.join(SUBPROCESS_HANG_S)") == []


def test_no_test_waits_for_a_fixed_number_of_seconds():
    found = {p.name: w for p in sorted(TESTS.glob("*.py")) if p.name != Path(__file__).name
             for w in [fixed_waits(p.read_text(encoding="utf-8"))] if w}
    assert not found, f"bound these waits by helpers.SUBPROCESS_HANG_S: {found}"
    assert SUBPROCESS_HANG_S >= 20 * 60
