"""``s2r depth --preset seed-sgbm`` with no other option is the seed's code on grey image files.

The seed reads each image with ``cv2.imread`` (a grey PNG becomes three equal channels), rectifies with
``stereoRectify``'s default alpha (-1) and its flat ``T``, and matches with its SGBM call (penalties for three
channels), then medianBlur 5 and a 3x3 close. Written out here independently of s2r, except for
``s2r.compat.stereo_rectify``, whose job is to accept that flat ``T`` on OpenCV 5.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from s2r.cli import main
from s2r.compat import stereo_rectify
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.depth.test_seed_verbatim import _seed_call, _seed_post


def _seed(profile: StereoProfile, left_png: Path, right_png: Path, *, post: bool) -> NDArray[np.int16]:
    """The seed, verbatim in what it calls: camera_configs (flat T, alpha left to OpenCV), imread, remap, SGBM."""
    K1, K2, D1, D2 = profile.left.K, profile.right.K, profile.left.D[None, :], profile.right.D[None, :]
    T = np.array([float(v) for v in profile.T])  # flat, as the seed's camera_configs.py writes it
    size = profile.image_size
    R1, R2, P1, P2, _, _, _ = stereo_rectify(K1, D1, K2, D2, size, profile.R, T)
    lm1, lm2 = cv2.initUndistortRectifyMap(K1, D1, R1, P1, size, cv2.CV_16SC2)
    rm1, rm2 = cv2.initUndistortRectifyMap(K2, D2, R2, P2, size, cv2.CV_16SC2)
    img1, img2 = cv2.imread(str(left_png)), cv2.imread(str(right_png))  # 3 channels, even for a grey file
    r1 = cv2.remap(img1, lm1, lm2, cv2.INTER_LINEAR)
    r2 = cv2.remap(img2, rm1, rm2, cv2.INTER_LINEAR)
    raw = _seed_call(r1, r2)
    return _seed_post(raw) if post else raw


def test_flat_t_crashes_plain_opencv_and_compat_accepts_it() -> None:
    K, D, T = np.array([[400.0, 0, 320], [0, 400, 240], [0, 0, 1]]), np.zeros((1, 5)), np.array([-0.1, 0.0, 0.0])
    if cv2.__version__.startswith("5"):
        with pytest.raises(cv2.error):
            cv2.stereoRectify(K, D, K, D, (640, 480), np.eye(3), T)
    P2 = stereo_rectify(K, D, K, D, (640, 480), np.eye(3), T)[3]
    assert P2[0, 3] == pytest.approx(-40.0)  # -fx' * B


@pytest.mark.parametrize("post", [True, False])
def test_seed_sgbm_equals_the_seed_on_grey_files(tmp_path: Path, post: bool) -> None:
    scenes = pytest.importorskip("s2r.render.scenes", reason="needs the PyBullet renderer")
    rig = make_rig(name="seed_rig", width=320, height=240, hfov_rad=1.396, distortion=(-0.05, 0.01, 0.0, 0.0, 0.0),
                   rotation_deg=(0.2, -0.6, 0.1))
    frame = scenes.render_scene(rig, scene="slanted", distances_m=(1.2,), supersample=1, jobs=1)[0]
    left_png, right_png = tmp_path / "left.png", tmp_path / "right.png"
    cv2.imwrite(str(left_png), cv2.cvtColor(frame.left, cv2.COLOR_BGR2GRAY))
    cv2.imwrite(str(right_png), cv2.cvtColor(frame.right, cv2.COLOR_BGR2GRAY))
    profile_path = dump_profile(rig, tmp_path / "rig.yaml")
    args = ["depth", str(left_png), str(right_png), "--profile", str(profile_path), "--preset", "seed-sgbm",
            "--keep-out-of-range", "-o", str(tmp_path / "out")]
    assert main(args if post else [*args, "--postprocess", ""]) == 0
    got = np.load(tmp_path / "out" / "disparity.npy")
    expected = _seed(rig, left_png, right_png, post=post).astype(np.float32) / 16
    assert (expected > 0).mean() > 0.5  # the scene is matched, not empty
    np.testing.assert_array_equal(got[expected > 0], expected[expected > 0])
    assert not np.isfinite(got[expected <= 0]).any()
