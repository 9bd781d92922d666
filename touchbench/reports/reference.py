"""Reference results: a shipped protocol's per-fold results, to compare a new method against
without rerunning the shipped methods.

A reference is a finished run's results, saved under a name by
``touchbench reference save RESULTS --name NAME``: per evaluation, its
``scores.parquet`` (one row per fold and method), ``predictions.parquet``
(one row per test capture and method, without the class probabilities, so
that a comparison on one test set can pair the captures) and ``manifest.json`` (the touchbench version, the
machine, the package versions and the test set's content hash), and a
``reference.json`` that lists them (each evaluation's folder, evaluation name, dataset, test-set
hash and methods; an index without the evaluation name, saved before it was recorded, is read as
naming each evaluation by its folder).

Where they live: the user's references in the user's folder of references
(:func:`touchbench.core.paths.user_reference_dir`: ``$TOUCHBENCH_REFERENCE_DIR``,
else ``reference/`` in the user's data directory), where ``save`` writes by
default; the shipped ones in the package (``touchbench/data/reference/<name>/``),
read-only: a user reference cannot take a shipped one's name. Only
``--to touchbench/data/reference`` (``make reference-results``, in a source
checkout) writes there. A name is found among the user's references first, then
the shipped ones (a user reference made before a shipped one of its name existed
keeps its meaning; ``reference list`` says which shipped one it hides).

A name is 1 to 64 ASCII letters, digits, ``-``, ``_`` and ``.``, starting with
a letter or a digit (:func:`check_reference_name`): it is one folder, never a path.
Saving replaces the reference's own folder whole (:func:`touchbench.core.atomic.replace_dir`),
only with ``force``, and only a folder that is a reference.

``touchbench leaderboard RESULTS --reference NAME`` places the reference's
methods beside the user's, as other methods ("<label> (reference NAME)"),
only for the evaluations whose test set has the same content (the SHA-256 of
its captures' frames and labels that the ledger records): the same captures,
whatever the protocol or the reader called them. Where several of the
reference's evaluations test the same captures (two splits of one dataset),
the one of the results' evaluation name is placed beside them (all of them
when none has it). It refuses when no evaluation of the results matches,
and says which matched. The folds are
paired as for any two runs: by the test captures of each fold.
"""

from __future__ import annotations

import json
import re
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

import pandas as pd

from ..core.atomic import atomic_write_bytes, replace_dir
from ..core.errors import TouchbenchError
from ..core.paths import user_reference_dir
from ..core.suggest import did_you_mean
from ..results.checksums import changed_files, file_checksums, recorded_checksums
from .results import ResultSet, find_result_dirs, load_results, read_manifest

__all__ = ["Reference", "ReferenceError", "add_reference", "check_reference_name", "find_reference",
           "reference_names", "save_reference", "shipped_names"]

SHIPPED = Path(__file__).resolve().parent.parent / "data" / "reference"
INDEX = "reference.json"
#: what a reference name may be: one folder name, portable, never hidden, never a path
NAME_RULE = "1 to 64 ASCII letters, digits, '-', '_' or '.', starting with a letter or a digit"
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
#: the files a reference keeps of each evaluation, beside its manifest
SAVED_FILES = ("scores.parquet", "predictions.parquet")


class ReferenceError(TouchbenchError):
    """A reference that does not exist, or whose test sets are not the user's."""


@dataclass(frozen=True)
class Reference:
    """A saved reference: its name, folder and index (protocol, version, machine, evaluations)."""

    name: str
    path: Path
    index: dict[str, Any]
    origin: str = "shipped"  # "user" or "shipped"

    def evaluations(self) -> list[dict[str, str]]:
        """One entry per saved evaluation: its ``folder`` (relative to the reference), ``evaluation``
        (the protocol's evaluation name; "" for a protocol of one) and ``test_set`` (content hash).
        Two evaluations may test the same captures (another split of one dataset): each keeps its
        own entry. An index saved before the evaluation's name was recorded gives the folder's name
        when it saved several (a run's evaluations are folders of their names)."""
        saved = self.index.get("evaluations", [])
        return [{"folder": e["folder"], "test_set": e["test_set"],
                 "evaluation": e.get("evaluation", Path(e["folder"]).name if len(saved) > 1 else "")}
                for e in saved]

    def describe(self) -> str:
        i = self.index
        return (f"reference {self.name}: protocol {i.get('protocol')}, touchbench {i.get('touchbench_version')} "
                f"on {i.get('machine')}, {i.get('created')}")


def check_reference_name(name: str) -> str:
    """``name`` when it is a valid reference name (:data:`NAME_RULE`), else a :class:`ReferenceError`."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ReferenceError(f"{name!r} is not a valid reference name: use {NAME_RULE}")
    return name


def _is_shipped(folder: Path) -> bool:
    return folder.resolve() == SHIPPED.resolve()


def _check_folder(root: Path, setting: str) -> Path:
    """``root`` when it is a folder or does not exist yet; a file there is refused naming ``setting``."""
    if root.exists() and not root.is_dir():
        raise ReferenceError(f"{root}: the folder of references ({setting}) is a file, not a folder: "
                             "set it to a folder (it is made if missing)")
    return root


def _search_path() -> list[tuple[str, Path]]:
    """(origin, folder) in the order a name is looked for: the user's references, then the shipped ones."""
    user = _check_folder(user_reference_dir(), "$TOUCHBENCH_REFERENCE_DIR or reference/ in the user's data directory")
    return ([] if _is_shipped(user) else [("user", user)]) + [("shipped", SHIPPED)]


def _names_in(root: Path) -> list[str]:
    """The references in ``root``: its folders with a ``reference.json`` and a valid name (a
    leftover temporary folder, or a folder no valid name reaches, is not one)."""
    if not root.is_dir():
        return []
    return sorted(p.parent.name for p in root.glob(f"*/{INDEX}") if _NAME.fullmatch(p.parent.name))


def shipped_names() -> list[str]:
    """The names of the references shipped in the package (read-only)."""
    return _names_in(SHIPPED)


def reference_names() -> list[str]:
    """The names of every reference found (the user's first, then the shipped ones; each name once)."""
    names: dict[str, None] = {}
    for _, root in _search_path():
        names.update(dict.fromkeys(_names_in(root)))
    return list(names)


def _read_index(index: Path) -> dict[str, Any]:
    """A reference's ``reference.json``, checked: a mapping whose ``evaluations`` is a list of
    mappings with a ``folder`` and a ``test_set``; anything else is refused naming the file."""
    fix = "save the reference again (`touchbench reference save RESULTS --name NAME --force`) or remove its folder"
    try:
        data = json.loads(index.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ReferenceError(f"{index}: damaged reference index, not JSON ({e}): {fix}") from None
    if not isinstance(data, dict):
        raise ReferenceError(f"{index}: damaged reference index: a JSON {type(data).__name__} where a mapping "
                             f"(protocol, evaluations, ...) is expected: {fix}")
    evaluations = data.get("evaluations", [])
    if not isinstance(evaluations, list) or not all(
            isinstance(e, dict) and isinstance(e.get("folder"), str) and isinstance(e.get("test_set"), str)
            for e in evaluations):
        raise ReferenceError(f"{index}: damaged reference index: 'evaluations' must be a list of mappings "
                             f"with a 'folder' and a 'test_set': {fix}")
    return data


def find_reference(name: str) -> Reference:
    """The reference ``name`` (the user's before a shipped one); a name that is not saved is refused
    with the names that are."""
    check_reference_name(name)
    for origin, root in _search_path():
        index = root / name / INDEX
        if index.is_file():
            return Reference(name, index.parent, _read_index(index), origin)
    known = reference_names()
    raise ReferenceError(f"no reference results named {name!r}{did_you_mean(name, known)}; "
                         f"saved: {', '.join(known) or 'none'}")


def _test_set(manifest: dict[str, Any]) -> str | None:
    return (manifest.get("ledger") or {}).get("test_set")


def _machine(manifest: dict[str, Any]) -> str:
    p = manifest.get("platform") or {}
    cpu = p.get("cpu_model") or p.get("processor") or p.get("machine") or "?"
    return f"{cpu}, {p.get('cpu_count', '?')} CPUs, {p.get('platform', '?')}"


def _evaluation_entry(folder: Path, root: Path) -> dict[str, Any]:
    m = read_manifest(folder)
    if not _test_set(m) or not (folder / "scores.parquet").is_file():
        raise ReferenceError(f"{folder}: not a finished results folder with a recorded test set "
                             "(scores.parquet and the manifest's test-set hash are needed)")
    if m.get("finished_at") is None:
        raise ReferenceError(f"{folder}: the run is not finished; finish it before saving it as a reference")
    changed = changed_files(folder, recorded_checksums(m))
    if changed:
        raise ReferenceError(f"{folder}: {'; '.join(changed)}: not saved as a reference (run its protocol into this "
                             "folder again: the run rebuilds its files from the results of each task)")
    rel = folder.relative_to(root).as_posix() if folder != root else (m.get("protocol") or {}).get("name", "run")
    methods = sorted(set(pd.read_parquet(folder / "scores.parquet", columns=["classifier"])["classifier"].astype(str)))
    return {"folder": rel, "source": folder, "test_set": _test_set(m),
            "evaluation": (m.get("protocol") or {}).get("evaluation") or "",
            "dataset": (m.get("dataset") or {}).get("ref"), "methods": methods, "manifest": m}


def _write_predictions(src: Path, dest: Path) -> None:
    """The predictions without their class probabilities (the comparisons read the labels only):
    a reference stays small whatever the number of classes."""
    preds = pd.read_parquet(src)
    preds.drop(columns=[c for c in preds.columns if c.startswith("proba_")]).to_parquet(dest, index=False)


def _portable(manifest: dict[str, Any]) -> dict[str, Any]:
    """The manifest without the paths of the machine that ran it (the protocol file's name is kept)."""
    m = json.loads(json.dumps(manifest))
    if (m.get("protocol") or {}).get("path"):
        m["protocol"]["path"] = Path(m["protocol"]["path"]).name
    (m.get("run") or {}).pop("results_dir", None)
    return m


def _saved_manifest(manifest: dict[str, Any], folder: Path) -> bytes:
    """The manifest of a reference's evaluation saved in ``folder``: :func:`_portable`, recording the
    SHA-256 of the files saved there (as a run does of those it wrote), which reports check."""
    m = _portable(manifest)
    if not isinstance(m.get("tasks"), dict):
        m["tasks"] = {}
    m["tasks"]["merged_files"] = file_checksums(folder, SAVED_FILES)
    return (json.dumps(m, indent=2) + "\n").encode()


def _destination(root: Path, name: str, force: bool) -> Path:
    """The folder the reference ``name`` goes to under ``root``, once it is sure that saving there
    replaces nothing it should not: a shipped reference's name is refused outside the shipped
    folder, an existing reference is replaced only with ``force``, anything else never."""
    if not _is_shipped(root) and name in shipped_names():
        raise ReferenceError(f"{name!r} is the name of a shipped reference (shipped references are read-only): "
                             "choose another --name")
    out = root / name
    if out.is_symlink() or (out.exists() and not (out / INDEX).is_file()):
        raise ReferenceError(f"{out} exists and is not a saved reference: it is left as it is; "
                             "choose another --name or --to")
    if out.exists() and not force:
        raise ReferenceError(f"a reference named {name!r} exists in {root}: add --force to replace it")
    return out


def _index(name: str, entries: list[dict[str, Any]]) -> dict[str, Any]:
    first = entries[0]["manifest"]
    return {"name": name, "protocol": (first.get("protocol") or {}).get("name"),
            "touchbench_version": first.get("touchbench_version"),
            "git_revision": (first.get("git") or {}).get("revision"), "machine": _machine(first),
            "created": first.get("finished_at"),
            "evaluations": [{k: e[k] for k in ("folder", "evaluation", "test_set", "dataset", "methods")}
                            for e in entries]}


def _write_reference(out: Path, name: str, entries: list[dict[str, Any]]) -> None:
    for e in entries:
        (out / e["folder"]).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(e["source"] / "scores.parquet", out / e["folder"] / "scores.parquet")
        if (e["source"] / "predictions.parquet").is_file():
            _write_predictions(e["source"] / "predictions.parquet", out / e["folder"] / "predictions.parquet")
        atomic_write_bytes(out / e["folder"] / "manifest.json", _saved_manifest(e["manifest"], out / e["folder"]))
    atomic_write_bytes(out / INDEX, (json.dumps(_index(name, entries), indent=2) + "\n").encode())


def save_reference(results: str | Path, name: str, dest: str | Path | None = None, force: bool = False) -> Path:
    """Save the finished run in ``results`` (a results folder, or one holding an evaluation per
    subfolder) as the reference ``name`` under ``dest`` (default: the user's references,
    :func:`touchbench.core.paths.user_reference_dir`); returns the reference's folder. An existing
    reference of that name is replaced whole, and only with ``force``; the replacement is atomic
    (written beside it, then renamed), so a failure leaves the old one as it was."""
    check_reference_name(name)
    root = _check_folder(Path(dest) if dest is not None else user_reference_dir(),
                         "--to" if dest is not None else "$TOUCHBENCH_REFERENCE_DIR")
    out = _destination(root, name, force)
    src = Path(results)
    entries = [_evaluation_entry(d, src) for d in find_result_dirs(src)]
    if not entries:
        raise ReferenceError(f"{src}: no results folder found")
    replace_dir(out, lambda tmp: _write_reference(tmp, name, entries))
    return out


def _matching(ref: Reference, rs: ResultSet) -> list[dict[str, str]]:
    """The reference's evaluations to place beside ``rs``: those whose test set is one of ``rs``'s
    evaluations'; where several of them test those captures, the one of the same evaluation name
    (all of them when none has it)."""
    chosen: dict[str, dict[str, str]] = {}
    for src in rs.sources:
        same = [e for e in ref.evaluations() if src.get("test_set") and e["test_set"] == src["test_set"]]
        named = [e for e in same if e["evaluation"] == (src.get("evaluation") or "")]
        chosen.update((e["folder"], e) for e in (named if len(same) > 1 and named else same))
    return list(chosen.values())


def _as_reference(rs: ResultSet, name: str) -> ResultSet:
    """The reference's rows as methods of their own: another method id, the label marked."""
    tag = f" (reference {name})"
    scores = rs.scores.copy()
    scores["method_id"] = "ref-" + scores["method_id"].astype(str)
    scores["classifier"] = scores["classifier"].astype(str) + tag
    preds = rs.predictions
    if preds is not None:
        preds = preds.copy()
        preds["method_id"] = "ref-" + preds["method_id"].astype(str)
    return ResultSet(scores=scores, predictions=preds, sources=rs.sources)


def add_reference(rs: ResultSet, name: str) -> tuple[ResultSet, list[str]]:
    """``rs`` with the reference ``name``'s methods added where a test set matches, and the lines
    that say what was added; refused when no evaluation of ``rs`` has a test set of the reference."""
    ref = find_reference(name)
    n = len(ref.evaluations())
    matched = sorted(e["folder"] for e in _matching(ref, rs))
    if not matched:
        raise ReferenceError(
            f"{ref.describe()}: none of its {n} test set(s) has the content of the "
            "results given (other captures, labels or frames), so their accuracies are not comparable; "
            "run the reference's protocol on the same data")
    extra = _as_reference(load_results([ref.path / f for f in matched]), name)
    combined = ResultSet(
        scores=pd.concat([rs.scores, extra.scores], ignore_index=True, sort=False),
        predictions=_concat_optional([rs.predictions, extra.predictions]),
        sources=rs.sources + extra.sources)
    lines = [f"beside {ref.describe()}: the test set of {', '.join(matched)} has the same "
             f"content as these results' ({len(matched)} of {n} evaluation(s))"]
    return combined, lines


def _concat_optional(frames: Iterable[pd.DataFrame | None]) -> pd.DataFrame | None:
    present = [f for f in frames if f is not None]
    return pd.concat(present, ignore_index=True, sort=False) if present else None
