"""Ground-truth depth scenes: exact depth, disparity = fx' B / Z in the rectified image, matchable texture."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from s2r.errors import OutputExistsError, RenderError
from s2r.profile import StereoProfile
from s2r.rectification import stereo_rectification
from s2r.render import SCENES, render_scene, write_scene


def _rect_rays_left(profile: StereoProfile) -> np.ndarray:
    """Rays (H, W, 3) of every rectified left pixel, expressed in the left optical frame."""
    rect = stereo_rectification(profile, alpha=0.0)
    w, h = profile.image_size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    Kr = rect.P1[:3, :3]
    ray_rect = np.stack([(u - Kr[0, 2]) / Kr[0, 0], (v - Kr[1, 2]) / Kr[1, 1], np.ones_like(u)], axis=-1)
    return np.asarray(ray_rect @ rect.R1)  # R1 maps left -> rectified, so left = R1^T rect


def test_plane_at_one_metre_is_exact(rig: StereoProfile) -> None:
    (frame,) = render_scene(rig, distances_m=[1.0], jobs=1)
    assert frame.left.shape == (480, 640, 3) and frame.left.dtype == np.uint8
    assert frame.depth_m.dtype == np.float32 and not np.isnan(frame.depth_m).any()
    assert np.max(np.abs(frame.depth_m - 1.0)) < 1e-4  # within 0.1 mm
    rect = stereo_rectification(rig, alpha=0.0)
    expected = rect.fx_px * rect.baseline_m / 1.0
    assert rect.doffs_px == 0.0
    assert np.nanmax(np.abs(frame.disparity_rect_px - expected)) < 1e-3
    assert np.nanmax(np.abs(frame.depth_rect_m - 1.0)) < 1e-4
    assert frame.description["rectification"]["fx_px"] == pytest.approx(rect.fx_px)


def test_rectified_truth_of_a_distorted_rotated_rig(distorted_rig: StereoProfile) -> None:
    """Plane z_left = 1.5 m: in the rectified frame, Z_rect = 1.5 / (R1^T ray_rect)_z per pixel."""
    (frame,) = render_scene(distorted_rig, distances_m=[1.5], jobs=1)
    ray_left = _rect_rays_left(distorted_rig)
    z_rect = 1.5 / ray_left[..., 2]
    valid = ~np.isnan(frame.depth_rect_m)
    assert valid.mean() > 0.99
    assert np.max(np.abs(frame.depth_rect_m[valid] - z_rect[valid])) < 2e-4
    rect = stereo_rectification(distorted_rig, alpha=0.0)
    np.testing.assert_allclose(frame.disparity_rect_px[valid], rect.fx_px * rect.baseline_m / z_rect[valid],
                               rtol=1e-5)
    assert np.nanmax(np.abs(frame.depth_m - 1.5)) < 1e-4


def test_slanted_plane_depth_matches_geometry(rig: StereoProfile) -> None:
    (frame,) = render_scene(rig, scene="slanted", distances_m=[2.0], jobs=1, supersample=1)
    (surface,) = frame.description["surfaces"]
    n, p0 = np.array(surface["normal"]), np.array(surface["point_m"])
    w, h = rig.image_size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = np.stack([(u - rig.left.cx_px) / rig.left.fx_px, (v - rig.left.cy_px) / rig.left.fy_px,
                     np.ones_like(u)], axis=-1)
    z = (n @ p0) / (rays @ n)
    assert np.ptp(z) > 1.0  # really slanted
    assert not np.isnan(frame.depth_m).any()
    np.testing.assert_allclose(frame.depth_m, z, rtol=2e-5)


def test_room_has_depth_edges_only_at_object_borders(rig: StereoProfile) -> None:
    (frame,) = render_scene(rig, scene="room", distances_m=[1.0, 2.0], jobs=1, supersample=1)
    nan = np.isnan(frame.depth_m)
    assert 0.0 < nan.mean() < 0.05  # edges of boxes and room corners
    assert np.nanmin(frame.depth_m) < 1.1 and np.nanmax(frame.depth_m) > 2.4
    assert [s["kind"] for s in frame.description["surfaces"]] == ["room", "box", "box"]


def test_sgbm_on_rendered_planes_finds_the_true_disparity(rig: StereoProfile) -> None:
    """The speckle texture is matchable: plain SGBM on the rectified pair agrees with the ground truth."""
    frames = render_scene(rig, distances_m=[0.5, 3.0], jobs=1, noise_sigma=1.0)
    rect = stereo_rectification(rig, alpha=0.0)
    maps = [cv2.initUndistortRectifyMap(cam.K, cam.D, R, P, rig.image_size, cv2.CV_32FC1)
            for cam, R, P in ((rig.left, rect.R1, rect.P1), (rig.right, rect.R2, rect.P2))]
    sgbm = cv2.StereoSGBM_create(0, 128, 5, P1=8 * 3 * 25, P2=32 * 3 * 25, uniquenessRatio=10,
                                 mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    for frame in frames:
        left, right = (cv2.remap(img, m[0], m[1], cv2.INTER_LINEAR) for img, m in zip((frame.left, frame.right),
                                                                                    maps, strict=True))
        disp = sgbm.compute(left, right).astype(np.float32) / 16.0
        good = (disp > 0) & ~np.isnan(frame.disparity_rect_px)
        assert good.mean() > 0.6
        err = np.abs(disp[good] - frame.disparity_rect_px[good])
        assert np.median(err) < 0.25, (frame.description["distance_m"], np.median(err))


def test_write_scene_layout_and_refusal(rig: StereoProfile, tmp_path: Path) -> None:
    frames = render_scene(rig, distances_m=[1.0, 2.0], jobs=2, supersample=1)
    out = write_scene(frames, tmp_path / "scene")
    assert sorted(p.name for p in (out / "depth").iterdir()) == ["00.npy", "01.npy"]
    depth = np.load(out / "depth" / "01.npy")
    assert depth.dtype == np.float32 and np.nanmax(np.abs(depth - 2.0)) < 2e-4
    np.testing.assert_array_equal(np.load(out / "disparity" / "00.npy"), frames[0].disparity_rect_px)
    np.testing.assert_array_equal(cv2.imread(str(out / "left" / "00.png")), frames[0].left)
    meta = yaml.safe_load((out / "scene.yaml").read_text())
    assert [f["name"] for f in meta["frames"]] == ["00", "01"]
    assert meta["frames"][1]["description"]["distance_m"] == 2.0
    with pytest.raises(OutputExistsError, match="pass --force"):
        write_scene(frames, out)
    write_scene(frames[:1], out, force=True)
    assert sorted(p.name for p in (out / "left").iterdir()) == ["00.png"]


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"scene": "forest"}, "scene"), ({"distances_m": []}, "distances"), ({"distances_m": [80.0]}, "distances"),
    ({"supersample": 9}, "supersample"), ({"noise_sigma": -0.5}, "noise_sigma"), ({"right_gain": 0.0}, "right_gain"),
])
def test_bad_scene_requests_name_the_field(rig: StereoProfile, kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(RenderError, match=rf"^{field}: "):
        render_scene(rig, jobs=1, **kwargs)  # type: ignore[arg-type]
    assert set(SCENES) == {"planes", "slanted", "span", "room"}


def test_gain_and_noise_change_only_the_right_image_as_asked(rig: StereoProfile) -> None:
    (plain,) = render_scene(rig, distances_m=[1.0], jobs=1, supersample=1)
    (gained,) = render_scene(rig, distances_m=[1.0], jobs=1, supersample=1, right_gain=0.8)
    np.testing.assert_array_equal(plain.left, gained.left)
    ratio = gained.right.astype(np.float64).mean() / plain.right.astype(np.float64).mean()
    assert ratio == pytest.approx(0.8, abs=0.01)
    (noisy,) = render_scene(rig, distances_m=[1.0], jobs=1, supersample=1, noise_sigma=3.0)
    diff = noisy.left.astype(np.float64) - plain.left.astype(np.float64)
    assert diff.std() == pytest.approx(3.0, rel=0.1)
