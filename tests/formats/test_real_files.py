"""Real calibration files from public projects (small excerpts written as fixtures), with hand-checked numbers.

Sources (repository: path), each excerpt's header says what was kept:
- rpng/open_vins: config/euroc_mav/kalibr_imucam_chain.yaml (``%YAML:1.0``, T_imu_cam only);
- UZ-SLAMLab/ORB_SLAM3: Examples/Stereo/EuRoC.yaml (old layout, LEFT/RIGHT K D R P, Camera.bf);
- HKUST-Aerial-Robotics/VINS-Fusion: config/euroc/euroc_stereo_imu_config.yaml + cam0/cam1_pinhole.yaml;
- MIT-SPARK/Kimera-VIO: params/Euroc/{Left,Right}CameraParams.yaml layout with EuRoC's T_BS;
- a ZED SN*.conf (stereolabs zed-opencv-native layout) with HD values published in a public script.

The EuRoC rig appears in four of them through three different conventions; all must give one baseline.
By hand: bf / fx = 47.90639384423901 / 435.2046959714599 = 0.1100778 m (ORB-SLAM's own rectified baseline),
and |p_cam1 - p_cam0| in the IMU frame = |(0.0017966, 0.1100457, -0.0019486)| = 0.1100778 m.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.detect import detect_format, load_any
from s2r.formats.kalibr import load_kalibr

FIX = Path(__file__).parent / "fixtures"
EUROC_BASELINE_M = 47.90639384423901 / 435.2046959714599  # 0.11007784 m


def test_euroc_baseline_by_hand() -> None:
    p0 = np.array([-0.0216401454975, -0.064676986768, 0.00981073058949])  # cam0 in the IMU frame (T_imu_cam)
    p1 = np.array([-0.0198435579556, 0.0453689425024, 0.00786212447038])
    assert float(np.linalg.norm(p1 - p0)) == pytest.approx(EUROC_BASELINE_M, abs=1e-7)


def test_openvins_camchain_with_yaml_directive_and_only_t_imu_cam() -> None:
    path = FIX / "openvins_euroc_imucam_chain.yaml"
    assert detect_format(path) == "kalibr"
    p = load_any(path)
    assert (p.left.fx_px, p.left.fy_px, p.left.cx_px, p.left.cy_px) == (458.654, 457.296, 367.215, 248.375)
    assert (p.right.fx_px, p.right.cx_px) == (457.587, 379.999)
    assert p.left.distortion.coefficients == (-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0)
    assert p.baseline_m == pytest.approx(EUROC_BASELINE_M, abs=1e-6)
    assert p.T[0] == pytest.approx(-0.1100738, abs=1e-6)  # right camera to the right: T_x < 0
    assert "T_cam_imu" in p.provenance.notes


def test_kalibr_chain_of_three_cameras_chooses_and_says(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """cam2 0.05 m right of cam1 (T_cn_cnm1): cam0 -> cam2 composes the chain to 0.1 + 0.05 = 0.15 m."""
    def cam(tx: float | None) -> str:
        extr = "" if tx is None else (f"  T_cn_cnm1:\n  - [1, 0, 0, {tx}]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n"
                                      "  - [0, 0, 0, 1]\n")
        return (f"{extr}  camera_model: pinhole\n  intrinsics: [400.0, 400.0, 320.0, 240.0]\n"
                "  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n")
    path = tmp_path / "camchain.yaml"
    path.write_text("cam0:\n" + cam(None) + "cam1:\n" + cam(-0.1) + "cam2:\n" + cam(-0.05))
    with caplog.at_level("WARNING", logger="s2r"):
        assert load_kalibr(path).baseline_m == pytest.approx(0.1)
    assert "3 cameras (cam0, cam1, cam2); using cam0 as left and cam1 as right" in caplog.text
    assert load_kalibr(path, left="cam0", right="cam2").T.tolist() == pytest.approx([-0.15, 0, 0])
    out = tmp_path / "p.yaml"
    assert main(["profile", "convert", str(path), "--left", "cam1", "--right", "cam2", "--to", "s2r", "-o",
                 str(out)]) == 0
    assert main(["profile", "convert", str(path), "--left", "cam0", "--right", "cam7", "--to", "s2r", "-o",
                 str(tmp_path / "q.yaml")]) == 2


def test_orbslam3_euroc_settings_recover_the_raw_pair() -> None:
    p = load_any(FIX / "orbslam3_euroc_rectified.yaml")
    assert (p.left.fx_px, p.left.fy_px, p.left.cx_px, p.left.cy_px) == (458.654, 457.296, 367.215, 248.375)
    assert (p.right.fx_px, p.right.fy_px, p.right.cx_px, p.right.cy_px) == (457.587, 456.134, 379.999, 255.238)
    assert p.baseline_m == pytest.approx(EUROC_BASELINE_M, abs=1e-6)


def test_orbslam3_new_layout_t_c1_c2_direction(tmp_path: Path) -> None:
    """Stereo.T_c1_c2 is camera 2's pose in camera 1: x = +0.12 (to the right) -> OpenCV T = (-0.12, 0, 0)."""
    path = tmp_path / "orb3.yaml"
    path.write_text('%YAML:1.0\nFile.version: "1.0"\nCamera.type: "PinHole"\n'
                    + "".join(f"Camera{n}.{k}: {v}\n" for n in (1, 2) for k, v in
                              (("fx", 500.5), ("fy", 500.25), ("cx", 320.5), ("cy", 240.5), ("k1", -0.1),
                               ("k2", 0.01), ("p1", 0.0), ("p2", 0.0)))
                    + "Camera.width: 640\nCamera.height: 480\nStereo.ThDepth: 40.0\nStereo.T_c1_c2: !!opencv-matrix\n"
                    "  rows: 4\n  cols: 4\n  dt: f\n  data: [1, 0, 0, 0.12, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n")
    p = load_any(path)
    assert p.T.tolist() == pytest.approx([-0.12, 0.0, 0.0]) and p.left.fy_px == 500.25
    assert p.left.distortion.coefficients[:2] == (-0.1, 0.01)


def test_vins_fusion_config_reads_its_camera_files() -> None:
    p = load_any(FIX / "vins_euroc" / "euroc_stereo_imu_config.yaml")
    assert p.left.fx_px == pytest.approx(461.70381623421628, abs=1e-9)
    assert p.right.cy_px == pytest.approx(253.97975828570469, abs=1e-9)
    assert p.left.distortion.coefficients[:4] == pytest.approx((-0.29250563288482467, 0.083305380138632271,
                                                                2.4650824570721693e-05, -1.1770093773613896e-04))
    assert p.baseline_m == pytest.approx(EUROC_BASELINE_M, abs=1e-6)


def test_kimera_pair_and_single_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    left, right = FIX / "kimera_euroc" / "LeftCameraParams.yaml", FIX / "kimera_euroc" / "RightCameraParams.yaml"
    p = load_any([left, right])
    assert (p.left.fx_px, p.right.cx_px) == (458.654, 379.999)
    assert p.baseline_m == pytest.approx(EUROC_BASELINE_M, abs=1e-6)
    assert main(["profile", "convert", str(left), "--to", "s2r", "-o", str(tmp_path / "k.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert "Kimera-VIO camera params holds one camera" in err and len(err.splitlines()) == 1


def test_zed_conf_baseline_in_millimetres() -> None:
    """|T| = sqrt(119.905^2 + 0.0458908^2 + 0.467919^2) mm = 119.9059 mm; R = Rodrigues(RX, CV, RZ)."""
    path = FIX / "zed_SN_excerpt.conf"
    assert detect_format(path) == "zed"
    p = load_any(path)
    assert p.image_size == (1280, 720)
    assert (p.left.fx_px, p.left.fy_px, p.left.cx_px, p.left.cy_px) == (699.41, 699.365, 652.8, 358.133)
    assert p.baseline_m == pytest.approx(math.sqrt(119.905**2 + 0.0458908**2 + 0.467919**2) / 1000, abs=1e-9)
    assert p.T[0] == pytest.approx(-0.119905)
    angle = math.degrees(math.sqrt(0.00239722**2 + 0.00697667**2 + 0.0021326**2))
    assert p.rotation_angle_rad == pytest.approx(math.radians(angle), abs=1e-9)
    with pytest.raises(Exception, match="resolution 1920x1080 not in the file"):
        load_any(path, resolution=(1920, 1080))


def test_opencv_k1_d1_k2_d2_names(tmp_path: Path) -> None:
    path = tmp_path / "stereo.yml"
    mat = "!!opencv-matrix\n   rows: {r}\n   cols: {c}\n   dt: d\n   data: [{d}]\n"
    path.write_text("%YAML:1.0\nimage_width: 640\nimage_height: 480\n"
                    f"K1: {mat.format(r=3, c=3, d='536.07, 0, 342.37, 0, 536.01, 235.53, 0, 0, 1')}"
                    f"D1: {mat.format(r=1, c=5, d='-0.265, -0.047, 0.0018, -0.0003, 0.25')}"
                    f"K2: {mat.format(r=3, c=3, d='542.34, 0, 326.41, 0, 541.94, 249.87, 0, 0, 1')}"
                    f"D2: {mat.format(r=1, c=5, d='-0.24, -0.11, 0.0007, 0.0001, 0.3')}"
                    f"R: {mat.format(r=3, c=3, d='1, 0, 0, 0, 1, 0, 0, 0, 1')}"
                    f"T: {mat.format(r=3, c=1, d='-0.0836, 0.001, 0.0013')}")
    p = load_any(path)
    assert (p.left.fx_px, p.right.fx_px) == (536.07, 542.34)
    assert p.baseline_m == pytest.approx(math.sqrt(0.0836**2 + 0.001**2 + 0.0013**2), abs=1e-12)


def test_multisense_r1_p1_r2_p2_only(tmp_path: Path) -> None:
    """Intrinsics M1 D1 M2 D2 plus extrinsics R1 P1 R2 P2 (no R, T): R = R2^T R1, T from P2's Tx = -fx' B."""
    mat = "!!opencv-matrix\n   rows: {r}\n   cols: {c}\n   dt: d\n   data: [{d}]\n"
    intr, extr = tmp_path / "intrinsics.yml", tmp_path / "extrinsics.yml"
    intr.write_text("%YAML:1.0\nimage_width: 1024\nimage_height: 544\n"
                    f"M1: {mat.format(r=3, c=3, d='590.1, 0, 512.3, 0, 590.2, 272.1, 0, 0, 1')}"
                    f"D1: {mat.format(r=1, c=8, d='-0.3, 0.1, 0, 0, 0, 0, 0, 0')}"
                    f"M2: {mat.format(r=3, c=3, d='589.9, 0, 511.7, 0, 590.0, 271.9, 0, 0, 1')}"
                    f"D2: {mat.format(r=1, c=8, d='-0.29, 0.1, 0, 0, 0, 0, 0, 0')}")
    extr.write_text("%YAML:1.0\n"
                    f"R1: {mat.format(r=3, c=3, d='1, 0, 0, 0, 1, 0, 0, 0, 1')}"
                    f"P1: {mat.format(r=3, c=4, d='580, 0, 512, 0, 0, 580, 272, 0, 0, 0, 1, 0')}"
                    f"R2: {mat.format(r=3, c=3, d='1, 0, 0, 0, 1, 0, 0, 0, 1')}"
                    f"P2: {mat.format(r=3, c=4, d='580, 0, 512, -121.8, 0, 580, 272, 0, 0, 0, 1, 0')}")
    p = load_any([intr, extr])
    assert p.baseline_m == pytest.approx(121.8 / 580, abs=1e-12)  # 0.21 m, a MultiSense S21's baseline
    assert p.left.distortion.model == "plumb_bob"  # 8 coefficients with k4 = k5 = k6 = 0: the 5-term model
    assert p.left.distortion.coefficients == (-0.3, 0.1, 0.0, 0.0, 0.0)


def test_ros_pair_with_six_decimal_and_zero_rotations(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """ORB-SLAM3's EuRoC LEFT/RIGHT R printed with 6 decimals as a driver would: re-orthonormalised, same pair."""
    r1 = [0.999966, -0.001423, 0.00808, 0.001366, 0.999974, 0.007056, -0.008089, -0.007044, 0.999942]
    r2 = [0.999963, -0.003626, 0.007755, 0.00368, 0.999968, -0.007036, -0.00773, 0.007064, 0.999945]

    def info(name: str, K: str, D: str, R: list[float], tx: float) -> str:
        return (f"image_width: 752\nimage_height: 480\ncamera_name: {name}\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                f"  data: [{K}]\ndistortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n"
                f"  data: [{D}]\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: {R}\n"
                f"projection_matrix:\n  rows: 3\n  cols: 4\n  data: [435.204696, 0, 367.451721, {tx}, 0, "
                "435.204696, 252.200851, 0, 0, 0, 1, 0]\n")
    left, right = tmp_path / "left.yaml", tmp_path / "right.yaml"
    left.write_text(info("euroc/left", "458.654, 0, 367.215, 0, 457.296, 248.375, 0, 0, 1",
                         "-0.283408, 0.073959, 0.000194, 0.000018, 0", r1, 0.0))
    right.write_text(info("euroc/right", "457.587, 0, 379.999, 0, 456.134, 255.238, 0, 0, 1",
                          "-0.283684, 0.074513, -0.000105, -0.000036, 0", r2, -47.906394))
    with caplog.at_level("INFO", logger="s2r"):
        p = load_any([left, right])
    assert "re-orthonormalised" in caplog.text
    assert p.baseline_m == pytest.approx(47.906394 / 435.204696, abs=1e-6)
    assert p.left.fx_px == 458.654
    zero = [0.0] * 9
    left.write_text(info("l", "400, 0, 376, 0, 400, 240, 0, 0, 1", "0, 0, 0, 0, 0", zero, 0.0))
    right.write_text(info("r", "400, 0, 376, 0, 400, 240, 0, 0, 1", "0, 0, 0, 0, 0", zero, -43.52047))
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any([left, right])
    assert "all zeros; read as the identity" in caplog.text
    assert p.baseline_m == pytest.approx(0.1, abs=1e-6) and np.allclose(p.R, np.eye(3))


def test_realsense_underscore_stream_names(tmp_path: Path) -> None:
    text = (Path(__file__).parent / "data" / "rs_enumerate_devices_d435.txt").read_text()
    path = tmp_path / "d435_new.txt"
    path.write_text(text.replace("Infrared 1", "Infrared_1").replace("Infrared 2", "Infrared_2"))
    p, ref = load_any(path), load_any(Path(__file__).parent / "data" / "rs_enumerate_devices_d435.txt")
    assert p.left.fx_px == ref.left.fx_px and p.baseline_m == ref.baseline_m


def test_implausible_baseline_in_squares_warns(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """OpenCV's sample T in squares (|T| = 3.34 'm' at 640 px, fx 536) reads as metres but is implausible."""
    mat = "!!opencv-matrix\n   rows: {r}\n   cols: {c}\n   dt: d\n   data: [{d}]\n"
    path = tmp_path / "squares.yml"
    path.write_text("%YAML:1.0\nimage_width: 640\nimage_height: 480\n"
                    f"M1: {mat.format(r=3, c=3, d='536.07, 0, 342.37, 0, 536.01, 235.53, 0, 0, 1')}"
                    f"D1: {mat.format(r=1, c=5, d='0, 0, 0, 0, 0')}"
                    f"M2: {mat.format(r=3, c=3, d='542.34, 0, 326.41, 0, 541.94, 249.87, 0, 0, 1')}"
                    f"D2: {mat.format(r=1, c=5, d='0, 0, 0, 0, 0')}"
                    f"R: {mat.format(r=3, c=3, d='1, 0, 0, 0, 1, 0, 0, 0, 1')}"
                    f"T: {mat.format(r=3, c=1, d='-3.344, 0.042, 0.053')}")
    with caplog.at_level("WARNING", logger="s2r"):
        load_any(path)
    assert "implausible" in caplog.text and "--units-m" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="s2r"):
        assert load_any(path, t_scale_m=0.025).baseline_m == pytest.approx(0.0836, abs=1e-4)
    assert "implausible" not in caplog.text


def test_orbslam3_rectified_realsense_settings(tmp_path: Path) -> None:
    """UZ-SLAMLab/ORB_SLAM3 Examples/Stereo/RealSense_D435i.yaml (excerpt): Camera.type Rectified, Stereo.b."""
    path = tmp_path / "RealSense_D435i.yaml"
    path.write_text('%YAML:1.0\nFile.version: "1.0"\nCamera.type: "Rectified"\nCamera1.fx: 382.613\n'
                    "Camera1.fy: 382.613\nCamera1.cx: 320.183\nCamera1.cy: 236.455\nStereo.b: 0.0499585\n"
                    "Camera.width: 640\nCamera.height: 480\nCamera.fps: 30\nStereo.ThDepth: 40.0\n")
    p = load_any(path)
    assert (p.left.fx_px, p.left.cx_px, p.right.cy_px) == (382.613, 320.183, 236.455)
    assert p.T.tolist() == [-0.0499585, 0.0, 0.0] and p.left.distortion.is_zero


@pytest.mark.parametrize(("text", "why"), [
    ('%YAML:1.0\nFile.version: "1.0"\nCamera.type: "PinHole"\nCamera1.fx: 500.0\nCamera1.fy: 500.0\n'
     "Camera1.cx: 320.0\nCamera1.cy: 240.0\nCamera.width: 640\nCamera.height: 480\n", "holds one camera"),
    ("%YAML:1.0\nimu: 1\nnum_of_cam: 1\ncam0_calib: \"cam0_pinhole.yaml\"\nimage_width: 752\nimage_height: 480\n",
     "monocular VINS-Fusion"),
    ("cam0:\n  camera_model: omni\n  intrinsics: [0.8, 500, 500, 320, 240]\n  distortion_model: radtan\n"
     "  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\n", "a camchain with 1 camera(s) (cam0)"),
    ("cam0:\n  camera_model: omni\n  intrinsics: [0.8, 500, 500, 320, 240]\n  distortion_model: radtan\n"
     "  distortion_coeffs: [0, 0, 0, 0]\n  resolution: [640, 480]\ncam1:\n  camera_model: omni\n", "'omni' is not "
     "supported"),
    ("%YAML:1.0\nimage_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n"
     "  dt: d\n  data: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n", "holds one camera"),
    ("[LEFT_CAM_HD]\nfx=700\nfy=700\ncx=640\ncy=360\n[STEREO]\nBaseline=120\n", "pick a resolution"),
    ("%YAML:1.0\nverbosity: INFO\nuse_stereo: true\nmax_cameras: 2\n", "unrecognised"),
])
def test_out_of_scope_files_exit_2_with_one_line(text: str, why: str, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "in.yaml"
    path.write_text(text)
    assert main(["profile", "convert", str(path), "--to", "s2r", "-o", str(tmp_path / "out.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and why in err and str(path) in err, err
