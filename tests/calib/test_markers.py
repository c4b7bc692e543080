"""cv2.aruco detection of ChArUco boards and Kalibr AprilGrids on ray-cast images with known corners."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml

from s2r.calib.detect import CornerCache, Detection
from s2r.calib.detect.markers import detect_target
from s2r.targets import target_from_mapping
from tests import raycast as rc

LENS = rc.Lens(480, 360, 400.0, 400.0, 241.3, 178.6, "plumb_bob", (-0.1, 0.02, 0.0, 0.0, 0.0))


def _view(target: rc.Target, shift: float) -> tuple[np.ndarray, np.ndarray]:
    """A ray-cast image of ``target`` tilted 25 deg, moved sideways by ``shift`` (m), and the true pixels."""
    R = np.asarray(cv2.Rodrigues(np.radians([15.0, 20.0, 10.0]).reshape(3, 1))[0], np.float64)
    if target.y_up:
        R = R @ np.diag([1.0, -1.0, -1.0])
    t = np.array([shift, 0.0, 0.45]) - R @ target.points.mean(axis=0)
    img = rc.render(LENS, target, R, t, seed=1, noise=1.0)
    return img, LENS.project(target.points @ R.T + t)


@pytest.mark.parametrize("make", [lambda: rc.charuco_target((7, 5), 0.04, 0.03, "DICT_4X4_50", 60),
                                  lambda: rc.aprilgrid_target((5, 4), 0.045, 0.3, 60)])
def test_corners_and_ids_match_the_truth(make) -> None:  # type: ignore[no-untyped-def]
    tg = make()
    target = target_from_mapping(yaml.safe_load(tg.yaml))
    img, truth = _view(tg, 0.0)
    found, _ = detect_target(img, target)
    assert found is not None
    ids, pts = found
    err = np.linalg.norm(pts - truth[ids], axis=1)
    assert len(ids) >= 0.9 * len(tg.ids)
    assert float(np.median(err)) < 0.1 and float(np.max(err)) < 0.5
    # a view cut by the image edge still yields its visible corners, with the right ids
    img, truth = _view(tg, 0.17)
    found, _ = detect_target(img, target)
    assert found is not None
    ids, pts = found
    assert 6 <= len(ids) < len(tg.ids)
    assert float(np.median(np.linalg.norm(pts - truth[ids], axis=1))) < 0.15


def test_cache_keeps_ids(tmp_path) -> None:  # type: ignore[no-untyped-def]
    target = target_from_mapping(yaml.safe_load(rc.charuco_target((5, 5), 0.04, 0.03, "DICT_4X4_50").yaml))
    cache = CornerCache(tmp_path, target)
    det = Detection("a.png", "ab" * 32, "ok", size=(10, 10), corners=np.ones((3, 2), np.float32),
                    ids=np.array([4, 7, 9], np.int32))
    cache.put(det, (0, 0))
    back = cache.get("b.png", "ab" * 32, (0, 0))
    assert back is not None and back.ids is not None and back.ids.tolist() == [4, 7, 9] and back.name == "b.png"
    # a chessboard cache of the same image is a different entry (no ids)
    assert CornerCache(tmp_path).get("b.png", "ab" * 32, (9, 6)) is None
