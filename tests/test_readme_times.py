"""Every README command that runs a shipped protocol (``touchbench run NAME``) or one of the long make
targets (``make demo``, ``make examples``, ``make touch-all``, ``make reproduce-papers``) says what it
costs before anyone types it: its number of tasks and its time, on its own line or in the sentence next
to it that names it, even when it takes seconds (how long a reference run took depends on how loaded
its machine was, so no command is exempted by it)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = {p.stem for p in (ROOT / "touchbench" / "protocols").rglob("*.yaml")}

RUNS = re.compile(r"^(?:touchbench run (?P<protocol>[\w.-]+)|make (?P<target>demo|examples|touch-all|reproduce-papers))(?![\w-])")
TIME = re.compile(r"\b\d+(?:\.\d+)?\s*(?:s|min|minutes?|h|hours?|days?)\b|\b(?:a|one|two|a few)\s+(?:minute|hour)s?\b"
                  r"|\b(?:seconds|minutes|hours|days)\b")
TASKS = re.compile(r"\b\d[\d,]*\s+(?:[\w-]+\s+)?tasks?\b")


def says_cost(text: str) -> bool:
    return bool(TIME.search(text) and TASKS.search(text))


def sentences(paragraph: str) -> list[str]:
    return re.split(r"(?<=[.])\s+(?=[A-Z`(])", " ".join(paragraph.split()))


def blocks(readme: str) -> list[tuple[str, list[str]]]:
    """The README as ("code" | "prose", lines) blocks, in order: fenced blocks, indented (4 spaces)
    blocks and paragraphs; a code block's lines stripped."""
    out: list[tuple[str, list[str]]] = []
    current: tuple[str, list[str]] | None = None
    fenced = False
    for line in readme.splitlines():
        if line.startswith("```") or (not fenced and not line.strip()):
            if current and current[1]:
                out.append(current)
            fenced = fenced != line.startswith("```")
            current = ("code", []) if fenced else None
        elif current is None:
            current = ("code" if line.startswith("    ") else "prose", [line.strip()])
        else:
            current[1].append(line.strip())
    if current and current[1]:
        out.append(current)
    return out


def commands(readme: str) -> list[dict]:
    """Each command line of a code block that runs a shipped protocol or a long target, with the
    sentences around its block (the last one before, the first one after), and each such command
    written in the prose only (an inline ``make examples``: the sentence that holds it)."""
    found, in_code = [], set()
    parts = blocks(readme)
    for i, (kind, lines) in enumerate(parts):
        if kind != "code":
            continue
        before = sentences(" ".join(parts[i - 1][1]))[-1:] if i and parts[i - 1][0] == "prose" else []
        after = sentences(" ".join(parts[i + 1][1]))[:1] if i + 1 < len(parts) and parts[i + 1][0] == "prose" else []
        for line in lines:
            m = RUNS.match(line)
            if m and (m["target"] or m["protocol"] in SHIPPED):
                key = m["protocol"] or f"make {m['target']}"
                in_code.add(key)
                found.append({"key": key, "line": line, "around": before + after})
    for kind, lines in parts:
        for sentence in sentences(" ".join(lines)) if kind == "prose" else []:
            for span in re.findall(r"`([^`]+)`", sentence):
                m = RUNS.match(span)
                key = m and (m["protocol"] if m["protocol"] in SHIPPED else None if m["protocol"] else f"make {m['target']}")
                if key and key not in in_code and key not in {c["key"] for c in found}:
                    found.append({"key": key, "line": sentence, "around": []})
    return found


def costed(command: dict) -> bool:
    """The command's line says its tasks and time, or a sentence around it that names it does."""
    name = command["key"].removeprefix("make ")
    return says_cost(command["line"]) or any(says_cost(s) and name in s for s in command["around"])


def test_the_parser_finds_commands_and_their_costs():
    readme = ("Intro.\n\n```bash\nmake demo   # 20 tasks, about 4 min\ntouchbench run stream-haart -j 2\n"
              "touchbench run MINE.yaml\n```\n\nThe run `stream-haart` has 10 tasks, 9 min on two cores. Then more.\n\n"
              "    touchbench run curves-haart -j 2\n\nIt is long.\n\n"
              "`make examples` runs them. Later `make examples` again, 160 tasks in 3 min.\n")
    found = commands(readme)
    assert [(c["key"], costed(c)) for c in found] == [
        ("make demo", True), ("stream-haart", True), ("curves-haart", False), ("make examples", False)]
    assert found[2]["around"] == ["Then more.", "It is long."]  # an indented block: the sentences on each side
    assert says_cost("12 tasks, about 25 min on two loaded cores") and says_cost("(10 folds = 40 tasks), seconds")
    assert not says_cost("20 tasks") and not says_cost("about 25 min") and not says_cost("10 folds, 3 min")


def test_every_long_readme_command_says_its_tasks_and_time():
    found = commands((ROOT / "README.md").read_text(encoding="utf-8"))
    keys = {c["key"] for c in found}
    assert {"make demo", "make examples", "make reproduce-papers", "touch-all", "socialtouch-loso",
            "socialtouch-within", "curves-haart", "example-haart-loso"} <= keys
    missing = [c["line"] for c in found if not costed(c)]
    assert missing == [], ("README commands without their number of tasks and their time on two cores "
                           "(on the line, or in the sentence before or after its block that names it)", missing)
