"""The hand alone: footprints, force profiles, rendering (touchbench.scenes.hand)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import ndtr

from touchbench.scenes.hand import Tracks, footprint, force_profile, normal_cdf, render


def _one_blob(x_mm, y_mm, sd_mm, force, T=1):
    return Tracks(
        cx=np.full((1, T), float(x_mm)),
        cy=np.full((1, T), float(y_mm)),
        force=np.full((1, T), float(force)),
        sdx=np.array([float(sd_mm)]),
        sdy=np.array([float(sd_mm)]),
        conform=np.zeros(1, dtype=bool),
    )


def test_normal_cdf_matches_scipy():
    z = np.linspace(-8, 8, 4001)
    assert np.max(np.abs(normal_cdf(z) - ndtr(z))) < 2.5e-4
    assert normal_cdf(np.array([0.0]))[0] == 0.5
    assert np.all(np.diff(normal_cdf(z)) >= 0)


@pytest.mark.parametrize("prim,blobs", [("fingertip", 1), ("palm", 1), ("hand", 5), ("wrap", 6), ("pinch", 2), ("none", 0)])
def test_footprint_shares_sum_to_one(prim, blobs):
    fp = footprint(prim)
    assert len(fp) == blobs
    if blobs:
        assert fp.share.sum() == pytest.approx(1.0)


def test_fingertips_row_spacing_scales_with_hand():
    fp = footprint("fingertips", hand_scale=1.0, fingers=3)
    big = footprint("fingertips", hand_scale=1.2, fingers=3)
    # three pads 19 mm apart across the hand, centred
    assert fp.offsets[:, 1].tolist() == pytest.approx([-19.0, 0.0, 19.0])
    assert big.offsets[:, 1].tolist() == pytest.approx([-22.8, 0.0, 22.8])
    assert big.sds[0, 0] == pytest.approx(1.2 * fp.sds[0, 0])


def test_force_profile_shape():
    # onset 1 s, 2 s long, 0.5 s raised-cosine rise and fall
    t = np.array([0.9, 1.0, 1.25, 1.5, 2.0, 2.75, 3.0, 3.1])
    env = force_profile(t, [1.0], [2.0], [0.5], [0.5])[0]
    # sin^2(pi/2 * 0.5) = 0.5 half way up and half way down
    assert env.tolist() == pytest.approx([0.0, 0.0, 0.5, 1.0, 1.0, 0.5, 0.0, 0.0])


def test_render_conserves_force_inside_the_grid():
    field = render(_one_blob(100.0, 100.0, 15.0, 7.0), (8, 8), 25.0)
    assert field.shape == (1, 8, 8)
    assert field.sum() == pytest.approx(7.0, abs=1e-3)


def test_render_splits_a_fingertip_between_two_cells():
    # centre on the border between cells (0, 3) and (0, 4) of a 25 mm grid
    field = render(_one_blob(100.0, 12.5, 2.0, 1.0), (1, 8), 25.0)[0, 0]
    assert field[3] == pytest.approx(0.5, abs=1e-3)
    assert field[4] == pytest.approx(0.5, abs=1e-3)


def test_render_loses_force_off_the_sensor():
    # centred on the left edge: half the blob is off the grid
    field = render(_one_blob(0.0, 100.0, 10.0, 2.0), (8, 8), 25.0)
    assert field.sum() == pytest.approx(1.0, abs=1e-3)


def test_render_skips_frames_without_force():
    tr = _one_blob(100.0, 100.0, 10.0, 1.0, T=4)
    tr.force[0, [0, 2]] = 0.0
    field = render(tr, (8, 8), 25.0)
    assert field[[0, 2]].sum() == 0.0
    assert field[1].sum() == pytest.approx(1.0, abs=1e-3)


@settings(max_examples=40, deadline=None)
@given(
    x=st.floats(80, 120),
    y=st.floats(80, 120),
    sd=st.floats(15, 20),
)
def test_render_centroid_is_the_blob_centre(x, y, sd):
    """Away from the edges, the force-weighted centroid of a blob wider
    than half a cell is its centre (a narrower one is binned into its cell,
    next test)."""
    field = render(_one_blob(x, y, sd, 1.0), (8, 8), 25.0)[0]
    w = field / field.sum()
    cy = (w.sum(axis=1) * (np.arange(8) + 0.5) * 25.0).sum()
    cx = (w.sum(axis=0) * (np.arange(8) + 0.5) * 25.0).sum()
    assert cx == pytest.approx(x, abs=0.5)
    assert cy == pytest.approx(y, abs=0.5)
    assert np.all(field >= 0)


def test_small_blob_lands_in_its_cell():
    field = render(_one_blob(60.0, 110.0, 2.0, 1.0), (8, 8), 25.0)[0]
    assert np.unravel_index(field.argmax(), field.shape) == (4, 2)
    assert field[4, 2] == pytest.approx(1.0, abs=1e-3)
