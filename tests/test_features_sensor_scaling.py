"""Feature sets whose constants depend on the grid or the value range scale with
the sensor by their stated rule (features/gaus_common.py, features/touch.py),
here on SocialTouch's 19 x 24 grid of values 0..255. Every expected value is
worked out by hand in the comments.

The rules: Gaus et al.'s ``sd`` histogram edges count cells of an 8 x 8 grid
and are multiplied by cells / 64 (456 / 64 = 7.125 here); ``bmh``'s offset 5
and ``smmhh``'s threshold 3 are raw units of 0..1023 and are multiplied by
255 / 1023; ``smmhh`` pools down to one cell; touchbench's own contact floors
(3 and 4 of 0..1023) are multiplied by 255 / 1023. A channel sensor is refused.
"""

from __future__ import annotations

import numpy as np
import pytest

from touchbench.datasets.model import SensorSpec
from touchbench.features.base import FeatureInputError, make_feature_set

WIDE = SensorSpec("wide", (19, 24), 12.0, (0, 255))
WIDE_10BIT = SensorSpec("wide-10bit", (19, 24), 12.0, (0, 1023))


def features(name: str, capture: np.ndarray, sensor=WIDE, **params) -> dict[str, float]:
    fs = make_feature_set(name, params, sensor)
    x = fs.fit_transform([capture])[0]
    return dict(zip(fs.get_feature_names_out(), x))


def block(f: dict[str, float], prefix: str) -> list[float]:
    return [v for k, v in f.items() if k.startswith(prefix)]


def hist(*bins: int, n: int = 12) -> list[int]:
    """A histogram of ``n`` bins holding one count per bin index given."""
    return np.bincount(bins, minlength=n).tolist()


# ---------------------------------------------------------------------- sd
def sd_capture() -> np.ndarray:
    """Three frames of 19 x 24 = 456 cells: all 0; 114 cells (a quarter) at 200; 228 cells (half) at 100."""
    c = np.zeros((3, 19, 24), dtype=np.uint8)
    c[1].flat[:114] = 200
    c[2].flat[:228] = 100
    return c


def test_sd_bins_scale_with_the_cells():
    # Per-frame counts (instance min 0, max 200; 1026 of the 1368 values are 0, so the median is 0):
    #   no touch (== 0, frame and instance):  456, 342, 228 cells
    #   touched (>= median 0):                456, 456, 456
    #   high frame (== frame max 0, 200, 100): 456, 114, 228
    #   high instance (== 200):               0, 114, 0
    # Scaled edges (x 456/64 = 7.125): no touch / high: width 35.625 from -3.5625, 12 bins (the last to 395.4375);
    # touched: width 35.625 from -3.5625, 14 bins (the last to 466.6875). As fractions of 64 cells:
    # 342 -> 48 (bin 9: [44.5, 49.5)), 228 -> 32 (bin 6), 114 -> 16 (bin 3), 0 -> bin 0, 456 -> 64: beyond 55.5,
    # clipped into the last no-touch / high bin (11), and in touched bin 12 ([59.5, 64.5)).
    f = features("sd", sd_capture())
    assert len(f) == 12 + 12 + 14 + 12 + 12  # as many values as on HAART
    assert block(f, "sd_notouch_frame") == hist(11, 9, 6)
    assert block(f, "sd_notouch_instance") == hist(11, 9, 6)
    assert block(f, "sd_touched_median") == hist(12, 12, 12, n=14)
    assert block(f, "sd_high_frame") == hist(11, 3, 6)
    assert block(f, "sd_high_instance") == hist(0, 3, 0)


def test_sd_named_preset_is_used_as_published():
    # HAART's own edges (width 5 up to 55.5 cells): 342, 228, 456 and even 114 lie beyond 55.5 -> all in bin 11
    f = features("sd", sd_capture(), preset="haart")
    assert block(f, "sd_notouch_frame") == [0] * 11 + [3]
    assert block(f, "sd_high_instance") == [2] + [0] * 10 + [1]


# --------------------------------------------------------------------- bmh
def test_bmh_offset_scales_with_the_value_range():
    # max 200; offset 5 * 255 / 1023 = 1.246: 199 >= 198.75 is set, 198 is not. Published 5: both set.
    c = np.zeros((2, 19, 24), dtype=np.uint8)
    c[0, 0, 0], c[1, 0, 1], c[1, 0, 2], c[1, 5, 5] = 200, 199, 198, 100
    scaled = features("bmh", c)
    assert len(scaled) == 456
    assert [k for k, v in scaled.items() if v] == ["bmh_r0_c0", "bmh_r0_c1"]
    published = features("bmh", c, preset="haart")
    assert [k for k, v in published.items() if v] == ["bmh_r0_c0", "bmh_r0_c1", "bmh_r0_c2"]
    # a 0..1023 sensor of the same grid keeps HAART's offset 5
    assert [k for k, v in features("bmh", c, WIDE_10BIT).items() if v] == ["bmh_r0_c0", "bmh_r0_c1", "bmh_r0_c2"]


# ------------------------------------------------------------------- smmhh
@pytest.mark.parametrize("change, moved", [
    (1, ["smmhh_k0_s2_m1_r0_c0"]),  # 1 > 0.748; pooled 1/4 is not
    (4, ["smmhh_k0_s2_m1_r0_c0", "smmhh_k1_s2_m1_r0_c0"]),  # pooled 4/4 = 1 > 0.748; 1/4 at the next scale is not
])
def test_smmhh_threshold_scales_and_pools_to_one_cell(change, moved):
    # threshold 3 * 255 / 1023 = 0.748; three frames, so only skip 2 has a pair (frame 0 against frame 2);
    # cell (0, 0) changes by `change` between them: one run of one motion frame where it exceeds the threshold.
    c = np.zeros((3, 19, 24), dtype=np.uint8)
    c[2, 0, 0] = change
    f = features("smmhh", c)
    # scales 19x24, 10x12, 5x6, 3x3, 2x2, 1x1 (456 + 120 + 30 + 9 + 4 + 1 = 620 pixels) x 5 skips x 5 lengths
    assert len(f) == 25 * 620
    assert [k for k, v in f.items() if v] == moved and all(f[k] == 1 for k in moved)
    # published threshold 3: a change of 1 or 4 at one cell; 4 > 3 moves the finest scale only
    published = features("smmhh", c, preset="haart")
    assert [k for k, v in published.items() if v] == (["smmhh_k0_s2_m1_r0_c0"] if change > 3 else [])


# ------------------------------------------------------------ own sets' floors
def own_capture(k: int = 10) -> np.ndarray:
    """Eight frames; k cells of row 3 are 0 in frame 0 and 2 in frames 1..7 (pressure 2 above their baseline 0)."""
    c = np.zeros((8, 19, 24), dtype=np.uint8)
    c[1:, 3, :k] = 2
    return c


def test_own_contact_floors_scale_with_the_value_range():
    c = own_capture()
    # touch-rhythm area: cells above max(20 % of the peak 2 = 0.4, floor 3 * 255 / 1023 = 0.748) -> 10 cells
    assert features("touch-rhythm", c)["A_max"] == 10
    assert features("touch-rhythm", c, WIDE_10BIT)["A_max"] == 0  # floor 3: a pressure of 2 is noise
    # cell-rhythm blobs: cells above max(50 % of the frame max = 1, 0.748) in frames 1..7: 10 each; 0 with floor 3
    assert features("cell-rhythm", c)["blob_cells_mean"] == 10
    assert features("cell-rhythm", c, WIDE_10BIT)["blob_cells_mean"] == 0
    # contact-motion: robust peak 2 (rank round(0.95 * 7) = 7 of the sorted frame maxima 0, 2, ..., 2);
    # threshold max(0.2, 4 * 255 / 1023 = 0.997): active in 7 of 8 frames; with floor 4 never
    assert features("contact-motion", c)["t10_actfrac"] == 7 / 8
    assert features("contact-motion", c, WIDE_10BIT)["t10_actfrac"] == 0


def test_own_sets_need_the_value_range_from_python():
    with pytest.raises(FeatureInputError, match=r"value range.*value_range=\(low, high\)"):
        make_feature_set("touch-rhythm", {"frame_rate": 12.0}, None).fit_transform([own_capture()])
    given = make_feature_set("touch-rhythm", {"frame_rate": 12.0, "value_range": (0, 255)}, None)
    assert np.array_equal(given.fit_transform([own_capture()]),
                          make_feature_set("touch-rhythm", {}, WIDE).fit_transform([own_capture()]))


# ------------------------------------------------------------ refused sensors
@pytest.mark.parametrize("name", ["sd", "bmh", "smmhh"])
def test_a_channel_sensor_is_refused_with_its_reason(name):
    fur = SensorSpec("fur", (1, 4), 50.0, (0, 1023), channels=("x", "y", "pressure", "fur"))
    fs = make_feature_set(name, {}, fur)
    problem = fs.check_sensor(fur)
    assert "channel sensor (x, y, pressure, fur)" in problem and "not cells of a pressure surface" in problem
    assert make_feature_set(name, {"preset": "haart"}, fur).check_sensor(fur) is None  # named: used as published
