"""Every preset in stereo_image_proc's ranges (Disparity.cfg), each change said; ranges written out by hand."""

from __future__ import annotations

import pytest

from s2r.depth.names import PRESETS
from s2r.depth.presets import resolve_preset
from s2r.depth.ros_params import ros_disparity_params
from tests.conftest import make_rig

#: image_pipeline 1.17 stereo_image_proc/cfg/Disparity.cfg, by hand.
RANGES = {"prefilter_size": (5, 255), "prefilter_cap": (1, 63), "correlation_window_size": (5, 255),
          "min_disparity": (-2048, 2048), "disparity_range": (32, 4096), "uniqueness_ratio": (0, 100),
          "texture_threshold": (0, 10000), "speckle_size": (0, 1000), "speckle_range": (0, 31), "P1": (0, 4000),
          "P2": (0, 4000), "disp12MaxDiff": (0, 128)}


@pytest.mark.parametrize("preset", PRESETS)
def test_each_preset_fits_ros_ranges(preset: str) -> None:
    rig = make_rig(width=320, height=240)
    config = resolve_preset(preset, rig, fx_px=rig.left.fx_px, baseline_m=rig.baseline_m)
    params, notes = ros_disparity_params(config)
    for name, value in params.items():
        if name in RANGES:
            assert RANGES[name][0] <= value <= RANGES[name][1], (name, value)
    assert params["disparity_range"] % 16 == 0 and params["correlation_window_size"] % 2 == 1
    assert params["stereo_algorithm"] == (0 if config.algorithm == "bm" else 1)
    if config.speckle_range > 31:
        assert f"speckle_range {config.speckle_range} is outside stereo_image_proc's range 0..31: set to 31" in notes
    if preset == "seed-sgbm":
        assert "P1 600 and P2 2400 were chosen for colour images; stereo_image_proc matches grey ones" in notes
        assert params["prefilter_cap"] == 15  # OpenCV's default 0, which SGBM runs as max(cap, 15) | 1 = 15
    if preset == "fast":
        assert any("mode sgbm_3way is not available" in note for note in notes)
