"""The feature registry, the ``touchbench features`` command, scikit-learn
compatibility, and every set on the real HAART recordings."""

from __future__ import annotations

import inspect
import json

import numpy as np
import pytest
from click.testing import CliRunner
from helpers import STATED, make_set
from sklearn.base import clone
from sklearn.pipeline import make_pipeline

from snapshots.registries import builtin_names, snapshot

from touchbench.cli.main import cli
from touchbench.features import FEATURES

EXPECTED_8X8 = {
    "sd": 62,
    "bmh": 64,
    "msd": 768,
    "smmhh": 2125,
    "lbptop": 177,
    "zhou-basic": 30,
    "zhou-wavelet": 234,
    "flagg-stats": 28,
    "raw-window": 432 * 64,
    # touchbench's own: 11 series x 35 statistics + 7 capture scalars + 3 x (7 ranks + sum) + 2
    "touch-rhythm": 11 * 35 + 7 + 3 * 8 + 2,
    "cell-rhythm": 9 + 11,  # nine band fractions + eleven named features
    "contact-motion": 3 * (12 + 4 + 2) + 1,  # per threshold: 12 motion, 4 position bands, 2 activity; + peak
    "touch-windows": 2 * (418 + 20 + 55),  # mean and sd of the three sets
}


def test_every_set_is_registered_with_paper_and_cost():
    assert builtin_names(FEATURES) == snapshot()["features"]  # tests/snapshots/registry-names.json (make snapshots)
    assert set(EXPECTED_8X8) <= set(FEATURES.names())
    for e in FEATURES.entries():
        if e.plugin is not None:  # a plugin's set cites no paper section (tests/test_plugins.py checks the example)
            continue
        cls = e.obj
        assert e.tags["paper"] and e.tags["cost"] in ("cheap", "moderate", "expensive")
        assert "section" in cls.paper and cls.fold_dependent is False
        doc = inspect.getdoc(cls)
        assert "Interpretations" in doc or "interpretations" in doc.lower()
        assert "sensor" in inspect.signature(cls.__init__).parameters
        fs = make_set(e.name)
        size = len(fs.feature_names((8, 8)))
        assert fs.n_features((8, 8)) == size and len(set(fs.feature_names((8, 8)))) == size  # names are unique
        if e.name in EXPECTED_8X8:  # sizes worked out by hand; a new set's own tests give its size
            assert size == EXPECTED_8X8[e.name]


def test_sklearn_api():
    caps = [np.random.default_rng(i).integers(0, 1024, (20, 8, 8)) for i in range(3)]
    for name in FEATURES.names():
        fs = make_set(name)
        c = clone(fs)
        assert c.get_params() == fs.get_params()
        assert np.array_equal(make_pipeline(c).fit_transform(caps), fs.fit_transform(caps))
        assert len(fs.get_feature_names_out()) == fs.n_features_out_


def test_cli_features_list_and_show():
    r = CliRunner().invoke(cli, ["features", "list", "--grid", "8x8", "--frame-rate", "54", "--value-range", "0..1023"], terminal_width=200)
    assert r.exit_code == 0, r.output
    for name, size in EXPECTED_8X8.items():
        if name in STATED:  # its size depends on a parameter that must be stated: shown as '-'
            continue
        line = next(ln for ln in r.output.splitlines() if f" {name} " in ln)
        assert str(size) in line
    assert "Gaus et al. 2015" in r.output and "moderate" in r.output
    r = CliRunner().invoke(cli, ["features", "show", "msd"])
    assert r.exit_code == 0 and "section 3.2.3" in r.output and "Interpretations" in r.output
    r = CliRunner().invoke(cli, ["features", "show", "smmh"])
    assert r.exit_code == 3 and "did you mean 'smmhh'" in r.output



def test_cli_features_list_frame_rate_is_spelled_as_the_readers_spell_it():
    """``--frame-rate HZ``, as every reader's option; the former ``--rate`` still works, hidden from the
    help, with a warning that gives the new spelling."""
    args = ["features", "list", "--grid", "8x8", "--value-range", "0..1023", "--json"]
    new = CliRunner().invoke(cli, args + ["--frame-rate", "54"])
    assert new.exit_code == 0 and "deprecated" not in new.stderr, new.output
    assert {r["name"]: r["size"] for r in json.loads(new.stdout)}["msd"] == EXPECTED_8X8["msd"]
    old = CliRunner().invoke(cli, args + ["--rate", "54"])
    assert old.exit_code == 0 and json.loads(old.stdout) == json.loads(new.stdout), old.output
    assert "--rate is deprecated" in old.stderr and "--frame-rate 54" in old.stderr
    both = CliRunner().invoke(cli, args + ["--frame-rate", "54", "--rate", "54"])
    assert both.exit_code == 2 and "give the frame rate once" in both.output
    help_text = CliRunner().invoke(cli, ["features", "list", "--help"]).output
    assert "--frame-rate" in help_text and "--rate " not in help_text


def test_cli_features_list_value_range_is_spelled_as_the_readers_spell_it():
    """``--value-range LO..HI``, as every reader's option; the former ``--range LO HI`` still works
    for one release, with a warning that gives the new spelling."""
    args = ["features", "list", "--grid", "8x8", "--frame-rate", "54", "--json"]
    new = CliRunner().invoke(cli, args + ["--value-range", "0..1023"])
    assert new.exit_code == 0, new.output
    sizes = {r["name"]: r["size"] for r in json.loads(new.stdout)}
    assert sizes["msd"] == EXPECTED_8X8["msd"]
    old = CliRunner().invoke(cli, args + ["--range", "0", "1023"])
    assert old.exit_code == 0, old.output
    assert {r["name"]: r["size"] for r in json.loads(old.stdout)} == sizes
    assert "--range LO HI is deprecated" in old.stderr and "--value-range 0..1023" in old.stderr
    assert "deprecated" not in new.stderr
    both = CliRunner().invoke(cli, args + ["--value-range", "0..1023", "--range", "0", "1023"])
    assert both.exit_code == 2 and "give the value range once" in both.output
    for bad in ("1023..0", "0-1023"):
        r = CliRunner().invoke(cli, args + ["--value-range", bad])
        assert r.exit_code == 2 and "--value-range" in r.output and "Traceback" not in r.output, r.output
    assert "--range" not in CliRunner().invoke(cli, ["features", "list", "--help"]).output

@pytest.mark.realdata
def test_every_set_on_real_haart(real_haart):
    ds = real_haart
    caps = ds.captures[::10]
    for name in FEATURES.names():
        fs = make_set(name, sensor=ds.sensor)
        out = fs.fit_transform(caps)
        assert out.shape == (len(caps), fs.n_features(ds.sensor.grid)) and np.isfinite(out).all(), name
    bmh = make_set("bmh").fit_transform(caps)
    assert set(np.unique(bmh)) <= {0.0, 1.0} and (bmh.sum(axis=1) >= 1).all()


@pytest.mark.realdata
def test_table4_edges_fit_real_haart(real_haart):
    # Gaus et al.: the edges were set "to fit all instances". Read as per-frame cell
    # counts, the no-touch counts of every real capture fall inside -0.5..55.5, so
    # dropping out-of-range counts (histcounts) loses nothing: each histogram sums to T.
    out = make_set("sd", clip=False).fit_transform(real_haart.captures)
    t = np.array([c.shape[0] for c in real_haart.captures])
    assert (out[:, :12].sum(axis=1) == t).all() and (out[:, 12:24].sum(axis=1) == t).all()
