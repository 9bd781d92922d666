"""A dataset's options are checked when a protocol is read, before any data: an option its loader
does not take (with the nearest name), and a window of no frame at the data's rate (HAART's sensor,
54 frames per second: one frame is 1/54 s, about 0.0185 s)."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli
from touchbench.datasets.formats import OptionValueError
from touchbench.datasets.haart_raw import read_haart_raw


def validate(tmp_path, options: str) -> str:
    path = tmp_path / "p.yaml"
    path.write_text("name: t\ndataset:\n  name: icmi15-study2\n  options:\n" + options
                    + "scheme: loso\nfeatures: [[msd]]\nclassifiers: [gaus-rf]\n")
    r = CliRunner().invoke(cli, ["protocols", "validate", "--schema-only", str(path)])
    assert r.exit_code == 3, r.output
    return r.output.strip().removeprefix("error: ").replace(str(path), "p.yaml")


@pytest.mark.parametrize("window,frames", [("first:0.001", 0), ("middle:0.009", 0)])
def test_a_window_of_no_frame_is_refused_at_its_option(tmp_path, window, frames):
    out = validate(tmp_path, f"    window: {window}\n")  # line 5
    assert out.startswith(f"p.yaml:5: dataset.options.window: window '{window}': ")
    assert f"is {frames} frames at 54 Hz: a window is at least one frame (0.0185 s)" in out


def test_an_unknown_dataset_option_is_refused_with_the_nearest_name(tmp_path):
    out = validate(tmp_path, "    windw: haart\n")
    assert out == ("p.yaml:5: dataset.options.windw: unknown option 'windw' for dataset 'icmi15-study2'; "
                   "did you mean 'window'? (accepted: window)")


@pytest.mark.parametrize("option,value", [("recording_window", "middle:0.005"), ("recording_seconds", 0.005)])
def test_the_raw_reader_refuses_a_window_of_no_frame_naming_the_option(tmp_path, option, value):
    # 0.005 s at 54 Hz is 0.27 frames: rounded, none (checked before any file is read)
    with pytest.raises(OptionValueError, match=f"^{option}: 0.005 s is 0 frames at 54 Hz"):
        read_haart_raw(tmp_path, **{option: value, **({"recording_window": "whole"} if option != "recording_window" else {})})
