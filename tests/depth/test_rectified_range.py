"""s2r depth --rectified (pairs rectified already, geometry given) against Middlebury's known disparity, and
--range (a fixed colour scale across a sequence)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.cli import main
from s2r.depth.outputs import depth_colour_with_bar
from s2r.fileio import read_npy
from tests.conftest import shared_data

GEOMETRY = ["--f", "1000", "--baseline", "0.1", "--cx", "224.5", "--cy", "187"]


def test_rectified_cones_match_the_known_disparity(tmp_path: Path) -> None:
    folder = shared_data("middlebury", "cones")
    out = tmp_path / "out"
    assert main(["-q", "depth", str(folder / "im2.png"), str(folder / "im6.png"), "--rectified", *GEOMETRY,
                 "--doffs", "2", "--num-disparities", "64", "--keep-out-of-range", "-o", str(out)]) == 0
    disparity = read_npy(out / "disparity.npy")
    gt = cv2.imread(str(folder / "disp2.png"), cv2.IMREAD_GRAYSCALE).astype(np.float64) / 4.0
    known, got = gt > 0, np.isfinite(disparity)
    both = known & got
    bad = float(np.mean(np.abs(disparity[both] - gt[both]) > 2.0))
    assert got[known].mean() > 0.6 and bad < 0.06, (got[known].mean(), bad)  # plain SGBM: 4.6 % bad-2.0
    depth_mm = cv2.imread(str(out / "depth.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)
    expected = 1000.0 * 1000.0 * 0.1 / (disparity[both] + 2.0)  # Z = f B / (d + doffs), mm
    assert np.allclose(depth_mm[both], expected, atol=0.6)


def test_rectified_needs_its_geometry_and_no_profile(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    image, right = tmp_path / "a.png", tmp_path / "b.png"
    for path in (image, right):
        cv2.imwrite(str(path), np.zeros((20, 30), np.uint8))
    base = ["depth", str(image), str(right), "-o", str(tmp_path / "o"), "--rectified"]
    assert main([*base, "--f", "100"]) == 2
    assert "--rectified: needs --baseline, --cx, --cy" in capsys.readouterr().err
    assert main([*base, *GEOMETRY, "--profile", "realsense_d435_848x480"]) == 2
    assert "--profile: does not apply to already-rectified pairs" in capsys.readouterr().err
    assert main([*base, "--f", "-1", "--baseline", "0.1", "--cx", "15", "--cy", "10"]) == 2
    assert "--f: out of range" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["5,1", "a,b", "0,2", "1", "nan,2", "1,inf"])
def test_a_bad_range_is_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path, text: str) -> None:
    image, right = tmp_path / "a.png", tmp_path / "b.png"
    for path in (image, right):
        cv2.imwrite(str(path), np.zeros((20, 30), np.uint8))
    assert main(["depth", str(image), str(right), "-o", str(tmp_path / "o"), "--rectified", *GEOMETRY,
                 "--range", text]) == 2
    assert capsys.readouterr().err.strip().startswith("error: --range:")


def test_a_fixed_range_gives_one_depth_one_colour_in_every_frame() -> None:
    f, B = 500.0, 0.1
    Q = np.array([[1, 0, 0, -50], [0, 1, 0, -40], [0, 0, 0, f], [0, 0, 1 / B, 0]], float)
    near_far = (1.0, 5.0)
    two_metres = f * B / 2.0  # 25 px
    frames = [np.full((80, 100), two_metres, np.float32), np.full((80, 100), two_metres, np.float32)]
    frames[0][:, :10], frames[1][:, :10] = f * B / 1.2, f * B / 4.0  # each frame's own extremes differ
    images = [depth_colour_with_bar(d, Q, near_far) for d in frames]
    assert np.array_equal(images[0][40, 50], images[1][40, 50])  # the same 2 m, the same colour
    own = [depth_colour_with_bar(d, Q) for d in frames]
    assert not np.array_equal(own[0][40, 50], own[1][40, 50])  # without --range each frame scales itself
    at_near = depth_colour_with_bar(np.full((80, 100), f * B / near_far[0], np.float32), Q, near_far)[40, 50]
    assert at_near[2] > 100 and at_near[0] < 50  # JET's near end is red (BGR)


def test_a_rectified_sequence_with_a_fixed_range(tmp_path: Path) -> None:
    root = shared_data("middlebury")
    for side, name in (("L", "im2.png"), ("R", "im6.png")):
        (tmp_path / side).mkdir()
        for k, scene in enumerate(("cones", "teddy")):
            (tmp_path / side / f"{k:02d}.png").write_bytes((root / scene / name).read_bytes())
    out = tmp_path / "seq"
    assert main(["-q", "depth", "--left-dir", str(tmp_path / "L"), "--right-dir", str(tmp_path / "R"),
                 "--rectified", *GEOMETRY, "--num-disparities", "64", "--range", "1.5,10", "-o", str(out)]) == 0
    assert (out / "00_depth_color.png").is_file() and (out / "01_depth_color.png").is_file()
    bars = [cv2.imread(str(out / f"{k:02d}_depth_color.png"))[:, -110:] for k in range(2)]
    assert np.array_equal(bars[0], bars[1])  # one scale: the colour bars (and their labels) are the same
