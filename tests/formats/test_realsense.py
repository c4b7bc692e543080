"""RealSense rs-enumerate-devices -c text: infrared pair, resolution choice, extrinsics convention."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from s2r.errors import FormatError
from s2r.formats.realsense.text import load_realsense, parse_realsense

FIXTURE = Path(__file__).parent / "data" / "rs_enumerate_devices_d435.txt"


def test_default_resolution_is_848x480_with_reference_figures() -> None:
    rig = load_realsense(FIXTURE)
    assert rig.image_size == (848, 480) and rig.name == "realsense_848x480"
    assert 421 <= rig.left.fx_px <= 427 and 420 <= rig.left.cx_px <= 425 and 234 <= rig.left.cy_px <= 236
    assert rig.left.fx_px == pytest.approx(424.691284179688)
    # right imager 50 mm to the right of the left one: OpenCV T = (-0.050, 0, 0)
    np.testing.assert_allclose(rig.T, [-0.0499795265495777, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(rig.R, np.eye(3))
    assert rig.left.distortion.model == "plumb_bob" and rig.left.distortion.is_zero
    assert rig.provenance.origin == "real" and rig.provenance.method == "imported from rs-enumerate-devices"
    assert rig.left.frame_id == "camera_infra1_optical_frame"


def test_other_resolution_on_request() -> None:
    rig = load_realsense(FIXTURE, resolution=(1280, 720))
    assert rig.image_size == (1280, 720)
    assert 636 <= rig.left.fx_px <= 645 and 634 <= rig.left.cx_px <= 642 and 351 <= rig.left.cy_px <= 353
    with pytest.raises(FormatError, match=r"--resolution: resolution 640x480 not listed \(available: 848x480, "
                                          r"1280x720\)"):
        load_realsense(FIXTURE, resolution=(640, 480))


def test_parser_reads_every_block() -> None:
    intrinsics, extrinsics = parse_realsense(FIXTURE)
    assert {(i.stream, i.width) for i in intrinsics} >= {("Infrared 1", 848), ("Infrared 2", 1280), ("Color", 640)}
    colour = next(e for e in extrinsics if e.target == "Color")
    assert colour.R[0, 1] == pytest.approx(0.00521343) and colour.t[0] == pytest.approx(0.0148525638505816)


def _text_with_rotation(rot_printed: np.ndarray, t_fwd: np.ndarray, t_rev: np.ndarray | None) -> str:
    base = FIXTURE.read_text().split("\nExtrinsic Parameters:")[0]

    def block(a: str, b: str, rot: np.ndarray, t: np.ndarray) -> str:
        rows = "\n".join("".join(f"{v:>14.9f}" for v in row) for row in rot)
        return (f'Extrinsic from "{a}"\t  To\t  "{b}" :\n Rotation Matrix:\n{rows}\n\n'
                f" Translation Vector: {float(t[0])!r}  {float(t[1])!r}  {float(t[2])!r}  \n\n")

    text = base + "\nExtrinsic Parameters:\n" + block("Infrared 1", "Infrared 2", rot_printed, t_fwd)
    if t_rev is not None:
        text += block("Infrared 2", "Infrared 1", rot_printed.T, t_rev)
    return text


def test_rotation_orientation_is_checked_against_the_reverse_extrinsic(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """p_B = R p_A + t: the reverse block must hold t' = -R^T t; a transposed print is detected and undone."""
    R = Rotation.from_euler("xyz", [2.0, -3.0, 1.5], degrees=True).as_matrix()
    t = np.array([-0.05, 0.001, 0.002])
    good = tmp_path / "good.txt"
    good.write_text(_text_with_rotation(R, t, -R.T @ t))
    rig = load_realsense(good)
    np.testing.assert_allclose(rig.R, R, atol=1e-8)
    np.testing.assert_allclose(rig.T, t, atol=1e-15)
    old = tmp_path / "old.txt"
    old.write_text(_text_with_rotation(R.T, t, -R.T @ t))  # storage order printed: the transpose
    with caplog.at_level(logging.WARNING, logger="s2r"):
        rig_old = load_realsense(old)
    np.testing.assert_allclose(rig_old.R, R, atol=1e-8)
    assert "storage order" in caplog.text


def test_missing_extrinsic_and_unsupported_distortion(tmp_path: Path) -> None:
    text = FIXTURE.read_text()
    cut = tmp_path / "no_extrinsics.txt"
    cut.write_text(text.split("\nExtrinsic Parameters:")[0])
    with pytest.raises(FormatError, match=r'Extrinsic from "Infrared 1" To "Infrared 2": extrinsic block is missing'):
        load_realsense(cut)
    bad = tmp_path / "ftheta.txt"
    bad.write_text(text.replace("Brown Conrady\n  Coeffs:     \t0  ", "Ftheta\n  Coeffs:     \t0.3  "))
    with pytest.raises(FormatError, match=r'"Infrared 1" 848x480: Distortion: distortion model \'Ftheta\''):
        load_realsense(bad)


def test_damaged_blocks_of_other_streams_are_ignored(tmp_path: Path) -> None:
    text = FIXTURE.read_text()
    damaged = tmp_path / "colour_damaged.txt"
    damaged.write_text(text.replace("  Fx:         \t610.463928222656\n", "  Fx:         \tbroken\n"))
    assert load_realsense(damaged).left.fx_px == pytest.approx(424.691284179688)
    with pytest.raises(FormatError, match=r'"Color" 640x480: Fx: expected numbers, got \'broken\''):
        parse_realsense(damaged)


def test_t265_fisheye_streams_are_the_pair() -> None:
    """A T265 dump has no infrared streams: "Fisheye 1" / "Fisheye 2" (Kannala Brandt4 -> equidistant, k1..k4)
    with realsense2_camera's fisheye frames; baseline |(-0.0640615, 0.000225, -0.000296)| = 0.0640626 m."""
    from s2r.formats.detect import load_any

    p = load_any(Path(__file__).parent / "data" / "rs_enumerate_devices_t265_format.txt")
    assert p.image_size == (848, 800) and p.left.fx_px == 286.149505615234
    assert p.left.distortion.model == "equidistant" and len(p.left.distortion.coefficients) == 4
    assert (p.left.frame_id, p.right.frame_id) == ("camera_fisheye1_optical_frame", "camera_fisheye2_optical_frame")
    assert p.baseline_m == pytest.approx(0.0640626, abs=1e-7)
