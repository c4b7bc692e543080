"""The independent generator itself: its numpy plumb_bob projection agrees with OpenCV's, and its rigs are sane."""

from __future__ import annotations

import cv2
import numpy as np

from tests.calib.independent_rig import SIZE, make_rig, project, rotation


def test_numpy_projection_matches_opencv() -> None:
    rig = make_rig(3, views=3, noise_px=0.0)
    lens = rig.left_lens
    K = np.array([[lens.fx, 0, lens.cx], [0, lens.fy, lens.cy], [0, 0, 1.0]])
    rvec = np.array([0.2, -0.3, 0.1])
    pts = rig.board + np.array([-0.1, -0.06, 0.5])
    ours = project(lens, pts @ rotation(rvec).T)
    theirs = cv2.projectPoints(pts, rvec, np.zeros(3), K, np.array(lens.dist))[0].reshape(-1, 2)
    assert np.max(np.abs(ours - theirs)) < 1e-9


def test_rig_views_are_inside_both_images_with_the_right_camera_to_the_right() -> None:
    rig = make_rig(5, views=20)
    assert len(rig.left) == len(rig.right) == 20
    for pts in (*rig.left, *rig.right):
        assert pts.shape == (54, 2) and pts[:, 0].min() > 0 and pts[:, 0].max() < SIZE[0]
    centre_right = -rig.R.T @ rig.T
    assert 0.06 <= centre_right[0] <= 0.12 and max(abs(rig.left_lens.dist[2]), abs(rig.left_lens.dist[3])) <= 5e-4
