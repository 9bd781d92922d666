"""The compiled loops of touchbench's own sets (numba, touchbench.features.touch_kernels) give the values of
the numpy path (``compiled.COMPILED = False``) within 1e-9, relative or absolute (sums in another order):
on real HAART captures (the real-data pattern: fails under CI=true without the data), on short
windows of a 19 x 27 skin (the live case, padded ones included) and on synthetic captures of other
grids, dtypes and lengths. Skipped where numba is not installed (the numpy path is then the only one)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import compiled_and_numpy, synthetic_captures
from numpy.testing import assert_allclose

from touchbench.datasets.model import SensorSpec

pytest.importorskip("numba")

SETS = ["touch-rhythm", "cell-rhythm", "contact-motion", "contact-evidence", "touch-windows"]
SKIN = SensorSpec(name="skin", grid=(19, 27), frame_rate=10.0, value_range=(0.0, 255.0))
TOL = {"rtol": 1e-9, "atol": 1e-9}


both = compiled_and_numpy


@pytest.mark.parametrize("name", SETS)
def test_real_haart_captures_agree_with_the_numpy_path(real_haart, name, monkeypatch):
    caps = real_haart.captures if name != "touch-windows" else real_haart.captures[::7]
    fast, plain = both(name, caps, real_haart.sensor, monkeypatch)
    assert_allclose(fast, plain, **TOL)


@pytest.mark.parametrize("name", SETS[:4])
@pytest.mark.parametrize("t", [1, 5, 10, 30])
@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_skin_windows_agree_with_the_numpy_path(name, t, dtype, monkeypatch):
    caps = synthetic_captures(t, t, SKIN.grid, dtype)
    caps.append(np.zeros_like(caps[0]))  # a window without pressure
    fast, plain = both(name, caps, SKIN, monkeypatch)
    assert_allclose(fast, plain, **TOL)


@pytest.mark.parametrize("name", SETS[:4])
@pytest.mark.parametrize("t, grid, dtype, top", [(64, (8, 8), np.uint16, 1023.0), (31, (5, 7), np.float64, 1023.0),
                                                 (9, (1, 6), np.int16, 100.0), (12, (4, 1), np.uint8, 255.0)])
@pytest.mark.parametrize("more_is_higher", [True, False])
def test_synthetic_captures_agree_with_the_numpy_path(name, t, grid, dtype, top, more_is_higher, monkeypatch):
    sensor = SensorSpec(name="synthetic", grid=grid, frame_rate=54.0, value_range=(0.0, top),
                        higher_is_more_pressure=more_is_higher)
    caps = synthetic_captures(t, t, grid, dtype, top)
    fast, plain = both(name, caps, sensor, monkeypatch)
    assert_allclose(fast, plain, **TOL)


def test_cell_spectra_inputs_are_numpys_bit_for_bit():
    """The cells' means and the windowed series the compiled paths give numpy's FFT are numpy's
    (``mean``, ``centred_spectrum``), so the spectra (whose peaks are taken) are the same bits:
    constant cells and cells at 0 included."""
    from touchbench.features import cell_kernels, touch_kernels
    from touchbench.features.touch_spectra import _hann_freqs, centred_spectrum

    rng = np.random.default_rng(4)
    for t in (8, 10, 33, 300, 9000):  # numpy sums in another order at 8 and 128 values and at each halving beyond
        s = np.maximum(rng.normal(0, 5, (2, t, 40)), 0.0) * 10.0 ** rng.integers(-8, 8, (2, t, 40))
        s[:, :, :5] = 7.0
        cells = np.swapaxes(s, 1, 2)
        mean = cells.mean(axis=2)
        p_plain, _ = centred_spectrum(cells - mean[..., None], cells.max(axis=2) == cells.min(axis=2), 10.0)
        hann = _hann_freqs(t, 10.0)[0]
        dw = np.empty((2, 40, t))
        mine = np.empty((2, 40))
        cell_kernels.cell_series(s, hann, mine, dw)  # cell-rhythm's layout, its means its own
        assert np.array_equal(mine, mean)
        assert np.array_equal((np.abs(np.fft.rfft(dw, axis=-1)) ** 2)[..., 1:], p_plain)
        rows = np.ascontiguousarray(cells)  # the same series stored one per row (touch-rhythm's layout)
        touch_kernels.windowed(rows, hann, dw)  # its means its own: numpy's of the rows
        p_rows, _ = centred_spectrum(rows - rows.mean(axis=2)[..., None], cells.max(axis=2) == cells.min(axis=2), 10.0)
        assert np.array_equal((np.abs(np.fft.rfft(dw, axis=-1)) ** 2)[..., 1:], p_rows)
        one = np.ascontiguousarray(s[:, :, 5:6])  # a single cell: its series contiguous, numpy sums it pairwise
        one_mean = np.swapaxes(one, 1, 2).mean(axis=2)
        p_one, _ = centred_spectrum(np.swapaxes(one, 1, 2) - one_mean[..., None], one.max(axis=1) == one.min(axis=1), 10.0)
        mine_one = np.empty((2, 1))
        cell_kernels.cell_series(one, hann, mine_one, dw[:, :1])
        assert np.array_equal(mine_one, one_mean)
        assert np.array_equal((np.abs(np.fft.rfft(dw[:, :1], axis=-1)) ** 2)[..., 1:], p_one)


def test_contact_weights_sums_are_numpys_bit_for_bit():
    # numpy's sum of a row is pairwise: its order changes at 8 and 128 values and at every split in
    # two beyond; rows of values spanning 16 orders of magnitude make every other order show
    from touchbench.features import motion_kernels

    rng = np.random.default_rng(11)
    scratch = np.empty((3, 64), dtype=np.int64), np.empty(64)
    for n in [1, 2, 7, 8, 9, 15, 16, 17, 63, 64, 65, 127, 128, 129, 130, 255, 256, 257, 432, 513, 1000, 5000]:
        rows = rng.random((40, n)) * 10.0 ** rng.integers(-8, 8, (40, n))
        assert [motion_kernels.numpy_sum(r, 0, n, *scratch) for r in rows] == rows.sum(axis=1).tolist(), n
        tail = rows[:, n // 3:]  # a sum starting inside a row
        assert [motion_kernels.numpy_sum(r, n // 3, n - n // 3, *scratch) for r in rows] == tail.sum(axis=1).tolist(), n
    s = rng.random((2, 6, 513)) * 10.0 ** rng.integers(-8, 8, (2, 6, 513))
    s[1, 2] = 0.0  # a frame without contact at every threshold
    rel = np.array([0.1, 0.3, 0.5])
    wt, area, peak, ws = np.empty((2 * 3 * 6, 513)), np.empty((2, 3, 6)), np.empty(2), np.empty((2, 3, 6))
    m = motion_kernels.contact_weights(s, 5, rel, 0.0, wt, area, peak, ws)
    # the same by numpy: the peak (the largest frame maximum of 6), the weights above each threshold
    assert np.array_equal(peak, s.max(axis=2).max(axis=1))
    plain = np.maximum(s[:, None] - (peak[:, None] * rel)[..., None, None], 0.0)  # (2, 3, 6, 513)
    assert np.array_equal(ws, plain.sum(axis=3))
    assert np.array_equal(area, np.count_nonzero(plain, axis=3))
    with_contact = plain.reshape(-1, 513)[np.count_nonzero(plain, axis=3).ravel() > 0]  # in order
    assert m == len(with_contact) < 2 * 3 * 6 and np.array_equal(wt[:m], with_contact)
