"""``touchbench data`` from the command line."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from touchbench.cli.main import cli


def test_data_list_and_sample_info():
    r = CliRunner().invoke(cli, ["data", "list"])
    assert r.exit_code == 0 and "haart-challenge" in r.output and "haart-sample" in r.output
    r = CliRunner().invoke(cli, ["data", "info", "haart-sample"])
    assert r.exit_code == 0, r.output
    assert "captures      14" in r.output and "subjects      2" in r.output


def test_unknown_dataset_suggests():
    r = CliRunner().invoke(cli, ["data", "info", "haart-challange"])
    assert r.exit_code == 3
    assert "did you mean 'haart-challenge'" in r.output


@pytest.mark.realdata
def test_data_info_haart(real_haart, tb_cache):
    r = CliRunner().invoke(cli, ["data", "info", "haart", "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    out = r.output
    assert "captures      830" in out and "subjects      10" in out and "gestures      7" in out
    assert "frames        432..432" in out
    assert "placeholders  10 byte-identical copies found" in out
    assert "140729-5/140729-5foamnonepat.csv.gz = s05-foam-short-pat" in out


@pytest.mark.realdata
def test_cli_export_then_convert_round_trip(real_haart_challenge, tb_cache, tmp_path):
    r = CliRunner().invoke(cli, ["data", "export", "haart-challenge", str(tmp_path), "--cache-dir", str(tb_cache)])
    assert r.exit_code == 0, r.output
    out = tmp_path / "back.parquet"
    r = CliRunner().invoke(cli, ["data", "convert", str(tmp_path), str(out), "--format", "challenge-csv"])
    assert r.exit_code == 0, r.output
    assert real_haart_challenge.content_hash in r.output
    r = CliRunner().invoke(cli, ["data", "info", "haart-challenge", "--cache-dir", str(tb_cache)])
    assert "by split      test: 251, train: 578" in r.output
