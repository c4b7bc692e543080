"""Output files: uint16 millimetre depth (0 invalid), float32 disparity, JET colour, PLY; reading images."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from s2r.depth.outputs import depth_to_mm, disparity_colour, read_image, write_depth_png, write_outputs
from s2r.depth.pipeline import StereoPipeline
from s2r.errors import DepthError, OutputExistsError
from s2r.profile import StereoProfile
from tests.depth.synth import SynthPair


def test_depth_to_mm_convention() -> None:
    depth = np.array([[np.nan, 0.0005, 1.2344, 1.2346], [65.535, 70.0, -1.0, np.inf]], np.float32)
    mm = depth_to_mm(depth)
    assert mm.dtype == np.uint16
    assert mm.tolist() == [[0, 1, 1234, 1235], [65535, 65535, 0, 0]]


def test_depth_png_round_trip(tmp_path: Path) -> None:
    depth = np.array([[np.nan, 0.5], [2.25, 10.0]], np.float32)
    path = write_depth_png(tmp_path / "depth.png", depth)
    back = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert back.dtype == np.uint16 and back.tolist() == [[0, 500], [2250, 10000]]
    with pytest.raises(OutputExistsError, match=r"depth.png: already exists"):
        write_depth_png(path, depth)


def test_disparity_colour_blacks_out_invalid() -> None:
    disp = np.array([[np.nan, 1.0, 5.0]], np.float32)
    colour = disparity_colour(disp)
    assert colour.shape == (1, 3, 3) and colour[0, 0].tolist() == [0, 0, 0]
    assert colour[0, 2, 2] > colour[0, 2, 0]  # the largest disparity (nearest) is red in JET (BGR order)


def test_write_outputs(tmp_path: Path, pair: SynthPair, small_rig: StereoProfile) -> None:
    result = StereoPipeline(small_rig, preset="fast").compute(pair.left, pair.right)
    written = write_outputs(tmp_path, result, prefix="03_", ply=True)
    assert sorted(p.name for p in written) == ["03_depth.png", "03_depth_color.png", "03_disparity.npy",
                                               "03_points.ply"]
    disp = np.load(tmp_path / "03_disparity.npy")
    np.testing.assert_array_equal(disp, result.disparity)
    depth_mm = cv2.imread(str(tmp_path / "03_depth.png"), cv2.IMREAD_UNCHANGED)
    assert np.all((depth_mm == 0) == ~result.valid)
    np.testing.assert_allclose(depth_mm[result.valid] / 1000.0, result.depth[result.valid], atol=5e-4)
    raw = (tmp_path / "03_points.ply").read_bytes()
    header, body = raw.split(b"end_header\n", 1)
    assert f"element vertex {int(result.valid.sum())}".encode() in header
    rows = np.frombuffer(body, dtype=[("xyz", "<f4", (3,)), ("rgb", "u1", (3,))])
    np.testing.assert_array_equal(rows["xyz"], result.point_cloud()[0])


def test_read_image_errors(tmp_path: Path) -> None:
    with pytest.raises(DepthError, match=r"missing.png: image file not found"):
        read_image(tmp_path / "missing.png")
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    with pytest.raises(DepthError, match=r"bad.png: cannot read image"):
        read_image(bad)
    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    with pytest.raises(DepthError, match=r"empty.png: cannot read image"):
        read_image(empty)
    deep = tmp_path / "deep.png"
    cv2.imwrite(str(deep), np.zeros((4, 4), np.uint16))
    with pytest.raises(DepthError, match=r"deep.png: image has uint16 pixels"):
        read_image(deep)
    rgba = tmp_path / "rgba.png"
    cv2.imwrite(str(rgba), np.full((4, 4, 4), 7, np.uint8))
    assert read_image(rgba).shape == (4, 4, 3)
