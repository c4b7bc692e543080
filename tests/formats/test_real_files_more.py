"""More real calibration files from public projects (excerpts written as fixtures), numbers checked by hand.

Sources (repository: path); each fixture's header says what was kept:
- rpng/open_vins: config/hilti/kalibr_imucam_chain.yaml (cam0 is the RIGHT camera), config/rs435i/
  camchain-imucam-realsense435i_race4.yaml (cam0 = infra2, T_cn_cnm1), config/kaist/kalibr_imucam_chain.yaml
  (T_imu_cam printed with 5 decimals);
- jpalves/elp: config/left.yaml + right.yaml (ROS camera_info pair, rectified R, P);
- carnegierobotics/LibMultiSense: ImageCalUtility/example_intrinsics.yml + example_extrinsics.yml (MultiSense
  factory calibration: M D, R1 P1 R2 P2, no R, no T);
- UZ-SLAMLab/ORB_SLAM3: Examples/Stereo/TUM_512.yaml (early layout, Tlr, KannalaBrandt8, "key:value"),
  Examples/Stereo/KITTI00-02.yaml (Rectified, Stereo.b);
- PRiME-project/PRiMEStereoMatch: data/intrinsics.yml + extrinsics.yml (14 coefficients, T in squares).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.detect import load_any
from s2r.formats.kalibr import load_kalibr

FIX = Path(__file__).parent / "fixtures"


def test_hilti_camchain_lists_the_right_camera_first(caplog: pytest.LogCaptureFixture) -> None:
    """cam0 at IMU (0.05099, +0.04586, -0.01263), cam1 at (0.05051, -0.06263, -0.01343); camera x is IMU +y, so
    cam1 is 10.85 cm to the LEFT: |p1 - p0| = |(-0.000479, -0.108492, -0.000803)| = 0.1084961 m."""
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any(FIX / "openvins_hilti_imucam_chain.yaml")
    assert "cam1 is 10.8 cm to the LEFT of cam0: using cam1 as left and cam0 as right" in caplog.text
    assert (p.left.fx_px, p.left.cy_px, p.right.fx_px) == (352.6489794433894, 270.5806692485468, 351.31400364193297)
    assert p.left.distortion.model == "equidistant" and p.left.distortion.coefficients[0] == -0.039086652082708805
    assert p.baseline_m == pytest.approx(0.1084961, abs=1e-7) and p.T[0] < 0
    assert "ERROR" not in caplog.text  # the pair as written is a usable left-right pair
    kept = load_kalibr(FIX / "openvins_hilti_imucam_chain.yaml", left="cam0", right="cam1")  # asked for: kept
    assert kept.T[0] > 0


def test_d435i_camchain_inverse_t_cn_cnm1() -> None:
    """cam0 is infra2: cam1 (infra1) becomes left and inv(T_cn_cnm1) gives T = -(0.05002772, 4.12e-5, 2.357e-4)
    exactly (R = I), not the 50.04 mm that the T_cam_imu pair would give."""
    p = load_any(FIX / "openvins_rs435i_race4_camchain.yaml")
    assert p.left.fx_px == 384.88335095659886 and p.right.fx_px == 384.81109268711907
    assert p.T.tolist() == pytest.approx([-0.05002772119355333, -4.1225333788413073e-05, -0.00023574091884769573],
                                         abs=1e-15)
    assert "inverse of T_cn_cnm1" in p.provenance.notes


def test_kaist_camchain_printed_with_five_decimals() -> None:
    """|p1 - p0| = |(1.73376 - 1.73944, -0.19706 - 0.27803, -0.08271 + 0.08785)| = |(-0.00568, -0.47509, 0.00514)|
    = 0.4751517 m; rotations re-orthonormalised within the printed precision."""
    p = load_any(FIX / "openvins_kaist_imucam_chain.yaml")
    assert (p.left.fx_px, p.left.fy_px, p.left.cx_px, p.left.cy_px) == (816.9037899277, 811.5680382849,
                                                                        608.5072628169, 263.4759976444)
    assert p.image_size == (1280, 560)
    assert p.baseline_m == pytest.approx(0.4751517, abs=1e-7)


def test_elp_camera_info_pair() -> None:
    """B = -P_right[0, 3] / P_right[0, 0] = 46.23921952191687 / 774.3112771918526 = 0.05971636 m."""
    p = load_any([FIX / "elp_ros" / "left.yaml", FIX / "elp_ros" / "right.yaml"])
    assert (p.left.fx_px, p.left.cx_px, p.right.fy_px) == (836.3811461119294, 692.0102704877412, 830.3524345250231)
    assert p.baseline_m == pytest.approx(46.23921952191687 / 774.3112771918526, abs=1e-9)
    assert p.left.distortion.coefficients[0] == -0.3837052906105479


def test_multisense_factory_calibration_p_tx_is_in_metres() -> None:
    """A real MultiSense file: B = 41.660152435302734 / 594.46551513671875 = 0.0700799 m, the MultiSense S7's
    70 mm baseline, so P2's Tx is -fx' B with B in metres. fy = 2 fx (the calibration's 2:1 pixel aspect) is kept,
    and 8 coefficients with k4..k6 = 0 are plumb_bob."""
    p = load_any([FIX / "multisense_factory" / "intrinsics.yml", FIX / "multisense_factory" / "extrinsics.yml"],
                 image_size=(1024, 1088))
    assert (p.left.fx_px, p.left.fy_px) == (602.91571044921875, 1205.65625)
    assert p.baseline_m == pytest.approx(41.660152435302734 / 594.46551513671875, abs=1e-8)  # R1, R2 float32
    assert p.left.distortion.model == "plumb_bob"
    assert p.left.distortion.coefficients[4] == pytest.approx(-1.0523323900997639e-02, abs=1e-18)


def test_orbslam3_early_layout_matches_the_kalibr_camchain() -> None:
    """TUM VI through two conventions: ORB-SLAM3's Tlr (right camera in the left frame, t = 0.10106 m) and the
    OpenVINS Kalibr chain's T_cam_imu pair give the same 101.09 mm; Camera.bf / fx = 19.3079 / 190.978 = 0.10110."""
    p = load_any(FIX / "orbslam3_tum512_old_layout.yaml", image_size=(512, 512))
    assert p.left.distortion.model == "equidistant" and p.right.fx_px == 190.44236969414825
    t = np.array([0.101063427414194, 0.001946204678584, 0.001015350132563])
    assert p.baseline_m == pytest.approx(float(np.linalg.norm(t)), abs=1e-6)  # float32 (dt: f) as OpenCV reads it
    assert p.baseline_m == pytest.approx(19.3079 / 190.97847715128717, abs=1e-4)


def test_orbslam3_file_without_image_size_asks_for_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "p.yaml"
    assert main(["profile", "convert", str(FIX / "orbslam3_tum512_old_layout.yaml"), "--to", "s2r", "-o",
                 str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Camera.width" in err and "--image-size" in err


def test_orbslam3_kitti_rectified() -> None:
    p = load_any(FIX / "orbslam3_kitti00_rectified.yaml")
    assert (p.left.fx_px, p.left.cx_px, p.image_size) == (718.856, 607.1928, (1241, 376))
    assert p.T.tolist() == [-0.53716, 0.0, 0.0] and p.left.distortion.is_zero


def test_opencv_rational_model_in_squares(caplog: pytest.LogCaptureFixture) -> None:
    """14 coefficients, only k1 k2 k6 set: the rational model. T = 5.0642 squares: implausible as metres (warned);
    with --units-m 0.0254 (a one-inch square) B = 0.0254 * |T| = 0.128643 m."""
    files = [FIX / "prime_opencv" / "intrinsics.yml", FIX / "prime_opencv" / "extrinsics.yml"]
    with caplog.at_level("WARNING", logger="s2r"):
        p = load_any(files, image_size=(1344, 752))
    assert "implausible" in caplog.text
    assert p.left.distortion.model == "rational_polynomial"
    assert p.left.distortion.coefficients[7] == -4.3109708144653959e-02
    scaled = load_any(files, image_size=(1344, 752), t_scale_m=0.0254)
    t = np.array([-5.0642389222739590, 2.5098869010049409e-02, -5.6501418395606122e-02])
    assert scaled.baseline_m == pytest.approx(0.0254 * float(np.linalg.norm(t)), abs=1e-12)


def test_camera_info_written_by_opencv_filestorage(tmp_path: Path) -> None:
    """The camera_calibration layout saved through cv::FileStorage (``%YAML:1.0``, ``!!opencv-matrix`` camera_matrix
    and distortion, plain rectification/projection maps), as a public narrow_stereo/left.yaml has it (left values
    as published; the right file written the same way with P Tx = -14.3895): B = 14.3895 / 239.825516 = 0.0600 m."""
    head = ("%YAML:1.0\nimage_width: 640\nimage_height: 480\ncamera_name: narrow_stereo/{side}\n"
            "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
            "  data: [369.40269, 0, 310.549287, 0, 371.158263, 230.099198, 0, 0, 1]\ndistortion_model: plumb_bob\n"
            "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 5\n  dt: d\n"
            "  data: [-0.331914, 0.068294, -0.00294, 0.004949, 0]\n"
            "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
            "projection_matrix:\n  rows: 3\n  cols: 4\n"
            "  data: [239.825516, 0, 320.12496, {tx}, 0, 302.331085, 220.692742, 0, 0, 0, 1, 0]\n")
    left, right = tmp_path / "left.yaml", tmp_path / "right.yaml"
    left.write_text(head.format(side="left", tx=0))
    right.write_text(head.format(side="right", tx=-14.3895))
    p = load_any([left, right])
    assert (p.left.fx_px, p.left.cy_px, p.image_size) == (369.40269, 230.099198, (640, 480))
    assert p.left.distortion.coefficients == (-0.331914, 0.068294, -0.00294, 0.004949, 0.0)
    assert p.baseline_m == pytest.approx(14.3895 / 239.825516, abs=1e-12)


def test_camera_info_with_a_flat_distortion_list(tmp_path: Path) -> None:
    """Some drivers' files give distortion_coefficients as a plain list (values from a public 1600x1200 file)."""
    text = ("image_width: 1600\nimage_height: 1200\ndistortion_model: plumb_bob\n"
            "distortion_coefficients: [-0.173831269260396, 0.10747272137157605, 0.004231076633773206, "
            "-0.0026692219494915187, 0.0]\n"
            "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [1158.625855755729, 0.0, 765.5609812846063,\n"
            "        0.0, 1156.0604864187183, 588.6683184401453,\n        0.0, 0.0, 1.0]\n"
            "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
            "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [1158.625855755729, 0.0, 765.5609812846063, {tx}, "
            "0.0, 1156.0604864187183, 588.6683184401453, 0.0, 0.0, 0.0, 1.0, 0.0]\n")
    left, right = tmp_path / "left.yaml", tmp_path / "right.yaml"
    left.write_text(text.format(tx=0.0))
    right.write_text(text.format(tx=-115.8625855755729))
    p = load_any([left, right])
    assert p.left.distortion.coefficients[0] == -0.173831269260396
    assert p.baseline_m == pytest.approx(0.1, abs=1e-12)


def test_kimera_d455_pair() -> None:
    """|p_right - p_left| in the body frame = |(0.06917448 + 0.02647408, 0.00427303 - 0.00914898,
    0.01451117 - 0.02575617)| = |(0.09564856, -0.00487595, -0.011245)| = 0.0964307 m."""
    d = FIX / "kimera_d455"
    p = load_any([d / "LeftCameraParams.yaml", d / "RightCameraParams.yaml"])
    assert (p.left.fx_px, p.left.cx_px, p.right.fy_px) == (377.229220831, 326.351864976, 384.44298975213155)
    assert p.left.distortion.coefficients == (-0.00439906, -0.00467669, 0.00017386, 0.00324217, 0.0)
    assert p.baseline_m == pytest.approx(0.0964307, abs=1e-7)


@pytest.mark.parametrize("resolution, fx, size", [(None, 534.25, (1280, 720)), ((2208, 1242), 1068.5, (2208, 1242))])
def test_zed_conf_with_2k_and_hd(resolution: tuple[int, int] | None, fx: float, size: tuple[int, int]) -> None:
    """Baseline = |(120.14, 0.0942712, -0.234404)| mm = 120.14027 mm at every resolution."""
    p = load_any(FIX / "zed_SN_sample_2k_hd.conf", resolution=resolution)
    assert (p.left.fx_px, p.image_size) == (fx, size)
    assert p.baseline_m == pytest.approx(0.12014027, abs=1e-8)


def test_camchain_with_ros_plumb_bob_name_and_k3(tmp_path: Path) -> None:
    """A public multi-camera rig's camchain names the model plumb_bob with 5 coefficients (k1 k2 p1 p2 k3): both
    cameras' entries as published, with a 0.2 m T_cn_cnm1 added (the excerpt has no extrinsics)."""
    path = tmp_path / "camchain.yaml"
    path.write_text(
        "cam0:\n  camera_model: pinhole\n  intrinsics: [907.580626, 908.178933, 800.913073, 678.792363]\n"
        "  distortion_model: plumb_bob\n  distortion_coeffs: [0.033815, -0.047453, 0.000617, -0.000162, 0.000000]\n"
        "  resolution: [1600, 1300]\n"
        "cam1:\n  T_cn_cnm1:\n  - [1, 0, 0, -0.2]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n"
        "  camera_model: pinhole\n  intrinsics: [910.6291839000, 910.7125457000, 786.7107435000, 625.9050966000]\n"
        "  distortion_model: plumb_bob\n"
        "  distortion_coeffs: [0.0472140054, -0.0720803351, 0.0002088803, -0.0001783977, 0.0114996117]\n"
        "  resolution: [1600, 1300]\n")
    p = load_any(path)
    assert p.right.distortion.coefficients == (0.0472140054, -0.0720803351, 0.0002088803, -0.0001783977, 0.0114996117)
    assert p.left.fx_px == 907.580626 and p.baseline_m == 0.2
