"""``touchbench scenes``: list and generate synthetic scenes, and check how faithful they are to real data."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import click
import yaml

from ..core.errors import TouchbenchError
from ..core.yamlsafe import safe_load
from . import exitcodes
from .common import echo_json, example, json_option


def _parse_sets(values: tuple[str, ...]) -> dict:
    """``--set a.b=value`` pairs; values are read as YAML (numbers, lists)."""
    out = {}
    for item in values:
        if "=" not in item:
            raise TouchbenchError(f"--set {item!r}: expected KEY=VALUE (e.g. protocol.repetitions=2)")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = safe_load(v)
        except yaml.YAMLError:
            raise TouchbenchError(f"--set {item!r}: value is not valid YAML") from None
    return out


@click.group(epilog=example("touchbench scenes list", "touchbench scenes generate tiny --out tiny.parquet"))
def scenes() -> None:
    """Synthetic scenes: sensors, gestures and people described in YAML."""


@scenes.command("list", epilog=example("touchbench scenes list --json"))
@json_option
def list_(as_json: bool) -> None:
    """Shipped scenes with their size and effects."""
    from ..scenes import SCENES, load_scene
    from ..scenes.spec import n_captures

    if as_json:
        echo_json([{"name": e.name, "description": e.description,
                    "captures": n_captures(load_scene(e.name)) - load_scene(e.name).protocol.lost,
                    "effects": list(load_scene(e.name).effects)} for e in SCENES.entries()])
        return
    for e in SCENES.entries():
        spec = load_scene(e.name)
        click.echo(f"{e.name:12s} {n_captures(spec) - spec.protocol.lost:6d} captures  {e.description}")
        click.echo(f"{'':12s} effects: {', '.join(spec.effects)}")


@scenes.command("generate", epilog=example("touchbench scenes generate tiny --out tiny.parquet --seed 1"))
@click.argument("name")
@click.option("--out", "out", type=click.Path(dir_okay=False), required=True, help="Parquet file to write")
@click.option("--seed", type=click.IntRange(min=0), default=None, help="seed (default: the scene's own)")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE", help="override a scene field, e.g. protocol.repetitions=2")
def generate(name: str, out: str, seed: int | None, sets: tuple[str, ...]) -> None:
    """Generate scene NAME (a shipped name or a YAML file) into a dataset
    file that `load_dataset` and the protocols read. A scene too large for
    the memory available is refused before anything is made; Ctrl-C or
    SIGTERM stop it, writing nothing."""
    t = time.perf_counter()
    try:
        from ..scenes import generate_scene

        ds = generate_scene(name, seed=seed, **_parse_sets(sets))
        ds.to_parquet(out)  # atomic: a file whole or none
    except KeyboardInterrupt:  # Ctrl-C, or SIGTERM (the group turns it into this)
        click.echo(f"\ninterrupted: nothing was written to {out}", err=True)
        sys.exit(exitcodes.INTERRUPTED)
    n = ds.n_frames
    click.echo(
        f"{ds.name}: {len(ds)} captures, {ds.meta['subject'].nunique()} subjects, "
        f"{ds.meta['gesture'].nunique()} gestures, {n.min()}..{n.max()} frames; "
        f"hash {ds.content_hash[:16]}; {time.perf_counter() - t:.1f} s -> {out}"
    )


@scenes.command("fidelity", epilog=example("touchbench scenes fidelity haart-like"))
@click.argument("name")
@click.option("--seed", type=click.IntRange(min=0), default=None, help="seed (default: the scene's own)")
@click.option("--real", default=None, help="real dataset to hold it against (default: the scene's real_counterpart)")
@click.option("--features", "feature_sets", default=None, help="comma-separated feature sets (default: the Gaus sets available)")
@click.option("--trees", type=int, default=100, show_default=True, help="random forest size")
@click.option("--no-accuracy", is_flag=True, help="distributions only")
@click.option("--json", "json_out", type=click.Path(dir_okay=False), default=None, help="also write the figures as JSON")
def fidelity(name: str, seed: int | None, real: str | None, feature_sets: str | None, trees: int, no_accuracy: bool, json_out: str | None) -> None:
    """Hold scene NAME against its real dataset: per-gesture distributions
    of total pressure, contact area and centroid speed, and the accuracy of
    Gaus features + random forest (LOSO and challenge split) on both. A
    scene without a real counterpart gets its separability instead: the
    accuracy of a few methods, person-independent and random 5-fold."""
    from ..scoring import fidelity as cal
    from ..scenes import generate_scene, load_scene

    spec = load_scene(name)
    sets = [s.strip() for s in feature_sets.split(",")] if feature_sets else None
    if real or spec.real_counterpart:
        rep = cal.check_fidelity(name, real=real, seed=seed, sets=sets, n_estimators=trees, accuracy_too=not no_accuracy)
        click.echo(rep.to_text())
        if json_out:
            payload = {
                "scene": rep.scene,
                "real": rep.real,
                "seed": rep.seed,
                "features": rep.sets,
                "trees": rep.n_estimators,
                "distributions": rep.distributions.to_dict(orient="records"),
                "accuracy": rep.accuracy.to_dict(orient="index"),
            }
            Path(json_out).write_text(json.dumps(payload, indent=2, default=float))
        return
    ds = generate_scene(name, seed=seed)
    methods = cal.METHODS if sets is None else (("+".join(sets) + "+rf", tuple(sets)),)
    table = cal.separability(ds, methods=methods, n_estimators=trees)
    click.echo(f"scene {spec.name!r} has no real counterpart; separability ({len(ds)} captures, random forest {trees} trees):")
    click.echo(table.to_string(float_format=lambda v: f"{100 * v:5.1f} %"))
    if json_out:
        Path(json_out).write_text(table.to_json(orient="index", indent=2))
