"""``touchbench data``: list, inspect, export and convert datasets; the file formats.

``list`` reads the registry index (:mod:`touchbench.core.listing`): the datasets' modules, and the
commands that read and write files (:mod:`.data_files`, their options taken from the file-format
registry), are imported by the commands that need them."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from ..core.listing import cached_rows
from .common import LazyGroup, echo_json, example, json_option
from .plugins import package_of, plugin_note

if TYPE_CHECKING:
    from ..datasets.model import TouchDataset


@click.group(cls=LazyGroup, lazy={"export": "touchbench.cli.data_files:export",
                                  "convert": "touchbench.cli.data_files:convert"},
             epilog=example("touchbench data list", "touchbench data info haart"))
def data() -> None:
    """Datasets: real readers, the cache, exports."""


def dataset_table() -> list[dict]:
    """One row per registered dataset: name, description, package (touchbench or the plugin's
    distribution and version) and the note a line listing ends with."""
    from ..datasets import DATASETS

    return [{"name": e.name, "description": e.description, "package": package_of(e), "note": plugin_note(e)}
            for e in DATASETS.entries()]


@data.command("list", epilog=example("touchbench data list --json"))
@json_option
def list_(as_json: bool) -> None:
    """Registered datasets (scenes: `touchbench scenes list`)."""
    rows = cached_rows("datasets", dataset_table, ("touchbench.datasets",))
    if as_json:
        echo_json([{k: r[k] for k in ("name", "description", "package")} for r in rows])
        return
    for r in rows:
        click.echo(f"{r['name']:18s} {r['description']}{r['note']}")


def _load(name: str, cache_dir: str | None, data_dir: str | None, refresh: bool = False) -> TouchDataset:
    from ..catalog import load_dataset, parse_dataset_ref

    kw = {}
    if parse_dataset_ref(name).kind == "registered":
        kw = {"cache_dir": cache_dir, "data_dir": data_dir, "refresh": refresh}
    return load_dataset(name, **kw)


def format_info(info: dict) -> str:
    s = info["sensor"]
    fpc = info["frames_per_capture"]
    lines = [
        f"dataset       {info['name']}",
        f"captures      {info['captures']}",
        f"subjects      {info['subjects']}",
        f"gestures      {info['gestures']}",
        f"sensor        {s['name']}: {s['grid'][0]} x {s['grid'][1]} at {s['frame_rate']:g} Hz, range "
        f"{s['value_range'][0]:g}..{s['value_range'][1]:g}",
        f"frames        {fpc['min']}..{fpc['max']} per capture (median {fpc['median']:g})",
        f"values        {info['value_range'][0]:g}..{info['value_range'][1]:g} ({info['dtype']})",
    ]
    for key, label in (("time_steps_ms", "time steps"), ("recorded_time_steps_ms", "recorded")):
        steps = info.get(key)
        if steps:
            lines.append(f"{label:13s} median {steps['median']:.4g} ms, 95th percentile {steps['p95']:.4g} ms "
                         f"({steps['min']:.4g}..{steps['max']:.4g})")
    lines += [
        f"content hash  {info['content_hash']}",
        "by subject    " + ", ".join(f"{k}: {v}" for k, v in info["by_subject"].items()),
        "by gesture    " + ", ".join(f"{k}: {v}" for k, v in info["by_gesture"].items()),
    ]
    if "by_split" in info:
        lines.append("by split      " + ", ".join(f"{k}: {v}" for k, v in info["by_split"].items()))
    st = info.get("streams") or {}
    if st.get("source") == "recorded":
        lines.append(f"streams       recorded: {st['recordings']} recordings labelled frame by frame "
                     f"({st['seconds']:.0f} s)")
    elif st:
        lines.append(f"streams       spliced: {st['note']}")
    return "\n".join(lines + provenance_lines(info.get("provenance", {})))


SHOWN = 20  # list entries of the provenance shown by `data info` (--json gives them all)


def provenance_lines(prov: dict) -> list[str]:
    """A dataset's provenance as ``data info`` prints it: one line a field, a list or mapping one
    indented line an entry (the first :data:`SHOWN`)."""
    lines = []
    ph = prov.get("placeholders")
    if ph is not None:
        if ph:
            lines.append(f"placeholders  {len(ph)} byte-identical copies found, left out:")
            lines += [f"  {p['file']} = {p['copy_of']} ({p['reason']})" for p in ph]
        else:
            lines.append("placeholders  none (no byte-identical copies)")
    for k, v in prov.items():
        if k == "placeholders":
            continue
        if isinstance(v, dict):
            v = [f"{a}: {b}" for a, b in v.items()]
        if not isinstance(v, list):
            lines.append(f"{k:13s} {v}")
            continue
        lines.append(f"{k:13s} ({len(v)})")
        lines += [f"  {', '.join(f'{a}: {b}' for a, b in e.items()) if isinstance(e, dict) else e}" for e in v[:SHOWN]]
        if len(v) > SHOWN:
            lines.append(f"  ... and {len(v) - SHOWN} more (--json lists every one)")
    return lines


@data.command(epilog=example("touchbench data info haart", "touchbench data info my-recordings.parquet --json"))
@click.argument("name")
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None, help="Cache folder (default: user cache).")
@click.option("--data-dir", type=click.Path(file_okay=False), default=None, help="The dataset's own folder (default: in $TOUCHBENCH_DATA_DIR, else in shared/data beside the working "
              "directory).")
@click.option("--refresh", is_flag=True, help="Rebuild the cache entry.")
@json_option
def info(name: str, cache_dir, data_dir, refresh: bool, as_json: bool) -> None:
    """Counts, ranges, placeholders and hash of dataset NAME (or scene:NAME or a Parquet file)."""
    inf = _load(name, cache_dir, data_dir, refresh).info()
    echo_json(inf) if as_json else click.echo(format_info(inf))


@data.command("formats", epilog=example("touchbench data formats"))
@json_option
def formats(as_json: bool) -> None:
    """File formats: what reads and writes them, and the options they take."""
    from ..datasets.formats import FORMATS

    if as_json:
        echo_json([{"name": e.name, "description": e.description, "reads": e.obj.reads,
                    "writes": e.obj.writer is not None, "replays": bool(e.obj.replay),
                    "options": [{"option": o.usage, "help": o.help, "required": o.required} for o in e.obj.options]}
                   for e in FORMATS.entries()])
        return
    for e in FORMATS.entries():
        f = e.obj
        can = [f"reads a {f.reads}"]
        if f.writer is not None:
            can.append("writes into a folder")
        if f.replay:
            can.append("replays in stream")
        click.echo(f"{e.name:14s} {e.description}{plugin_note(e)}")
        click.echo(f"{'':14s} {', '.join(can)}")
        for o in f.options:
            need = " (convert needs it)" if o.required else ""
            click.echo(f"{'':14s} {o.usage:18s} {o.help}{need}")
