"""``seed-sgbm`` is the seed's call verbatim: bit-equal to ``cv2.StereoSGBM_create`` with only the seed's arguments
(everything else at OpenCV's default), on real Middlebury pairs and on a rendered pair, raw and post-processed."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from s2r.depth.pipeline import StereoPipeline
from s2r.depth.presets import create_matcher
from s2r.profile import StereoProfile
from tests.conftest import make_rig, shared_data

_CLOSE = np.ones((3, 3), np.uint8)


def _seed_call(left: NDArray[np.uint8], right: NDArray[np.uint8], num_disparities: int = 112) -> NDArray[np.int16]:
    """The seed's own matcher, written out independently of s2r: only the arguments the seed passes."""
    sgbm = cv2.StereoSGBM_create(minDisparity=0, numDisparities=num_disparities, blockSize=5, P1=8 * 3 * 5 ** 2,
                                 P2=32 * 3 * 5 ** 2, disp12MaxDiff=1, uniquenessRatio=10, speckleWindowSize=100,
                                 speckleRange=32)
    return np.asarray(sgbm.compute(left, right), np.int16)


def _seed_post(raw: NDArray[np.int16]) -> NDArray[np.int16]:
    return np.asarray(cv2.morphologyEx(cv2.medianBlur(raw, 5), cv2.MORPH_CLOSE, _CLOSE), np.int16)


def test_seed_matcher_keeps_opencv_defaults(small_rig: StereoProfile) -> None:
    matcher = create_matcher(StereoPipeline(small_rig, preset="seed-sgbm").config)
    default = cv2.StereoSGBM_create()
    assert matcher.getPreFilterCap() == default.getPreFilterCap()  # the seed never sets it (OpenCV: 0)
    assert matcher.getMode() == default.getMode()
    assert (matcher.getP1(), matcher.getP2(), matcher.getNumDisparities()) == (600, 2400, 112)


@pytest.mark.parametrize("scene", ["cones", "teddy"])
def test_bit_equal_to_the_seed_call_on_middlebury(scene: str) -> None:
    folder = shared_data("middlebury", scene)
    left, right = cv2.imread(str(folder / "im2.png")), cv2.imread(str(folder / "im6.png"))
    rig = make_rig(name="mb", width=left.shape[1], height=left.shape[0])
    raw_pipe = StereoPipeline(rig, preset="seed-sgbm", postprocess=())
    geo = raw_pipe.geometry_for(rig.image_size)
    raw = raw_pipe.match(left, right, geo)
    expected = _seed_call(left, right)
    np.testing.assert_array_equal(raw, expected)
    full = StereoPipeline(rig, preset="seed-sgbm").match(left, right, geo)
    np.testing.assert_array_equal(full, _seed_post(expected))  # the seed's medianBlur 5 + 3x3 close, verbatim


def test_bit_equal_to_the_seed_call_on_a_rendered_pair() -> None:
    scenes = pytest.importorskip("s2r.render.scenes", reason="needs the PyBullet renderer")
    rig = make_rig(name="seed_rig", hfov_rad=1.396)  # the seed tutorial's camera_info (fx 381.36)
    frame = scenes.render_scene(rig, scene="slanted", distances_m=(1.5,), supersample=1, jobs=1)[0]
    pipe = StereoPipeline(rig, preset="seed-sgbm")
    rect_left, rect_right, _ = pipe.rectify(frame.left, frame.right)
    result = pipe.compute(frame.left, frame.right)
    expected = _seed_post(_seed_call(rect_left, rect_right)).astype(np.float32) / 16
    got = np.where(result.valid, result.disparity, np.float32(-1))
    np.testing.assert_array_equal(got[expected > 0], expected[expected > 0])
    assert not result.valid[expected <= 0].any()  # disparity 0 (infinitely far) and holes stay invalid
