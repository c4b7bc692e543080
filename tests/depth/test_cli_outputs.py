"""``s2r depth`` outputs a downstream node can use: camera_info.yaml of the rectified left camera, f/B/Q in
--json, depth limited to the profile's working range (unless --keep-out-of-range), a colour bar in metres."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.depth.outputs import depth_colour_with_bar, disparity_colour
from s2r.formats.ros_read import read_camera_info
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.depth.synth import SynthPair

# small_rig: fx 277.19 px, B 0.1 m; the synthetic pair's background is 12 px (2.31 m), its box 30 px (0.92 m)
FB = 320 / (2 * np.tan(1.047 / 2)) * 0.1


def _run(tmp_path: Path, pair: SynthPair, rig: StereoProfile, *extra: str,
         capsys: pytest.CaptureFixture[str]) -> tuple[Path, dict[str, object]]:
    profile = dump_profile(rig, tmp_path / f"{rig.name}.yaml")
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    cv2.imwrite(str(left), pair.left)
    cv2.imwrite(str(right), pair.right)
    out = tmp_path / "out"
    assert main(["depth", "--profile", str(profile), str(left), str(right), "-o", str(out), "--preset", "fast",
                 "--ply", "--json", *extra]) == 0
    return out, json.loads(capsys.readouterr().out)


def _ply_points(path: Path) -> np.ndarray:
    data = path.read_bytes()
    head, body = data.split(b"end_header\n", 1)
    n = int(head.split(b"element vertex ")[1].split(b"\n")[0])
    return np.frombuffer(body, dtype=[("xyz", "<f4", (3,)), ("rgb", "u1", (3,))], count=n)["xyz"]


def test_camera_info_describes_the_depth_image(tmp_path: Path, pair: SynthPair, small_rig: StereoProfile,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out, data = _run(tmp_path, pair, small_rig, capsys=capsys)
    info = read_camera_info(out / "camera_info.yaml")  # s2r's ROS reader; checked by hand against the format
    depth_mm = cv2.imread(str(out / "depth.png"), cv2.IMREAD_UNCHANGED)
    assert (info.width, info.height) == (depth_mm.shape[1], depth_mm.shape[0]) == (320, 240)
    assert np.allclose(info.R, np.eye(3)) and np.allclose(info.D, 0) and info.distortion_model == "plumb_bob"
    assert np.allclose(info.K, info.P[:, :3]) and np.allclose(info.P[:, 3], 0)
    # --json states the same f, the baseline and Q
    assert data["f_px"] == pytest.approx(info.K[0, 0]) == pytest.approx(FB / 0.1, rel=1e-3)
    assert data["baseline_m"] == pytest.approx(0.1)
    Q = np.array(data["Q"])
    assert Q.shape == (4, 4) and Q[2, 3] == pytest.approx(data["f_px"])
    # every PLY point projects through the camera_info's P back onto a pixel whose depth.png holds its z
    xyz = _ply_points(out / "points.ply").astype(np.float64)
    uvw = np.c_[xyz, np.ones(len(xyz))] @ info.P.T
    u, v = np.rint(uvw[:, 0] / uvw[:, 2]).astype(int), np.rint(uvw[:, 1] / uvw[:, 2]).astype(int)
    assert np.all((u >= 0) & (u < 320) & (v >= 0) & (v < 240))
    assert np.allclose(depth_mm[v, u] / 1000.0, xyz[:, 2], atol=0.0006)


def test_depth_is_limited_to_the_profile_range(tmp_path: Path, pair: SynthPair,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    rig = make_rig(name="short_range", width=320, height=240)
    rig = rig.model_copy(update={"matcher": rig.matcher.model_copy(update={"max_depth_m": 1.5})})
    out, data = _run(tmp_path, pair, rig, capsys=capsys)
    depth_mm = cv2.imread(str(out / "depth.png"), cv2.IMREAD_UNCHANGED)
    x0, x1, y0, y1 = pair.box
    assert depth_mm.max() <= 1500 and np.median(depth_mm[y0 + 4:y1 - 4, x0 + 4:x1 - 4]) == pytest.approx(924, abs=5)
    assert depth_mm[:, :x0 - 20].max() == 0  # the 2.31 m background is beyond 1.5 m: invalid
    assert np.all(np.isnan(np.load(out / "disparity.npy"))[depth_mm == 0])
    assert _ply_points(out / "points.ply")[:, 2].max() <= 1.5
    assert data["depth_range_m"] == [0.3, 1.5] and int(str(data["out_of_range_removed"])) > 10000
    (tmp_path / "keep").mkdir()
    kept, data = _run(tmp_path / "keep", pair, rig, "--keep-out-of-range", capsys=capsys)
    depth_kept = cv2.imread(str(kept / "depth.png"), cv2.IMREAD_UNCHANGED)
    assert np.median(depth_kept[:, :x0 - 20][depth_kept[:, :x0 - 20] > 0]) == pytest.approx(FB / 12 * 1000, rel=0.01)
    assert data["depth_range_m"] is None and data["out_of_range_removed"] == 0


def test_colour_bar_adds_a_labelled_panel(pair: SynthPair, small_rig: StereoProfile) -> None:
    from s2r.depth.pipeline import StereoPipeline

    pipe = StereoPipeline(small_rig, preset="fast")
    result = pipe.compute(pair.left, pair.right)
    plain, with_bar = disparity_colour(result.disparity), depth_colour_with_bar(result.disparity, result.Q)
    assert with_bar.shape[0] == plain.shape[0] and with_bar.shape[1] > plain.shape[1]
    assert np.array_equal(with_bar[:, :plain.shape[1]], plain)
    panel = with_bar[:, plain.shape[1]:]
    assert (panel < 100).all(axis=2).sum() > 100  # dark label text on the white panel
    assert len(np.unique(panel.reshape(-1, 3), axis=0)) > 100  # the JET ramp
