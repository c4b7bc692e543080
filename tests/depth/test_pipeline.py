"""StereoPipeline on synthetic pairs with known disparity: every preset, NaN conventions, sizes, inputs."""

from __future__ import annotations

import dataclasses
import logging
import threading
from typing import Any

import cv2
import numpy as np
import pytest

from s2r.depth.names import PRESETS
from s2r.depth.pipeline import DepthResult, StereoPipeline
from s2r.errors import DepthError
from s2r.profile import Distortion, StereoProfile
from s2r.rectification import stereo_rectification
from tests.conftest import make_rig
from tests.depth.synth import SynthPair, make_pair


def _errors(result: DepthResult, pair: SynthPair) -> np.ndarray:
    known = np.isfinite(pair.disparity) & result.valid
    return np.abs(result.disparity - pair.disparity)[known]


@pytest.mark.parametrize("preset", PRESETS)
def test_every_preset_recovers_known_disparity(preset: str, pair: SynthPair, small_rig: StereoProfile) -> None:
    result = StereoPipeline(small_rig, preset=preset, num_disparities=64).compute(pair.left, pair.right)
    err = _errors(result, pair)
    assert err.size > 0.5 * pair.disparity.size  # most of the image (right of the 64 px blind border) matched
    assert np.median(err) <= 0.125
    assert np.mean(err > 1.0) < 0.01
    x0, x1, y0, y1 = pair.box
    box = result.disparity[y0 + 4:y1 - 4, x0 + 4:x1 - 4]
    assert np.isfinite(box).mean() > 0.98
    assert np.nanmedian(box) == pytest.approx(pair.d_box, abs=0.1)
    # depth along the rectified axis: fx' B / d, here fx' = fx (ideal rig) and B = 0.1 m
    expected_z = small_rig.left.fx_px * 0.1 / pair.d_box
    assert np.nanmedian(result.depth[y0 + 4:y1 - 4, x0 + 4:x1 - 4]) == pytest.approx(expected_z, rel=2e-3)


def test_nan_conventions(pair: SynthPair, small_rig: StereoProfile) -> None:
    result = StereoPipeline(small_rig, preset="fast").compute(pair.left, pair.right)
    assert result.disparity.dtype == np.float32 and result.depth.dtype == np.float32
    assert result.valid.dtype == np.bool_
    assert result.disparity.shape == result.depth.shape == result.valid.shape == (240, 320)
    np.testing.assert_array_equal(result.valid, np.isfinite(result.disparity))
    np.testing.assert_array_equal(result.valid, np.isfinite(result.depth))
    assert not result.valid.all()  # the left border cannot match
    assert np.all(result.depth[result.valid] > 0)
    assert not np.any(result.depth == 0)
    assert np.all(np.isnan(result.disparity[:, :16]))  # left of the disparity range: NaN, never 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.depth = result.depth  # type: ignore[misc]


def test_depth_matches_rectification_and_q(pair: SynthPair, distorted_rig: StereoProfile) -> None:
    pipe = StereoPipeline(distorted_rig, preset="fast")
    rect = stereo_rectification(distorted_rig, alpha=0.0)
    np.testing.assert_array_equal(pipe.rectification.P2, rect.P2)
    rl = cv2.resize(pair.left, (640, 480))
    rr = cv2.resize(pair.right, (640, 480))
    result = pipe.compute(rl, rr)
    np.testing.assert_allclose(result.depth, rect.depth_from_disparity(result.disparity), rtol=1e-6)
    points, colours = result.point_cloud()
    assert points.shape == colours.shape == (int(result.valid.sum()), 3)
    assert points.dtype == np.float32 and colours.dtype == np.uint8
    ys, xs = np.nonzero(result.valid)
    np.testing.assert_allclose(points[:, 2], result.depth[ys, xs], rtol=1e-5)
    np.testing.assert_allclose(points[:, 0], (xs - rect.P1[0, 2]) * points[:, 2] / rect.fx_px, rtol=1e-4, atol=1e-5)
    np.testing.assert_array_equal(colours[:, 0], result.rect_left[ys, xs])


def test_profile_matcher_settings_drive_the_profile_preset(small_rig: StereoProfile) -> None:
    matcher = small_rig.matcher.model_copy(update={"algorithm": "bm", "block_size": 9, "num_disparities": 48})
    pipe = StereoPipeline(small_rig.model_copy(update={"matcher": matcher}))
    assert (pipe.config.algorithm, pipe.config.block_size, pipe.config.num_disparities) == ("bm", 9, 48)


def test_num_disparities_derived_from_nearest_depth(small_rig: StereoProfile) -> None:
    # fx' B / z_min = 277.19 * 0.1 / 0.3 = 92.4 px -> 96
    assert StereoPipeline(small_rig, preset="fast").config.num_disparities == 96
    assert StereoPipeline(small_rig, preset="bm").config.num_disparities == 96
    assert StereoPipeline(small_rig, preset="fast", num_disparities=32).config.num_disparities == 32
    assert StereoPipeline(small_rig, preset="seed-sgbm").config.num_disparities == 112  # the seed's fixed range


def test_warns_when_preset_cannot_see_working_range(caplog: pytest.LogCaptureFixture, small_rig: StereoProfile
                                                     ) -> None:
    with caplog.at_level(logging.WARNING, logger="s2r"):
        StereoPipeline(small_rig, preset="ros-default")  # 64 px sees down to 0.44 m, the rig works from 0.3 m
    assert "ros-default" in caplog.text and "0.300 m" in caplog.text and "num_disparities=96" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="s2r"):
        StereoPipeline(small_rig, preset="fast")
    assert caplog.text == ""


def test_grey_and_colour_inputs(pair: SynthPair, small_rig: StereoProfile) -> None:
    grey = StereoPipeline(small_rig, preset="fast").compute(pair.left, pair.right)
    bgr = [cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) for img in (pair.left, pair.right)]
    colour = StereoPipeline(small_rig, preset="fast").compute(*bgr)
    np.testing.assert_array_equal(grey.disparity, colour.disparity)
    seed_colour = StereoPipeline(small_rig, preset="seed-sgbm").compute(*bgr)
    assert seed_colour.rect_left.ndim == 3  # the seed matches colour images
    seed_grey = StereoPipeline(small_rig, preset="seed-sgbm").compute(pair.left, pair.right)
    assert seed_grey.rect_left.ndim == 3  # a grey pair as the seed's cv2.imread gives it: three equal channels
    np.testing.assert_array_equal(seed_grey.disparity, seed_colour.disparity)
    assert np.nanmedian(seed_grey.disparity[60:180, 164:236]) == pytest.approx(30, abs=0.1)


def test_size_mismatch_with_profile_is_an_error(pair: SynthPair) -> None:
    rig = make_rig(name="vga_rig")
    with pytest.raises(DepthError, match=r"images are 320x240 but profile vga_rig is 640x480.*resize"):
        StereoPipeline(rig, preset="fast").compute(pair.left, pair.right)


def test_resize_rescales_intrinsics(pair: SynthPair) -> None:
    rig = make_rig(name="vga_rig")  # fx 554.38 at 640: at 320 wide fx' = 277.19
    result = StereoPipeline(rig, preset="fast", resize=True).compute(pair.left, pair.right)
    x0, x1, y0, y1 = pair.box
    z = np.nanmedian(result.depth[y0 + 4:y1 - 4, x0 + 4:x1 - 4])
    assert z == pytest.approx(rig.left.fx_px / 2 * 0.1 / pair.d_box, rel=2e-3)


def test_left_right_size_mismatch(pair: SynthPair, small_rig: StereoProfile) -> None:
    with pytest.raises(DepthError, match=r"right: left image is 320x240 but right is 320x200"):
        StereoPipeline(small_rig).compute(pair.left, pair.right[:200])


@pytest.mark.parametrize(
    ("image", "message"),
    [
        (np.zeros((240, 320), np.uint16), "expected 8-bit pixels, got uint16"),
        (np.zeros((240, 320, 2), np.uint8), r"got shape \(240, 320, 2\)"),
        ([[0, 1]], "expected a numpy image, got list"),
    ],
)
def test_bad_image_arrays(image: object, message: str, pair: SynthPair, small_rig: StereoProfile) -> None:
    with pytest.raises(DepthError, match=f"left: .*{message}"):
        StereoPipeline(small_rig, preset="fast").compute(image, pair.right)


def test_bad_options(small_rig: StereoProfile) -> None:
    with pytest.raises(DepthError, match="preset: unknown preset 'nope'"):
        StereoPipeline(small_rig, preset="nope")
    with pytest.raises(DepthError, match="postprocess: unknown post-processing stage 'blur'"):
        StereoPipeline(small_rig, postprocess=["median", "blur"])
    with pytest.raises(DepthError, match=r"num_disparities: .*multiple of 16, got 40"):
        StereoPipeline(small_rig, num_disparities=40)
    with pytest.raises(DepthError, match="do not fit the 320 px image"):
        StereoPipeline(small_rig, num_disparities=320)


def test_lr_check_and_fill_through_the_pipeline(pair: SynthPair, small_rig: StereoProfile) -> None:
    plain = StereoPipeline(small_rig, preset="bm", postprocess=()).compute(pair.left, pair.right)
    checked = StereoPipeline(small_rig, preset="bm", postprocess=["lr-check"]).compute(pair.left, pair.right)
    assert checked.valid.sum() <= plain.valid.sum()
    assert np.all(plain.valid[checked.valid])  # lr-check only removes
    filled = StereoPipeline(small_rig, preset="bm", postprocess=["lr-check", "fill"]).compute(pair.left, pair.right)
    rows_with_data = checked.valid.any(axis=1)
    assert filled.valid[rows_with_data].all() and not filled.valid[~rows_with_data].any()
    assert rows_with_data.sum() == 240 - 14  # StereoBM's 15 px block leaves 7 rows top and bottom unmatched
    np.testing.assert_array_equal(filled.disparity[checked.valid], checked.disparity[checked.valid])


def test_compute_is_thread_safe(small_rig: StereoProfile) -> None:
    pairs = [make_pair(seed=s) for s in range(4)]
    pipe = StereoPipeline(small_rig, preset="profile")
    serial = [pipe.compute(p.left, p.right).disparity for p in pairs]
    out: dict[int, np.ndarray] = {}
    threads = [threading.Thread(target=lambda i=i: out.__setitem__(i, pipe.compute(pairs[i].left,
                                                                                  pairs[i].right).disparity))
               for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(4):
        np.testing.assert_array_equal(out[i], serial[i])


def test_fisheye_profile_uses_fisheye_maps(pair: SynthPair) -> None:
    rig = make_rig(name="fisheye_rig", width=320, height=240)
    cam = rig.left.model_copy(update={"distortion": Distortion(model="equidistant", coefficients=(0.0,) * 4)})
    fisheye = rig.model_copy(update={"left": cam, "right": cam})
    pipe = StereoPipeline(fisheye, preset="fast", num_disparities=48)
    K_new = pipe.rectification.P1[:, :3]
    expected, _ = cv2.fisheye.initUndistortRectifyMap(cam.K, cam.D, pipe.rectification.R1, K_new, (320, 240),
                                                      cv2.CV_16SC2)
    np.testing.assert_array_equal(pipe.maps.left_map1, expected)
    result = pipe.compute(pair.left, pair.right)
    assert result.valid.mean() > 0.5


def test_derived_range_is_clamped_to_the_image(caplog: pytest.LogCaptureFixture, small_rig: StereoProfile) -> None:
    close_up = small_rig.model_copy(update={"matcher": small_rig.matcher.model_copy(update={"min_depth_m": 0.05})})
    with caplog.at_level(logging.WARNING, logger="s2r"):
        pipe = StereoPipeline(close_up, preset="fast")  # fx' B / z = 554 px > 320 px image
    assert pipe.config.num_disparities == 304
    assert "it needs num_disparities=560" in caplog.text


@pytest.mark.parametrize("name", ["gazebo_dual_camera", "xbot_u_stereo", "realsense_d435_848x480"])
def test_shipped_profiles_build_every_preset(name: str) -> None:
    from s2r.registry import list_profiles

    if name not in list_profiles():
        pytest.skip(f"profile {name} not shipped yet")
    for preset in PRESETS:
        pipe = StereoPipeline(name, preset=preset)
        assert pipe.profile.name == name and pipe.maps.left_map1.shape[:2] == pipe.profile.image_size[::-1]


def test_resize_scales_a_fixed_disparity_range(pair: SynthPair) -> None:
    rig = make_rig(name="vga_rig")
    rig = rig.model_copy(update={"matcher": rig.matcher.model_copy(update={"num_disparities": 112})})
    pipe = StereoPipeline(rig, resize=True)
    assert pipe.config.num_disparities == 112
    pipe.compute(pair.left, pair.right)
    assert pipe.geometry_for((320, 240)).config.num_disparities == 64  # 112 / 2 = 56, up to 16



def _compute_in_child(rig: StereoProfile, left: np.ndarray, right: np.ndarray, out: Any) -> None:
    result = StereoPipeline(rig, preset="profile", postprocess=("lr-check",)).compute(left, right)
    out.put(int(result.valid.sum()))


def test_lr_check_works_in_a_forked_child_after_use_in_the_parent(pair: SynthPair, small_rig: StereoProfile) -> None:
    # The lr-check thread pool is process-global; a forked child must not inherit the parent's dead pool
    # (this hung `s2r validate` when its process pool forked after an earlier pipeline had run).
    import multiprocessing
    import queue

    pipe = StereoPipeline(small_rig, preset="profile", postprocess=("lr-check",))
    in_parent = int(pipe.compute(pair.left, pair.right).valid.sum())
    context = multiprocessing.get_context("fork")
    out = context.Queue()
    child = context.Process(target=_compute_in_child, args=(small_rig, pair.left, pair.right, out))
    child.start()
    try:
        in_child = out.get(timeout=60)
    except queue.Empty:
        pytest.fail("the depth pipeline hung in a forked child process")
    finally:
        child.join(timeout=5)
        if child.is_alive():
            child.kill()
    assert in_child == in_parent > 0
