"""Scene to dataset: metadata as the real readers give it, determinism,
Parquet, load_dataset and the command line (touchbench.scenes.generate)."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from touchbench.datasets import TouchDataset

from touchbench.catalog import load_dataset
from touchbench.scenes import generate_scene


@pytest.fixture(scope="module")
def tiny():
    return generate_scene("tiny")


def test_tiny_metadata(tiny):
    assert tiny.name == "tiny" and len(tiny) == 32
    # only the columns the scene has: one session, no variants, substrates, covers, groups or split
    assert list(tiny.meta.columns) == ["capture_id", "subject", "gesture", "repetition"]
    assert sorted(tiny.meta["subject"].unique()) == ["s01", "s02", "s03", "s04"]
    assert tiny.meta["repetition"].dtype == np.int64 and set(tiny.meta["repetition"]) == {1, 2}
    assert tiny.meta["capture_id"].iloc[0] == "s01-pat-01"
    assert sorted(tiny.meta["gesture"].unique()) == ["pat", "rub", "scratch", "stroke"]
    assert all(c.shape == (108, 8, 8) and c.dtype == np.uint16 for c in tiny.captures)
    s = tiny.sensor
    assert (s.grid, s.frame_rate, s.value_range, s.higher_is_more_pressure, s.channels) == ((8, 8), 54.0, (0.0, 1023.0), True, None)


def test_same_seed_same_hash_other_seed_other_hash(tiny):
    assert generate_scene("tiny").content_hash == tiny.content_hash
    assert generate_scene("tiny", seed=1).content_hash == tiny.content_hash  # the scene's seed is 1
    assert generate_scene("tiny", seed=2).content_hash != tiny.content_hash


def test_a_capture_does_not_depend_on_the_others(tiny):
    # two of the four people: the same first 16 captures, bit for bit
    half = generate_scene("tiny", subjects=2)
    assert len(half) == 16
    for a, b in zip(half.captures, tiny.captures[:16]):
        assert np.array_equal(a, b)


def test_notouch_is_baseline_and_noise_only():
    ds = generate_scene("tiny", gestures=["notouch", "constant"])  # library defaults for both
    nt = [c for c, g in zip(ds.captures, ds.labels) if g == "notouch"]
    touch = [c for c, g in zip(ds.captures, ds.labels) if g == "constant"]
    assert max(c.max() for c in nt) < 20  # baseline 2 (gamma spread 0.5) + noise 0.8
    # 64 cells x 2 counts of baseline vs a hand of ~12 N at 60 counts / N
    assert max(c.astype(float).sum(axis=(1, 2)).mean() for c in nt) < 250
    assert min(c.astype(float).sum(axis=(1, 2)).mean() for c in touch) > 400


def test_noise_level_end_to_end():
    # noise alone (flat baseline of 100 counts to stay clear of 0): the
    # frame-to-frame sd is that of the noise plus rounding, sqrt(sd^2 + 1/12)
    ds = generate_scene("tiny", gestures=["notouch"], **{"sensor.noise_sd": 3.0, "sensor.baseline": {"level": 100.0, "spread": 0.0, "drift": 0.0}})
    x = np.stack(ds.captures).astype(float)
    assert x.std(axis=1).mean() == pytest.approx(np.sqrt(9 + 1 / 12), rel=0.03)
    assert x.mean() == pytest.approx(100.0, abs=0.1)


def test_parquet_round_trip_and_load_dataset(tiny, tmp_path):
    p = tiny.to_parquet(tmp_path / "tiny.parquet")
    back = load_dataset(p)
    assert back.content_hash == tiny.content_hash
    assert TouchDataset.from_parquet(p, verify=True).content_hash == tiny.content_hash
    assert load_dataset("scene:tiny").content_hash == tiny.content_hash


def test_haart_like_metadata_mirrors_haart():
    ds = generate_scene("haart-like", subjects=3)
    assert list(ds.meta.columns) == ["capture_id", "subject", "substrate", "cover", "gesture", "split"]
    assert len(ds) == 3 * 84
    assert set(ds.meta["substrate"]) == {"curve", "foam", "none"}
    assert set(ds.meta["cover"]) == {"fur", "long", "none", "short"}
    assert set(ds.meta["gesture"]) == {"constant", "notouch", "pat", "rub", "scratch", "stroke", "tickle"}
    # s01 is the challenge's T1 (test), s03 its P3 (train)
    split = ds.meta.groupby("subject")["split"].first().to_dict()
    assert split == {"s01": "test", "s02": "test", "s03": "train"}
    assert ds.meta["capture_id"].iloc[2] == "s01-curve-fur-pat"
    assert all(c.shape == (432, 8, 8) and c.dtype == np.uint16 for c in ds.captures)
    assert max(int(c.max()) for c in ds.captures) <= 1023
    assert ds.sensor.frame_rate == 54.0


def test_haart_like_cover_lowers_and_curve_raises_pressure():
    ds = generate_scene("haart-like", subjects=2, gestures=["constant"])
    peak = {(r.substrate, r.cover): int(c.max()) for r, c in zip(ds.meta.itertuples(), ds.captures)}
    tot = {}
    for r, c in zip(ds.meta.itertuples(), ds.captures):
        tot.setdefault(r.cover, []).append(c.astype(float).sum(axis=(1, 2)).mean())
    assert np.mean(tot["fur"]) < np.mean(tot["none"])
    assert peak  # every condition generated


def test_cost_like_metadata_and_lengths():
    ds = generate_scene("cost-like", subjects=2, repetitions=2, lost=0)
    assert list(ds.meta.columns) == ["capture_id", "subject", "variant", "gesture", "repetition", "split"]
    assert len(ds) == 2 * 3 * 14 * 2
    assert set(ds.meta["variant"]) == {"gentle", "normal", "rough"}
    # the challenge used gentle and normal only
    assert set(ds.meta.loc[ds.meta["variant"] == "rough", "split"]) == {"none"}
    assert set(ds.meta.loc[ds.meta["variant"] != "rough", "split"]) == {"train"}
    n = ds.n_frames
    # cut at the touch: 75 ms .. 9.6 s at 135 Hz
    assert n.min() >= round(0.075 * 135) and n.max() <= round(9.6 * 135)
    med = ds.meta.assign(n=n).groupby("gesture")["n"].median()
    assert med["hit"] < 60 < med["massage"]
    # rough is firmer than gentle
    peak = ds.meta.assign(p=[int(c.max()) for c in ds.captures]).groupby("variant")["p"].median()
    assert peak["rough"] > peak["normal"] > peak["gentle"]


def test_cost_like_loses_seven_captures():
    ds = generate_scene("cost-like", subjects=1, repetitions=1, gestures=["poke", "hit", "pat", "tap"], lost=3)
    assert len(ds) == 12 - 3


def test_tpm_like_groups_sessions_and_bursts():
    ds = generate_scene(
        "tpm-like",
        repetitions=2,
        protocol__groups={"A": {"subjects": 2}, "B": {"subjects": 1}},
    )
    m = ds.meta
    assert list(m.columns) == ["capture_id", "subject", "group", "session", "substrate", "gesture", "repetition"]
    assert set(m["substrate"]) == {"fabric"}  # every capture through the fabric's response lag
    assert m.groupby("group")["subject"].unique().apply(list).to_dict() == {"A": ["s01", "s02"], "B": ["s03"]}
    assert set(m.loc[m["group"] == "A", "session"]) == {1, 2} and set(m.loc[m["group"] == "B", "session"]) == {1}
    assert len(ds) == (2 * 2 + 1) * 7 * 2
    assert m["capture_id"].iloc[0] == "s01-r1-fabric-grab-01"
    assert all(c.shape[1:] == (20, 20) for c in ds.captures)
    # group A's stroke is a quick burst of three: shorter than group B's continuous strokes
    n = ds.n_frames
    a = n[((m["group"] == "A") & (m["gesture"] == "stroke")).to_numpy()]
    b = n[((m["group"] == "B") & (m["gesture"] == "stroke")).to_numpy()]
    assert np.median(a) < np.median(b)


def test_fur_like_is_a_channel_sensor():
    ds = generate_scene("fur-like", subjects=2, repetitions=2)
    assert ds.sensor.channels == ("x", "y", "pressure", "fur") and ds.sensor.grid == (1, 4)
    assert all(c.shape == (100, 1, 4) for c in ds.captures)
    assert len(ds) == 2 * 9 * 2
    nt = np.stack([c for c, g in zip(ds.captures, ds.labels) if g == "notouch"]).astype(float)
    st = np.stack([c for c, g in zip(ds.captures, ds.labels) if g == "stroke"]).astype(float)
    # strokes press and move the fur; nothing touches the notouch examples
    assert st[..., 2].mean() > nt[..., 2].mean() + 10 and st[..., 3].mean() > nt[..., 3].mean() + 20


def test_cli_list_generate_fidelity(tmp_path):
    from touchbench.cli.main import cli

    r = CliRunner().invoke(cli, ["scenes", "list"])
    assert r.exit_code == 0 and "cost-like" in r.output and "7805 captures" in r.output
    out = tmp_path / "t.parquet"
    r = CliRunner().invoke(cli, ["scenes", "generate", "tiny", "--out", str(out), "--seed", "3", "--set", "population.subjects=2"])
    assert r.exit_code == 0, r.output
    ds = load_dataset(out)
    assert len(ds) == 16 and ds.content_hash == generate_scene("tiny", seed=3, subjects=2).content_hash
    r = CliRunner().invoke(cli, ["scenes", "generate", "tiny", "--out", str(out), "--set", "protocol.repetitions=0"])
    assert r.exit_code == 3 and "protocol.repetitions" in r.output
    r = CliRunner().invoke(cli, ["scenes", "generate", "nosuch", "--out", str(out)])
    assert r.exit_code == 3 and "unknown scene" in r.output
    r = CliRunner().invoke(cli, ["scenes", "fidelity", "tiny", "--features", "msd", "--trees", "10"])
    assert r.exit_code == 0, r.output
    assert "no real counterpart" in r.output and "msd+rf" in r.output
