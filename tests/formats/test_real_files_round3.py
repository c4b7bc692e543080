"""Third round of real files: six-significant-digit rotations and ORB-SLAM2 leftovers (fixtures written by hand).

- ``orbslam3_t265_excerpt.yaml``: UZ-SLAMLab/ORB_SLAM3 Examples/Stereo-Inertial/RealSense_T265.yaml, whose
  Stereo.T_c1_c2 is printed with 6 significant digits (0.999983 and 0.00445005 alike) and stored as float32:
  |R^T R - I| = 1.04e-6, refused before at 1e-6.
- ``ros_six_decimals/``: a ZED/I3DR-like camera_info pair printed with 6 decimals; each R passes 1e-6 alone,
  R2^T R1 made of them is off by 1.9e-6.
- ``orbslam2_leftover_euroc.yaml``: Camera.* edited for a 1280x720 camera (fx 859.04, bf 64.428 -> B 75 mm), the
  EuRoC LEFT/RIGHT blocks left over (752x480, fx' 435.2, B 110 mm).
- ``orbslam2_empty_placeholders.yaml``: a complete Camera.* + Camera.bf block (848x480, fx 421.5, bf 21.075 ->
  B 50 mm) with empty LEFT/RIGHT placeholders (``data: []``, ``LEFT.height:`` with no value).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.detect import load_any

FIX = Path(__file__).parent / "fixtures"



def _orthonormality(R: np.ndarray) -> float:
    return float(np.max(np.abs(R.T @ R - np.eye(3))))


def test_t265_six_significant_digits_as_float32() -> None:
    printed = np.array([[0.999983, 0.00445005, 0.00385861, 0.0636739954352379],
                        [-0.00443664, 0.999984, -0.00347621, -0.000252007856033742],
                        [-0.00387402, 0.00345903, 0.999986, -8.87895439518616e-05]], dtype=np.float32)
    R_c1_c2 = printed[:, :3].astype(np.float64)
    assert 1.0e-6 < _orthonormality(R_c1_c2) < 1.1e-6  # the figure the field report quotes
    p = load_any(FIX / "orbslam3_t265_excerpt.yaml")
    assert _orthonormality(p.R) < 1e-12  # re-orthonormalised: the nearest rotation
    assert np.max(np.abs(p.R - R_c1_c2.T)) < 2e-6  # R = R_c1_c2^T within the printed digits
    assert p.baseline_m == pytest.approx(float(np.linalg.norm(printed[:, 3].astype(np.float64))), abs=1e-9)
    assert p.left.fx_px == 284.9501953125 and p.right.cx_px == 411.864196777344
    assert p.left.distortion.model == "equidistant" and p.image_size == (848, 800)


def test_ros_pair_whose_product_of_rotations_exceeds_1e6(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = FIX / "ros_six_decimals"
    r1 = np.array([0.999914, -0.012811, -0.002626, 0.012805, 0.999915, -0.002531, 0.002658, 0.002498,
                   0.999993]).reshape(3, 3)
    r2 = np.array([0.999916, -0.007243, -0.010705, 0.00722, 0.999972, -0.002137, 0.010721, 0.002059,
                   0.99994]).reshape(3, 3)
    assert _orthonormality(r1) < 1e-6 and _orthonormality(r2) < 1e-6 and _orthonormality(r2.T @ r1) > 1.8e-6
    out = tmp_path / "zed.yaml"
    assert main(["profile", "convert", str(folder / "left.yaml"), str(folder / "right.yaml"), "--to", "s2r", "-o",
                 str(out)]) == 0
    p = load_any(out)
    assert p.baseline_m == pytest.approx(81.614815 / 680.123456, abs=1e-9)  # |t2 - t1| = |Tx| / fx'
    assert np.max(np.abs(p.R - r2.T @ r1)) < 3e-6 and _orthonormality(p.R) < 1e-12
    assert (p.left.fx_px, p.right.cx_px) == (699.412, 638.914)


def test_rotation_off_beyond_its_printed_digits_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = FIX / "ros_six_decimals"
    left = tmp_path / "left.yaml"
    left.write_text((folder / "left.yaml").read_text().replace("0.999914, -0.012811", "0.999914, -0.012911"))
    code = main(["profile", "convert", str(left), str(folder / "right.yaml"), "--to", "s2r", "-o",
                 str(tmp_path / "p.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "rectification_matrix: not a rotation: max |R^T R - I| = 9.93e-05, beyond the 2.0e-06" \
        in err and err.count("\n") == 1


def test_orbslam2_leftover_euroc_blocks_lose_to_camera_block(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any(FIX / "orbslam2_leftover_euroc.yaml")
    assert p.image_size == (1280, 720) and p.left.fx_px == 859.04 and p.right.cx_px == 637.52
    assert p.baseline_m == pytest.approx(64.428 / 859.04, abs=1e-12) and np.allclose(p.R, np.eye(3))
    assert ("the LEFT/RIGHT blocks (752x480, fx 435.205, bf 47.9064 (B 110.1 mm)) disagree with Camera.* "
            "(1280x720, fx 859.04, bf 64.428 (B 75.0 mm)); using Camera.*") in caplog.text
    assert "Camera.bf / Camera.fx" in p.provenance.notes


def test_orbslam2_empty_placeholders_use_the_camera_block(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level("INFO", logger="s2r"):
        p = load_any(FIX / "orbslam2_empty_placeholders.yaml")
    assert p.image_size == (848, 480) and (p.left.fx_px, p.left.cx_px, p.left.cy_px) == (421.5, 424.25, 239.75)
    assert p.baseline_m == pytest.approx(21.075 / 421.5, abs=1e-12)
    assert "LEFT/RIGHT blocks are empty placeholders" in caplog.text


def test_orbslam2_consistent_blocks_keep_the_raw_pair(caplog: pytest.LogCaptureFixture, tmp_path: Path) -> None:
    """Camera.* set to the EuRoC rectified values (fx' 435.2047, bf 47.9064, 752x480): LEFT/RIGHT agree and
    give the raw pair (fx 458.654), with no warning."""
    text = (FIX / "orbslam2_leftover_euroc.yaml").read_text()
    for old, new in (("Camera.fx: 859.04", "Camera.fx: 435.2046959714599"), ("Camera.width: 1280", "Camera.width: 752"),
                     ("Camera.height: 720", "Camera.height: 480"), ("Camera.bf: 64.428", "Camera.bf: 47.90639384")):
        text = text.replace(old, new)
    path = tmp_path / "euroc.yaml"
    path.write_text(text)
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any(path)
    assert p.left.fx_px == 458.654 and p.right.fx_px == 457.587 and "disagree" not in caplog.text
    assert p.baseline_m == pytest.approx(47.90639384423901 / 435.2046959714599, abs=1e-6)


def test_orbslam2_half_filled_leftright_with_camera_block(caplog: pytest.LogCaptureFixture, tmp_path: Path) -> None:
    """LEFT/RIGHT with a K but no P: unusable, named; Camera.* is complete and is used."""
    head = "LEFT.K: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: "
    text = (FIX / "orbslam2_empty_placeholders.yaml").read_text().replace(
        head + "[]", head + "[421.5, 0, 424.25, 0, 421.5, 239.75, 0, 0, 1]")
    path = tmp_path / "half.yaml"
    path.write_text(text)
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any(path)
    assert p.baseline_m == pytest.approx(0.05, abs=1e-12)
    assert "the LEFT/RIGHT blocks are unusable (LEFT.width: expected a number" in caplog.text


def test_orbslam2_leftovers_without_camera_bf_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "no_bf.yaml"
    path.write_text((FIX / "orbslam2_leftover_euroc.yaml").read_text().replace("Camera.bf: 64.428\n", ""))
    assert main(["profile", "convert", str(path), "--to", "s2r", "-o", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err
    assert "Camera.bf: the LEFT/RIGHT blocks (752x480, fx 435.205" in err and "(1280x720, fx 859.04)" in err
    assert err.count("\n") == 1
