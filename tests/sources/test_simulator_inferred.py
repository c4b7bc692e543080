"""Issue 24 items 7-8: the pixel convention comes from the simulator the file loads (gz-sim systems -> gz-sim,
gazebo_ros plugins -> gazebo-classic), is said (log line, provenance) and overridable; lint's advice follows it."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from s2r.cli import main
from s2r.registry import load_profile
from s2r.sources import lint_description, load_description_profile
from tests.sources.rigs import sensor, two_camera_urdf, write

FIXTURES = Path(__file__).parent / "fixtures"
GZ_WORLD = FIXTURES / "gz_sim_sensors_world.sdf"
CLASSIC_PLUGIN = ('<plugin name="c" filename="libgazebo_ros_camera.so"><cameraName>{0}</cameraName>'
                  "<frameName>{0}_optical</frameName></plugin>")
FX = 320 / math.tan(1.047 / 2)


def _from_urdf(path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> tuple[str, Path]:
    out = tmp_path / "p.yaml"
    assert main(["profile", "from-urdf", str(path), "-o", str(out), "--force", *extra]) == 0
    captured = capsys.readouterr()
    return captured.out + captured.err, out


def test_gz_sim_world_is_read_in_gz_sim_pixels(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text, out = _from_urdf(GZ_WORLD, tmp_path, capsys)
    assert "pixel convention gz-sim, inferred from <plugin filename='gz-sim-physics-system'> line 8" in text
    profile = load_profile(out)
    assert profile.provenance.convention == "gz-sim"
    assert (profile.left.cx_px, profile.left.cy_px) == (320.0, 240.0)
    assert profile.left.fx_px == pytest.approx(FX, abs=1e-9)
    assert pytest.approx([-0.06, 0.0, 0.0], abs=1e-12) == profile.T
    assert "pixel convention gz-sim inferred from <plugin filename='gz-sim-physics-system'>" in \
        profile.provenance.notes
    text, out = _from_urdf(GZ_WORLD, tmp_path, capsys, "--convention", "gazebo-classic")  # the override
    assert "pixel convention" not in text and load_profile(out).left.cx_px == 320.5


def test_gazebo_ros_urdf_is_read_in_classic_pixels(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = two_camera_urdf(left_sensor=sensor("left_cam", plugin=CLASSIC_PLUGIN.format("left")),
                          right_sensor=sensor("right_cam", plugin=CLASSIC_PLUGIN.format("right")))
    text, out = _from_urdf(write(tmp_path, "rig.urdf", rig), tmp_path, capsys)
    assert "pixel convention gazebo-classic, inferred from <plugin filename='libgazebo_ros_camera.so'> line" in text
    assert load_profile(out).left.cx_px == 320.5


def test_no_evidence_and_both_fall_back_to_classic_and_say_so(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    text, out = _from_urdf(write(tmp_path, "plain.urdf", two_camera_urdf()), tmp_path, capsys)
    assert "pixel convention gazebo-classic, assumed: the file loads no gz-sim system and no gazebo_ros plugin" in text
    assert load_profile(out).left.cx_px == 320.5
    both = two_camera_urdf(left_sensor=sensor("left_cam", plugin=CLASSIC_PLUGIN.format("left")),
                           right_sensor=sensor("right_cam")).replace(
        "</robot>", '<gazebo><plugin filename="gz-sim-sensors-system" name="gz::sim::systems::Sensors"/></gazebo>'
                    "</robot>")
    text, out = _from_urdf(write(tmp_path, "both.urdf", both), tmp_path, capsys)
    assert "pixel convention gazebo-classic, assumed: the file loads gz-sim (<plugin filename='gz-sim-sensors-system'" \
           in text and "Gazebo classic (<plugin filename='libgazebo_ros_camera.so'>" in text


def test_library_default_infers_and_explicit_wins() -> None:
    assert load_description_profile(GZ_WORLD).left.cx_px == 320.0
    assert load_description_profile(GZ_WORLD, convention="exact").left.cx_px == 319.5


def _lens_rig(tmp_path: Path, *, plugin: bool) -> Path:
    lens = "<lens><intrinsics><fx>600</fx><fy>600</fy><cx>320</cx><cy>240</cy><s>0</s></intrinsics></lens>"
    sensors = {side: sensor(f"{side}_cam", extra=lens, plugin=CLASSIC_PLUGIN.format(side) if plugin else "")
               for side in ("left", "right")}
    return write(tmp_path, f"lens_{plugin}.urdf", two_camera_urdf(left_sensor=sensors["left"],
                                                                  right_sensor=sensors["right"]))


def test_lint_lens_advice_follows_the_simulator(tmp_path: Path) -> None:
    classic = [f.message for f in lint_description(_lens_rig(tmp_path, plugin=True)) if f.code == "lens-intrinsics"]
    assert classic and all("gazebo_ros publishes camera_info from horizontal_fov" in m and "gz-sim" not in m
                           for m in classic)
    lens = "<lens><intrinsics><fx>600</fx><fy>600</fy><cx>320</cx><cy>240</cy><s>0</s></intrinsics></lens>"
    world = GZ_WORLD.read_text().replace("<clip>", lens + "<clip>")
    gz = [f.message for f in lint_description(write(tmp_path, "gz.sdf", world)) if f.code == "lens-intrinsics"]
    assert gz and all("gz-sim renders and publishes the intrinsics" in m and "classic" not in m for m in gz)


def test_lint_crop_advice_for_a_gazebo_ros_file_is_gazebo_ros(tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    """The reproducer: lint of a gazebo_ros rig with barrel distortion said 'gz-sim has no switch for it'."""
    distortion = ("<distortion><k1>-0.25</k1><k2>0.1</k2><k3>0</k3><p1>0</p1><p2>0</p2><center>0.5 0.5</center>"
                  "</distortion>")
    rig = two_camera_urdf(left_sensor=sensor("left_cam", extra=distortion, plugin=CLASSIC_PLUGIN.format("left")),
                          right_sensor=sensor("right_cam", extra=distortion, plugin=CLASSIC_PLUGIN.format("right")))
    path = write(tmp_path, "barrel.urdf", rig)
    main(["lint", str(path)])
    err = capsys.readouterr().err
    assert "set <borderCrop>false</borderCrop> in its gazebo_ros camera plugin" in err and "gz-sim" not in err
    world = GZ_WORLD.read_text().replace("<clip>", distortion + "<clip>")
    main(["lint", str(write(tmp_path, "gz.sdf", world))])
    err = capsys.readouterr().err
    assert "gz-sim has no switch for it" in err and "borderCrop" not in err
