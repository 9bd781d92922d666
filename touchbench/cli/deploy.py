"""``touchbench train``, ``touchbench predict`` and ``touchbench stream``:
from a leaderboard's method to a model file, offline labels and live labels."""

from __future__ import annotations

import json
import math
import sys
from dataclasses import asdict
from pathlib import Path

import click
import yaml

from ..core.atomic import atomic_write_bytes
from ..core.errors import TouchbenchError
from ..deploy.model import TrainedModel
from ..deploy.predict import (
    accuracy_text, adaptation_text, adaptation_warning, predict_dataset, read_data, write_table,
)
from ..deploy.stream import (
    SlidingRecognizer,
    choose_rule,
    load_replay,
    replay,
    run_stream,
    text_frames,
)
from ..deploy.train import parse_selection, train_from_protocol
from ..results.store import PREDICTED, TRUE
from .common import example
from .formats import FORMATS_HELP, FormatChoice, format_options


def _rule(text: str | None):
    """``--rule``: a rule's name or its YAML mapping, as read (None: not given)."""
    if text is None:
        return None
    try:
        spec = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise click.BadParameter(f"not a rule name or a YAML mapping ({e})", param_hint="--rule") from None
    if not isinstance(spec, (str, dict)):
        raise click.BadParameter(f"a rule is a name (max, majority, hmm, gate, onset) or a YAML mapping such as "
                                 f"'{{name: majority, n: 5}}', got {text!r}", param_hint="--rule")
    return spec


def _speed(ctx, param, value: float) -> float:
    """``--speed``: a finite number above 0."""
    if not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"the replay speed must be a finite number above 0, got {value!r}",
                                 param_hint="--speed")
    return value


#: the malformed lines of standard input reported one by one; the others are counted in one line
SKIPPED_SHOWN = 10


def _floats(values, option: str) -> list[float] | None:
    out = []
    for v in values:
        for part in str(v).split(","):
            if part.strip():
                try:
                    out.append(float(part))
                except ValueError:
                    raise click.BadParameter(f"expected seconds, got {part!r}", param_hint=option) from None
    return out or None


@click.command("train", epilog=example("touchbench train demo-haart --method msd/gaus-rf --out msd.joblib"))
@click.argument("protocol")
@click.option("--method", "-m", default=None,
              help="FEATURES/METHOD as the results name it, e.g. msd+sd/gaus-rf, or a method's label alone when "
                   "unique, e.g. touch-et (optional when the protocol has one).")
@click.option("--out", "-o", required=True, type=click.Path(dir_okay=False), help="Model file to write (any name; the manifest goes beside it as <file>.json).")
@click.option("--fold", default=None, help="Train on the training part of this fold of the protocol's scheme only.")
@click.option("--evaluation", default=None, help="The evaluation to train on, for a protocol with several.")
@click.option("--where", multiple=True, metavar="COL=V1,V2", help="Keep only captures with these values (repeatable).")
@click.option("--exclude", multiple=True, metavar="COL=V1,V2", help="Drop captures with these values (repeatable).")
@click.option("--window", "windows", multiple=True, metavar="SECONDS",
              help="Train on sliding windows of this length (repeatable, or comma-separated) for `stream`.")
@click.option("--train-hop", type=float, default=None, help="Hop between training windows, seconds [default: half a window].")
@click.option("--seed", type=int, default=None, help="Classifier seed [default: derived from the protocol seed].")
def train(protocol, method, out, fold, evaluation, where, exclude, windows, train_hop, seed) -> None:
    """Fit one method of PROTOCOL on its evaluation's training side (never a test capture of it) and save it
    with its manifest."""
    model = train_from_protocol(
        protocol, method, fold=fold, evaluation=evaluation, where=parse_selection(where, "--where"),
        exclude=parse_selection(exclude, "--exclude"), windows=_floats(windows, "--window"),
        train_hop=train_hop, seed=seed,
    )
    path = model.save(out)
    click.echo(model.describe())
    t = model.manifest["timings"]
    click.echo(f"saved {path} (manifest {path}.json); features {t['features_s']:.1f} s, fit {t['fit_s']:.1f} s", err=True)


#: the option that reads a model file naming types outside the trusted list, or an older (pickle) file
trust_option = click.option(
    "--trust", is_flag=True,
    help="Also read a model file that can run code when read (an older, pickled model file, or one naming types "
         "outside touchbench's trusted list): only for a file you made or trust.")


def _load_model(path: str, trust: bool) -> TrainedModel:
    model = TrainedModel.load(path, trust=trust)
    for note in model.version_notes():
        click.echo(f"warning: {note}", err=True)
    return model


@click.command("predict", epilog=example("touchbench predict msd.joblib haart-challenge --out labels.csv"))
@click.argument("model_path", metavar="MODEL")
@click.argument("data")
@click.option("--format", "fmt", type=FormatChoice("read", extra=("auto",)), default="auto", show_default=True,
              help=f"Reader of DATA (auto: dataset name, scene:NAME or touchbench Parquet; {FORMATS_HELP}).")
@click.option("--out", "-o", type=click.Path(dir_okay=False), default=None, help="Write the labels here (.csv or .parquet).")
@click.option("--whole", is_flag=True, help="Label whole captures even when the model was trained on windows.")
@trust_option
@format_options
def predict(model_path, data, fmt, out, whole, trust, **options) -> None:
    """Label the captures of DATA with MODEL; refuses data from another sensor (grid, frame rate beyond
    1 %, value range), naming both."""
    model = _load_model(model_path, trust)
    ds = read_data(data, fmt, model, **{k: v for k, v in options.items() if v is not None})
    table = predict_dataset(model, ds, whole=whole, source=data)
    adapted = adaptation_text(model, ds)
    if adapted:
        click.echo(f"note: {adapted}", err=True)
    alone = adaptation_warning(model, ds)
    if alone:
        click.echo(f"warning: {alone}", err=True)
    if out:
        write_table(table, out)
        click.echo(f"{out}: {len(table)} captures labelled", err=True)
    else:
        cols = [c for c in ("capture_id", TRUE, PREDICTED, "probability") if c in table.columns]
        click.echo(table[cols].to_csv(index=False, float_format="%.4f"), nl=False)
    note = accuracy_text(model, table)
    if note:
        click.echo(note, err=True)


@click.command("stream", epilog=example("touchbench stream msd.joblib recording.csv --window 1 --hop 0.5",
                                        "touchbench stream live.joblib sessions.parquet --recording rec-p1 --rule gate"))
@click.argument("model_path", metavar="MODEL")
@click.argument("source", default="-")
@click.option("--window", "windows", multiple=True, metavar="SECONDS",
              help="Window length (repeatable or comma-separated: several at once) [default: the model's].")
@click.option("--hop", type=float, default=0.5, show_default=True, help="Seconds between decisions.")
@click.option("--threshold", type=float, default=0.5, show_default=True,
              help="Under this best probability the decision is 'none' (none of the above), for the max rule "
                   "that decides when neither --rule nor the model file names one.")
@click.option("--combine", type=click.Choice(["max", "mean"]), default="max", show_default=True,
              help="Several windows: the most confident one decides (max) or their mean probabilities.")
@click.option("--none-label", default="none", show_default=True)
@click.option("--rule", default=None, metavar="RULE",
              help="Decision rule: a name (max, majority, hmm, gate, onset) or a YAML mapping such as "
                   "'{name: majority, n: 5}'; a model trained on a stream protocol holds that protocol's rules "
                   "fitted (the gate's and onset's level), and a name or mapping matching one of them takes it "
                   "[default: the model file's rule when it records one, else max with --threshold].")
@click.option("--format", "fmt", type=FormatChoice("replay", lambda f: f.replay, extra=("auto",)), default="auto",
              show_default=True, help="Reader of the file SOURCE (auto: a touchbench dataset, or a table of one "
                                      f"frame per row; {FORMATS_HELP}).")
@click.option("--capture", default=None, help="Replay only this capture_id of SOURCE.")
@click.option("--recording", default=None, metavar="NAME",
              help="Replay this recording of SOURCE (a dataset name or file whose captures are segments of "
                   "recordings, e.g. a table read with --frame-labels), its segments in order, as a stream "
                   "evaluation replays it.")
@click.option("--speed", type=float, default=1.0, show_default=True, callback=_speed,
              help="Replay speed (2: twice the frame rate).")
@click.option("--realtime/--no-realtime", default=True, show_default=True,
              help="Replay files at their frame rate, or as fast as possible.")
@click.option("--jsonl", is_flag=True,
              help="One JSON object per decision instead of text: frame (the number of frames received when the "
                   "decision was made, counting from 1), t (frame / frame rate, seconds), label (the best class or "
                   "the none label), probability, best, window_s (the deciding window; null for --combine mean), "
                   "latency_ms, windows (each window's length, best class and probability).")
@click.option("--summary-json", type=click.Path(dir_okay=False), default=None, help="Write the summary (latencies) here.")
@trust_option
@format_options
def stream(model_path, source, windows, hop, threshold, combine, none_label, rule, fmt, capture, recording, speed,
           realtime, jsonl, summary_json, trust, **options) -> None:
    """Label a stream of frames with MODEL: SOURCE is a CSV/Parquet file replayed at
    its frame rate, a dataset's recording (--recording), or - for standard input (one frame per line:
    H*W comma-separated values, row-major). Prints one decision per hop, then latency p50/p99. A file
    that does not say its frame rate is replayed at the model's. A malformed line of standard input is
    reported (with its line number; the first 10, then counted) and skipped; a malformed file is refused
    before its replay. Exits with status 3 when no decision could be made."""
    if source == "-" and (fmt != "auto" or recording is not None):
        given = "--format" if fmt != "auto" else "--recording"
        raise click.UsageError(f"standard input is read as one frame per line; {given} is for files")
    model = _load_model(model_path, trust)
    chosen, origin = choose_rule(model, _rule(rule), threshold)
    rec = SlidingRecognizer(model, _floats(windows, "--window"), hop_s=hop, threshold=threshold,
                            combine=combine, none_label=none_label, rule=chosen, rule_origin=origin)
    for note in rec.notes():
        click.echo(f"note: {note}", err=True)
    late, skipped = [0], [0]

    def skip(error):
        skipped[0] += 1
        if skipped[0] <= SKIPPED_SHOWN:
            click.echo(f"skipped: {error}", err=True)

    if source == "-":
        frames = text_frames(sys.stdin, model, on_error=skip)
        what = "standard input"
    else:
        arr, rate, what = load_replay(source, model, capture, fmt, recording=recording,
                                      **{k: v for k, v in options.items() if v is not None})
        frames = replay(arr, rate, speed=speed, realtime=realtime, late=late)
    click.echo(f"{model.method} on {what}: windows {', '.join(f'{w:g}' for w in rec.windows_s)} s, "
               f"hop {hop:g} s, threshold {threshold:g}", err=True)

    def emit(d):
        click.echo(d.to_json() if jsonl else d.to_text())
        sys.stdout.flush()

    summary = run_stream(rec, frames, emit, late=late)
    summary.skipped_lines = skipped[0]
    if skipped[0] > SKIPPED_SHOWN:
        click.echo(f"skipped: {skipped[0] - SKIPPED_SHOWN} more malformed lines, not shown", err=True)
    click.echo(summary.to_text(), err=True)
    if summary_json:
        atomic_write_bytes(Path(summary_json), json.dumps(asdict(summary), indent=2).encode())
    if not summary.decisions:
        raise TouchbenchError(
            f"no decision: {summary.frames} frames read from {what}"
            + (f" ({skipped[0]} malformed lines skipped)" if skipped[0] else "")
            + f"; the shortest window needs {rec.lengths[0]} frames")
