"""``s2r profile export-gazebo``: export then import reproduces the profile (or the format's stated limit)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import dump_profile
from s2r.profile import CalibrationQuality, StereoProfile
from s2r.registry import load_profile
from s2r.sources import load_description_profile
from s2r.sources.conventions import opencv_to_gazebo_distortion
from s2r.sources.export.gazebo import export_gazebo
from tests.conftest import make_rig

SUFFIX = {"urdf": "urdf", "sdf": "sdf", "gz-sim": "sdf"}
IMPORT_CONVENTION = {"urdf": "exact", "sdf": "exact", "gz-sim": "gz-sim"}


def _round_trip(profile: StereoProfile, fmt: str, tmp_path: Path) -> tuple[StereoProfile, list[str]]:
    text, warnings = export_gazebo(profile, fmt=fmt)
    path = tmp_path / f"{profile.name}_{fmt}.{SUFFIX[fmt]}"
    path.write_text(text)
    return load_description_profile(path, convention=IMPORT_CONVENTION[fmt]), warnings


@pytest.mark.parametrize("fmt", ["urdf", "sdf", "gz-sim"])
def test_realsense_round_trip(fmt: str, tmp_path: Path) -> None:
    real = load_profile("realsense_d435_848x480")
    back, warnings = _round_trip(real, fmt, tmp_path)
    assert back.left.fx_px == pytest.approx(real.left.fx_px, rel=1e-6)
    assert back.right.fx_px == pytest.approx(real.right.fx_px, rel=1e-6)
    assert back.baseline_m == pytest.approx(real.baseline_m, rel=1e-6)
    assert np.allclose(back.T, real.T, atol=1e-9) and np.allclose(back.R, real.R, atol=1e-9)
    assert back.left.distortion.is_zero and back.image_size == (848, 480)
    # both simulators render <lens><intrinsics> (continuous pixels: OpenCV + 0.5): the off-centre principal point
    # (422.5, 235.0) comes back: 423.0, 235.5 in gz-sim's convention, 422.5, 235.0 in the exact one
    assert (back.left.cx_px, back.left.cy_px) == ((423.0, 235.5) if fmt == "gz-sim" else (422.5, 235.0))
    assert warnings == []


@pytest.mark.parametrize("name", ["gazebo_dual_camera", "xbot_u_stereo"])
def test_sim_profiles_round_trip_exactly(name: str, tmp_path: Path) -> None:
    sim = load_profile(name)
    for fmt in ("urdf", "sdf"):
        text, warnings = export_gazebo(sim, fmt=fmt)
        assert warnings == []  # a gazebo-classic profile is expressible in Gazebo classic
        path = tmp_path / f"{name}.{fmt}"
        path.write_text(text)
        back = load_description_profile(path)  # gazebo-classic, like the shipped profile
        assert back.left == sim.left.model_copy(update={"frame_id": back.left.frame_id})
        assert np.allclose(back.T, sim.T, atol=1e-12) and back.simulation == sim.simulation


def test_hfov_is_the_exact_inverse_of_fx() -> None:
    text, _ = export_gazebo(load_profile("realsense_d435_848x480"), fmt="urdf")
    hfov = float(text.split("<horizontal_fov>")[1].split("<")[0])
    assert hfov == pytest.approx(2 * math.atan(848 / (2 * 424.0)), rel=1e-12)  # 1.570796 rad: 90 deg at fx = W/2


def test_square_distorted_rig_round_trips_to_1e6(tmp_path: Path) -> None:
    rig = make_rig(name="square", width=480, height=480, distortion=(-0.12, 0.05, 0.001, -0.002, 0.01),
                   rotation_deg=(0.3, -0.5, 0.2))
    for fmt in ("urdf", "sdf", "gz-sim"):
        back, warnings = _round_trip(rig, fmt, tmp_path)
        assert back.left.fx_px == pytest.approx(rig.left.fx_px, rel=1e-6)
        assert back.baseline_m == pytest.approx(rig.baseline_m, rel=1e-6)
        assert np.allclose(back.R, rig.R, atol=1e-9)
        assert pytest.approx(rig.left.D, rel=1e-6, abs=1e-12) == back.left.D
        assert not any("converted" in w for w in warnings)  # exact on a square image


def _displacement(coeffs: np.ndarray, w: int, h: int, f: float) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(0, w - 1, 25), np.linspace(0, h - 1, 25))
    x, y = (u.ravel() - (w - 1) / 2) / f, (v.ravel() - (h - 1) / 2) / f
    k1, k2, p1, p2, k3 = coeffs
    r2 = x * x + y * y
    radial = k1 * r2 + k2 * r2**2 + k3 * r2**3
    return f * np.column_stack([x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                                y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y])


def test_non_square_distorted_rig_round_trips_within_the_stated_limit(tmp_path: Path,
                                                                       distorted_rig: StereoProfile) -> None:
    """640x480: Gazebo's image-normalised model is not OpenCV's; the warning states the pixel limit."""
    back, warnings = _round_trip(distorted_rig, "sdf", tmp_path)
    assert back.left.fx_px == pytest.approx(distorted_rig.left.fx_px, rel=1e-6)
    assert back.baseline_m == pytest.approx(distorted_rig.baseline_m, rel=1e-6)
    left = distorted_rig.in_opencv_pixels().left
    fit = opencv_to_gazebo_distortion(tuple(left.D), width=640, height=480, fx=left.fx_px, fy=left.fy_px,
                                      principal=(left.cx_px, left.cy_px))
    assert any(f"{fit.max_px:.3f} px worst" in w for w in warnings)
    f = distorted_rig.left.fx_px
    moved = np.hypot(*(_displacement(back.left.D, 640, 480, f) - _displacement(distorted_rig.left.D, 640, 480, f)).T)
    assert moved.max() <= 2 * fit.max_px  # export fit + import fit, each within the stated worst error
    assert not any("principal point" in w for w in warnings)  # <lens><intrinsics> carries it


def test_fx_not_fy_and_skew_warnings_state_the_error(rig: StereoProfile) -> None:
    left = rig.left.model_copy(update={"fy_px": rig.left.fx_px * 1.01})
    profile = rig.model_copy(update={"left": left, "right": left})
    _, warnings = export_gazebo(profile, fmt="urdf")
    # the image renders fy (<lens><intrinsics>); gazebo_ros' camera_info has one focal length
    assert any("fx 554.383 != fy 559.927" in w and "camera_info publishes fx for both" in w for w in warnings)
    _, gz_warnings = export_gazebo(profile, fmt="gz-sim")
    assert not any("fy" in w for w in gz_warnings)


def test_noise_only_from_a_sensor_noise_figure(rig: StereoProfile, tmp_path: Path) -> None:
    """A calibration RMS is corner localisation, not sensor noise: no <noise> from it; --noise or the profile's
    simulation.noise_stddev is written as is."""
    cal = CalibrationQuality(pattern=(9, 6), square_m=0.025, views_used=20, rms_stereo_px=0.5)
    profile = rig.model_copy(update={"provenance": rig.provenance.model_copy(update={"calibration": cal}),
                                     "simulation": None})
    text, warnings = export_gazebo(profile, fmt="sdf")
    assert "<noise>" not in text and not any("noise" in w for w in warnings)
    text, _ = export_gazebo(profile, fmt="gz-sim", noise=0.007)
    assert [float(t.split("<")[0]) for t in text.split("<stddev>")[1:]] == [0.007, 0.007]
    src = dump_profile(profile, tmp_path / "p.yaml")
    assert main(["profile", "export-gazebo", str(src), "--noise", "2", "-o", str(tmp_path / "x.sdf")]) == 2


def test_urdf_snippet_defines_its_optical_frames_and_mount(tmp_path: Path) -> None:
    """The plugins' frameName links exist, 90 deg turned (rpy -pi/2 0 -pi/2), and --parent-link mounts the rig;
    a RealSense's infrared imagers are mono L8 on realsense2_camera's topics."""
    out = tmp_path / "rs.urdf"
    assert main(["profile", "export-gazebo", "realsense_d435_848x480", "--format", "urdf", "--parent-link",
                 "base_link", "-o", str(out)]) == 0
    import xml.etree.ElementTree as ET

    robot = ET.parse(out).getroot()
    links = {link.get("name") for link in robot.findall("link")}
    frames = [p.findtext("frameName") for p in robot.iter("plugin")]
    assert frames == ["camera_infra1_optical_frame", "camera_infra2_optical_frame"] and set(frames) <= links
    joints = {j.get("name"): j for j in robot.findall("joint")}
    optical = joints["camera_infra1_optical_frame_joint"].find("origin")
    assert optical is not None and [float(v) for v in optical.get("rpy", "").split()] == [-math.pi / 2, 0, -math.pi / 2]
    mount = joints["realsense_d435_848x480_mount_joint"]
    assert mount.find("parent").get("link") == "base_link"  # type: ignore[union-attr]
    assert [f.text for f in robot.iter("format")] == ["L8", "L8"]
    assert [p.findtext("cameraName") for p in robot.iter("plugin")] == ["camera/infra1", "camera/infra2"]
    assert [p.findtext("imageTopicName") for p in robot.iter("plugin")] == ["image_rect_raw"] * 2
    gz, _ = export_gazebo(load_profile("realsense_d435_848x480"), fmt="gz-sim")
    assert "<topic>camera/infra1/image_rect_raw</topic>" in gz and "<format>L8</format>" in gz
    # without a parent link the snippet stands alone and reads back
    alone = tmp_path / "alone.urdf"
    assert main(["profile", "export-gazebo", "realsense_d435_848x480", "--format", "urdf", "-o", str(alone)]) == 0
    assert load_description_profile(alone).left.frame_id == "camera_infra1_optical_frame"


def test_cli_export_refuses_to_overwrite(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "rs.urdf"
    assert main(["profile", "export-gazebo", "realsense_d435_848x480", "--format", "urdf", "-o", str(out)]) == 0
    first = out.read_text()
    captured = capsys.readouterr()
    assert "(urdf, 0 warning(s))" in captured.out  # <lens><intrinsics> carries the off-centre principal point
    assert main(["profile", "export-gazebo", "realsense_d435_848x480", "--format", "sdf", "-o", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err and out.read_text() == first
    assert main(["profile", "export-gazebo", "realsense_d435_848x480", "--format", "sdf", "-o", str(out),
                 "--force"]) == 0
    assert "<sdf" in out.read_text()
    assert main(["profile", "export-gazebo", "no_such_profile", "-o", str(tmp_path / "x.sdf")]) == 2


def test_cli_from_urdf_then_export_then_import(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               distorted_rig: StereoProfile) -> None:
    src = dump_profile(distorted_rig, tmp_path / "rig.yaml")
    xml = tmp_path / "rig.sdf"
    assert main(["profile", "export-gazebo", str(src), "--format", "gz-sim", "-o", str(xml)]) == 0
    out = tmp_path / "back.yaml"
    assert main(["profile", "from-urdf", str(xml), "-o", str(out), "--convention", "gz-sim"]) == 0
    assert "wrote" in capsys.readouterr().out
    back = load_profile(out)
    assert back.left.fx_px == pytest.approx(distorted_rig.left.fx_px, rel=1e-6)
    assert back.left.cx_px == pytest.approx(distorted_rig.left.cx_px + 0.5, abs=1e-9)
    assert main(["profile", "from-urdf", str(xml), "-o", str(out)]) == 2  # exists, no --force


def test_gz_sim_writes_gz_rendering_units_and_classic_turns_the_crop_off(distorted_rig: StereoProfile,
                                                                        tmp_path: Path,
                                                                        caplog: pytest.LogCaptureFixture) -> None:
    """gz-sim's <distortion> is in gz-rendering's scaled units (classic k / s^2, s = 2 tan(fov / 2)); classic's
    gazebo_ros plugins get borderCrop false. A classic file that keeps the crop is read with a warning saying how
    much the crop magnifies the image."""
    from s2r.sources.conventions import gz_sim_distortion_scale, hfov_from_focal

    classic, _ = export_gazebo(distorted_rig, fmt="sdf")
    gz, warnings = export_gazebo(distorted_rig, fmt="gz-sim")
    left = distorted_rig.left
    s = gz_sim_distortion_scale(640, 480, hfov_from_focal(640, left.fx_px))
    k1_classic, k1_gz = (float(t.split("<k1>")[1].split("<")[0]) for t in (classic, gz))
    assert k1_gz == pytest.approx(k1_classic / s**2, rel=1e-12)
    assert "<borderCrop>false</borderCrop>" in classic and any("--render-engine ogre" in w for w in warnings)
    cropped = tmp_path / "cropped.sdf"
    cropped.write_text(classic.replace("<borderCrop>false</borderCrop>", ""))
    load_description_profile(cropped)
    assert "magnifying it" in caplog.text and "<borderCrop>false</borderCrop>" in caplog.text


def test_classic_legacy_mode_false_reads_in_scaled_units(distorted_rig: StereoProfile, tmp_path: Path) -> None:
    """<ignition:legacy_mode>false (gazebo-classic PR 3009) multiplies texture offsets by W / f first, so the same
    lens is written with k1 / s^2, k2 / s^4, p / s (s = 2 tan(hfov / 2) = W / f): both files read back alike."""
    import re

    from s2r.sources.conventions import classic_distortion_scale, hfov_from_focal

    legacy, _ = export_gazebo(distorted_rig, fmt="sdf")
    a = tmp_path / "legacy.sdf"
    a.write_text(legacy)

    def rescaled(match: re.Match[str]) -> str:
        cam_fx = distorted_rig.left.fx_px if match.start() < legacy.index('name="right"') else distorted_rig.right.fx_px
        s = classic_distortion_scale(640, 480, hfov_from_focal(640, cam_fx))
        powers = {"k1": 2, "k2": 4, "k3": 6, "p1": 1, "p2": 1}
        return f"<{match[1]}>{float(match[2]) / s ** powers[match[1]]!r}</{match[1]}>"

    scaled = re.sub(r"<(k1|k2|k3|p1|p2)>([^<]+)</\1>", rescaled, legacy)
    b = tmp_path / "new_mode.sdf"
    b.write_text(scaled.replace("<center>", "<ignition:legacy_mode>false</ignition:legacy_mode><center>"))
    assert pytest.approx(load_description_profile(a).left.D, rel=1e-9) == load_description_profile(b).left.D
    assert pytest.approx(load_description_profile(a).right.D, rel=1e-9) == load_description_profile(b).right.D


def test_fx_not_fy_below_a_tenth_of_a_pixel_is_not_warned(rig: StereoProfile) -> None:
    """0.006 px between fx and fy (a calibration's noise) moves nothing visibly: no warning; 0.5 px does."""
    for delta, warned in ((0.006, False), (0.5, True)):
        left = rig.left.model_copy(update={"fy_px": rig.left.fx_px + delta})
        _, warnings = export_gazebo(rig.model_copy(update={"left": left, "right": left}), fmt="urdf")
        assert any("!= fy" in w for w in warnings) is warned
