"""A file format's reader options given in a protocol (``dataset: {name: FILE, format: F, options:
...}``) are checked when the protocol is read, before any data: an option the reader does not take
(with the nearest names), a boolean, and a text or number its command-line form refuses, each at
``file:line: dataset.options.NAME``. Then the values are read as the command line reads them."""

from __future__ import annotations

from pathlib import Path

import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.engine.planning import plan_run
from touchbench.protocols.loading import parse_protocol

SKIN = Path(__file__).resolve().parents[1] / "docs" / "formats" / "my-skin.csv"
#: what my-skin.csv needs said: its capture and subject columns
COLUMNS = "capture_columns: take, subject_column: person"


def _text(fmt: str, options: str) -> str:
    return (f"name: t\ndataset: {{name: {SKIN}, format: {fmt}, options: {{{options}}}}}\n"  # line 2
            "scheme: loso\nfeatures: [[msd]]\nclassifiers: [{name: gaus-rf, params: {n_estimators: 5}}]\n")


@pytest.mark.parametrize("fmt, options, field, words", [
    ("table", "frame_rate: -5", "frame_rate", "above 0, got '-5'"),
    ("table", "frame_rate: true", "frame_rate", "--frame-rate takes a value, not a boolean"),
    ("table", "value_range: 0...255", "value_range", "each with a digit before any dot"),
    ("table", "grid: 19 by 24", "grid", "expected HxW"),
    ("table", "frame_rat: 5", "frame_rat", "did you mean 'frame_rate'"),
    ("haart-raw", "recording_window: banana", "recording_window", "expected middle, middle:SECONDS"),
])
def test_a_reader_option_is_refused_at_its_field_before_any_data(fmt, options, field, words):
    with pytest.raises(TouchbenchError) as e:
        parse_protocol(_text(fmt, options), "p.yaml")
    msg = str(e.value)
    assert msg.startswith(f"p.yaml:2: dataset.options.{field}: ") and words in msg, msg


def test_text_and_numbers_are_read_as_the_command_line_reads_them(tmp_path):
    # 0..255 as text, the rate as a number (my-skin.csv names its captures in `take`, people in `person`)
    plan = plan_run(parse_protocol(_text("table", f"frame_rate: 20, value_range: 0..255, {COLUMNS}"), "p.yaml"),
                    cache_root=tmp_path)
    sensor = plan.dataset.sensor
    assert sensor.frame_rate == 20.0 and tuple(sensor.value_range) == (0.0, 255.0)
