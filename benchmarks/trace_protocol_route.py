"""The route a protocol takes through touchbench, counted with a profiler hook.

Two walks, each a `touchbench run` with one job in this process under ``sys.setprofile``:

- ``protocol``: from the command to the results store, on a leave-one-subject-out protocol of
  ``scene:tiny`` with two repetitions. A *stop* is a call into touchbench code that receives a
  protocol object (the protocol or one of its evaluations) as an argument; a *room* is a module
  with at least one stop; a *return* is a stop that hands a value back (not None). The walk ends
  at the first task the store is handed (``ResultsSession.add``). Beside it, how many times each
  scheme was built per seed (``Splitter.from_params`` and ``Splitter.__init__``): one build per
  scheme and repetition is the aim (a wrapping scheme builds its base once too).
- ``rule``: from the YAML to the first decision, on a stream-over-LOSO protocol of ``haart-sample``
  with the rule ``{name: hmm, switch: 0.01}``. A stop is a call whose arguments carry the rule (as a
  mapping, JSON text, a validated model or spec, or a list holding one); the walk ends at the first
  ``HmmRule.decide``. With ``--per-frame`` the calls of the replay loop count too.

    python benchmarks/trace_protocol_route.py

Counts depend on the code only (not on the machine); the figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import collections
import sys
import tempfile
from pathlib import Path

PROTOCOL = """name: walk
dataset: scene:tiny
scheme: loso
repetitions: 2
seed: 1
features: [[msd]]
classifiers: [{name: flagg-rf, params: {n_estimators: 5}}]
"""
STREAM = """name: route
dataset: haart-sample
target: gesture
scheme:
  name: stream
  base: loso
  idle: notouch
  per_stream: 1
  rules: [{name: hmm, switch: 0.01}]
features: [[msd]]
classifiers: [{name: flagg-rf, params: {n_estimators: 5}}]
"""
PACKAGE = str(Path(__file__).resolve().parents[1] / "touchbench")


class _Done(BaseException):
    """Raised by the hook at the end of a walk (not an ``Exception``: a task's error handling lets it by)."""


def _carries(value, wanted, depth: int = 0) -> bool:
    """Whether ``value`` is what ``wanted`` picks, or holds it (in a list, a tuple or a field of a
    dataclass such as a fold's extras, two levels down)."""
    if wanted(value):
        return True
    if depth >= 3:
        return False
    if isinstance(value, (list, tuple)):
        return any(_carries(v, wanted, depth + 1) for v in value[:50])
    fields = getattr(value, "__dataclass_fields__", None)
    return bool(fields) and any(_carries(getattr(value, f, None), wanted, depth + 1) for f in fields)


def _walk(text: str, wanted, end, per_frame: bool = False) -> dict:
    """Run ``text`` under a profiler hook; count the calls whose arguments ``wanted`` picks until
    ``end(frame)`` says the walk is over."""
    from touchbench.cli.main import cli

    stops, rooms, returns = [], collections.Counter(), [0]
    open_frames: set[int] = set()
    replay = ("decide", "push", "step", "proba", "_decide_at", "feed")

    def hook(frame, event, arg):
        code = frame.f_code
        if not code.co_filename.startswith(PACKAGE):
            return
        if event == "call":
            if end(frame):
                raise _Done
            if not per_frame and code.co_name in replay:
                return
            args = [frame.f_locals.get(n) for n in code.co_varnames[:code.co_argcount + code.co_kwonlyargcount]]
            if any(_carries(a, wanted) for a in args):
                stops.append(f"{code.co_filename[len(PACKAGE) - 10:]}:{code.co_name}")
                rooms[code.co_filename] += 1
                open_frames.add(id(frame))
        elif event == "return" and id(frame) in open_frames:
            open_frames.discard(id(frame))
            returns[0] += arg is not None

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.yaml"
        path.write_text(text)
        sys.setprofile(hook)
        try:
            cli.main(["run", str(path), "--out", str(Path(tmp) / "out"), "--jobs", "1", "--no-progress"],
                     standalone_mode=False)
        except (_Done, SystemExit):
            pass
        finally:
            sys.setprofile(None)
    return {"stops": len(stops), "functions": len(set(stops)), "rooms": len(rooms), "returns": returns[0],
            "route": stops}


def _builds() -> collections.Counter:
    """Count every scheme build by (scheme, seed) from now on: a call of ``Splitter.__init__`` (its
    subclasses call it once) or of ``Splitter.from_params`` (which builds without it), where it exists."""
    from touchbench.protocols.schemes.base import Splitter

    built: collections.Counter = collections.Counter()
    real_init = Splitter.__init__

    def init(self, target="gesture", random_state=None, **params):
        built[(self.name, random_state)] += 1
        real_init(self, target, random_state, **params)

    Splitter.__init__ = init
    if "from_params" in Splitter.__dict__:
        real_from = Splitter.__dict__["from_params"].__func__

        def from_params(cls, params, target="gesture", random_state=None):
            built[(cls.name, random_state)] += 1
            return real_from(cls, params, target=target, random_state=random_state)

        Splitter.from_params = classmethod(from_params)
    return built


def _stored(frame) -> bool:
    """Whether ``frame`` hands the store a finished task (``add`` today; ``write_task`` or a task
    writer's ``write`` in older code)."""
    code = frame.f_code
    return "/results/" in code.co_filename and code.co_name in ("add", "write_task", "write")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-frame", action="store_true", help="count the replay loop's calls too")
    ap.add_argument("--route", action="store_true", help="print every stop")
    args = ap.parse_args()
    from touchbench.protocols.schema import Protocol

    built = _builds()
    walk = _walk(PROTOCOL, lambda v: isinstance(v, Protocol), _stored)
    twice = {k: n for k, n in built.items() if n > 1}
    print(f"protocol, `touchbench run` to the store (LOSO on scene:tiny, 2 repetitions): {walk['stops']} stops "
          f"({walk['functions']} functions), {walk['rooms']} rooms, {walk['returns']} returns")
    print(f"  schemes built: {sum(built.values())} ({', '.join(f'{n} x{c}' for (n, _), c in sorted(built.items()))}); "
          f"built twice for one seed: {twice or 'none'}")
    rule = _walk(STREAM, _is_rule, lambda f: f.f_code.co_name == "decide" and "self" in f.f_locals
                 and type(f.f_locals["self"]).__name__ == "HmmRule", per_frame=args.per_frame)
    print(f"stream rule, YAML to first decision{' (per-frame calls too)' if args.per_frame else ''}: "
          f"{rule['stops']} stops ({rule['functions']} functions), {rule['rooms']} rooms, {rule['returns']} returns")
    if args.route:
        for name, w in (("protocol", walk), ("rule", rule)):
            print(f"\n{name}:\n  " + "\n  ".join(w["route"]))


def _is_rule(v) -> bool:
    """Whether ``v`` is the rule ``{name: hmm, switch: 0.01}`` in one of its forms."""
    if isinstance(v, dict):
        return v.get("name") == "hmm" and v.get("switch") == 0.01
    if isinstance(v, str):
        return '"hmm"' in v and "0.01" in v
    declared = getattr(v, "declared", None)
    if isinstance(declared, dict):
        return _is_rule({"name": "hmm", **declared}) or _is_rule(declared)
    return type(v).__name__ == "HmmParams" and getattr(v, "switch", None) == 0.01


if __name__ == "__main__":
    main()
