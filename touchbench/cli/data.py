"""``touchbench data``: list, inspect, export and convert datasets."""

from __future__ import annotations

import json
from pathlib import Path

import click

from ..catalog import load_dataset, parse_dataset_ref
from ..datasets import DATASETS
from ..datasets.model import TouchDataset

FORMATS = ("challenge-csv", "cost-csv", "long")


@click.group()
def data() -> None:
    """Datasets: real readers, the cache, exports."""


@data.command("list")
def list_() -> None:
    """Registered datasets (scenes: `touchbench scenes list`)."""
    for e in DATASETS.entries():
        click.echo(f"{e.name:18s} {e.description}")


def _load(name: str, cache_dir: str | None, data_dir: str | None, refresh: bool = False) -> TouchDataset:
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
        f"sensor        {s['name']}: {s['grid'][0]} x {s['grid'][1]} at {s['frame_rate']:g} Hz, range {s['value_range']}",
        f"frames        {fpc['min']}..{fpc['max']} per capture (median {fpc['median']:g})",
        f"values        {info['value_range'][0]:g}..{info['value_range'][1]:g} ({info['dtype']})",
        f"content hash  {info['content_hash']}",
        "by subject    " + ", ".join(f"{k}: {v}" for k, v in info["by_subject"].items()),
        "by gesture    " + ", ".join(f"{k}: {v}" for k, v in info["by_gesture"].items()),
    ]
    if "by_split" in info:
        lines.append("by split      " + ", ".join(f"{k}: {v}" for k, v in info["by_split"].items()))
    prov = info.get("provenance", {})
    ph = prov.get("placeholders")
    if ph is not None:
        lines.append(f"placeholders  {len(ph)} byte-identical copies found:")
        lines += [f"  {p['file']} = {p['copy_of']} ({p['reason']})" for p in ph]
    for k, v in prov.items():
        if k != "placeholders":
            lines.append(f"{k:13s} {v}")
    return "\n".join(lines)


@data.command()
@click.argument("name")
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None, help="Cache folder (default: user cache).")
@click.option("--data-dir", type=click.Path(file_okay=False), default=None, help="Raw data folder (default: ../shared/data).")
@click.option("--refresh", is_flag=True, help="Rebuild the cache entry.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def info(name: str, cache_dir, data_dir, refresh: bool, as_json: bool) -> None:
    """Counts, ranges, placeholders and hash of dataset NAME (or scene:NAME or a Parquet file)."""
    inf = _load(name, cache_dir, data_dir, refresh).info()
    click.echo(json.dumps(inf, indent=2) if as_json else format_info(inf))


@data.command()
@click.argument("name")
@click.argument("out_dir", type=click.Path(file_okay=False))
@click.option("--format", "fmt", type=click.Choice(["challenge-csv", "parquet"]), default="challenge-csv", show_default=True)
@click.option("--cache-dir", type=click.Path(file_okay=False), default=None)
@click.option("--data-dir", type=click.Path(file_okay=False), default=None)
def export(name: str, out_dir: str, fmt: str, cache_dir, data_dir) -> None:
    """Write dataset NAME to OUT_DIR (the challenge's training.csv and testWITHLABELS.csv, or Parquet)."""
    ds = _load(name, cache_dir, data_dir)
    if fmt == "challenge-csv":
        from ..datasets.challenge_csv import export_challenge_csv

        paths = export_challenge_csv(ds, out_dir)
    else:
        paths = [ds.to_parquet(Path(out_dir) / f"{ds.name}.parquet")]
    for p in paths:
        click.echo(str(p))


@data.command()
@click.argument("source", type=click.Path(exists=True))
@click.argument("out", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(FORMATS), required=True, help="Format of SOURCE.")
@click.option("--grid", default=None, help="H,W of the grid (format long).")
@click.option("--frame-rate", type=float, default=None, help="Frames per second (format long).")
@click.option("--name", default=None, help="Dataset name (default: from the file).")
def convert(source: str, out: str, fmt: str, grid, frame_rate, name) -> None:
    """Read SOURCE in a supported format and save it as a touchbench Parquet dataset OUT."""
    if fmt == "challenge-csv":
        from ..datasets.challenge_csv import read_challenge_csv

        ds = read_challenge_csv(source, name=name or "haart-challenge")
    elif fmt == "cost-csv":
        from ..datasets.cost import read_cost_csv

        ds = read_cost_csv(source, name=name or "cost")
    else:
        if grid is None or frame_rate is None:
            raise click.UsageError("--format long needs --grid H,W and --frame-rate")
        from ..datasets.generic import read_long_table

        try:
            h, w = (int(x) for x in grid.split(","))
        except ValueError:
            raise click.BadParameter("expected H,W such as 8,8", param_hint="--grid") from None
        ds = read_long_table(source, (h, w), frame_rate, name=name)
    ds.to_parquet(out)
    click.echo(f"{out}: {len(ds)} captures, hash {ds.content_hash}")
