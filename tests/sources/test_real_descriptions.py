"""Robot descriptions written after real public macros: the optical axis comes from the composed sensor pose.

Fixtures (small excerpts written for these tests, see their header comments):
- ``fixtures/pointgrey_bumblebee2.urdf.xacro`` after ros-drivers/pointgrey_camera_driver
  ``pointgrey_camera_description/urdf/pointgrey_bumblebee2.urdf.xacro`` (Clearpath Jackal / Husky);
- ``fixtures/pointgrey_flea3_stereo.urdf.xacro`` after ``.../urdf/pointgrey_flea3.urdf.xacro``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.errors import FormatError
from s2r.formats.ros import ros_pair_from_profile
from s2r.registry import load_profile
from s2r.sources import lint_description, load_description_profile

FIXTURES = Path(__file__).parent / "fixtures"
BB2 = FIXTURES / "pointgrey_bumblebee2.urdf.xacro"
FLEA3 = FIXTURES / "pointgrey_flea3_stereo.urdf.xacro"


def test_bumblebee2_on_an_optical_link_is_a_sideways_12_cm_pair() -> None:
    """Camera pose rpy (0, -1.5707, 1.5707) turns Gazebo's +x onto the optical link's +z (forward): the right
    camera's pose x = 0.120 m is along the optical link's x, i.e. 12 cm to the RIGHT, not above.

    By hand: fx = 640 / (2 tan(1.15191730632 / 2)) = 320 / 0.649408 = 492.7572 px; cx = 320.5 (classic);
    |T| = 0.120 m exactly (a pure translation between two equally rotated cameras); the 1.5707 (not pi/2)
    leaves T_y = -0.12 sin(9.63e-5) = -1.16e-5 m.
    """
    p = load_description_profile(BB2)
    assert p.left.fx_px == pytest.approx(640 / (2 * math.tan(1.15191730632 / 2)), abs=1e-6)
    assert p.left.fx_px == pytest.approx(492.757, abs=1e-3)
    assert (p.left.cx_px, p.left.cy_px) == (320.5, 240.5)
    assert p.baseline_m == pytest.approx(0.120, abs=1e-9)
    assert pytest.approx([-0.120, 0.0, 0.0], abs=2e-5) == p.T
    assert np.allclose(p.R, np.eye(3), atol=1e-9)
    assert p.left.frame_id == "front_camera_optical"  # the plugin's frameName, which is where the images live
    assert not [f for f in lint_description(BB2) if f.severity in ("error", "warning")]


def test_flea3_stereo_bar_is_a_sideways_32_cm_pair(tmp_path: Path) -> None:
    """Two Flea3 macros at y = +-0.16 m on a bar: 0.32 m apart; fx = 1280 / (2 tan(pi/6)) = 1108.5125 px."""
    p = load_description_profile(FLEA3)
    assert p.left.fx_px == pytest.approx(640 / math.tan(1.0471975512 / 2), abs=1e-6)
    assert p.left.fx_px == pytest.approx(1108.5125, abs=1e-4)
    assert pytest.approx([-0.32, 0.0, 0.0], abs=4e-5) == p.T  # T_y = -0.32 sin(9.63e-5) = -3.08e-5 m
    out = tmp_path / "flea.yaml"
    assert main(["profile", "from-urdf", str(FLEA3), "-o", str(out)]) == 0
    assert load_profile(out).baseline_m == pytest.approx(0.32, abs=1e-9)


def test_lint_and_from_urdf_share_one_rule(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The Flea3 pair with its cameras swapped by name: lint says baseline-side (error), from-urdf refuses with
    exit 2 naming the same code; --allow-bad-baseline writes it with a loud warning; --to ros then refuses."""
    swapped = FLEA3.read_text().replace('"0 0.16 0"', "SWAP").replace('"0 -0.16 0"', '"0 0.16 0"')
    swapped = swapped.replace("SWAP", '"0 -0.16 0"')
    path = tmp_path / "swapped.urdf.xacro"
    path.write_text(swapped)
    assert [f.code for f in lint_description(path) if f.severity == "error"][:1] == ["baseline-side"]
    out = tmp_path / "swapped.yaml"
    assert main(["profile", "from-urdf", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "[baseline-side]" in err and "32.0 cm to the LEFT" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
    assert main(["profile", "from-urdf", str(path), "-o", str(out), "--allow-bad-baseline"]) == 0
    assert "warning:" in (err := capsys.readouterr().err) and "ERROR [baseline-side]" in err
    assert main(["profile", "convert", str(out), "--to", "ros", "-o", str(tmp_path / "ros")]) == 2
    assert "[baseline-side]" in capsys.readouterr().err
    assert not (tmp_path / "ros" / "left.yaml").exists()
    with pytest.raises(FormatError, match="baseline-side"):
        ros_pair_from_profile(load_profile(out))


def test_drcsim_multisense_sl_multicamera() -> None:
    """osrf/drcsim's MultiSense SL: 800x800 at horizontal_fov 1.3962634 rad (80 deg): fx = 400 / tan(0.6981317)
    = 476.70144 px; the right camera's pose y = -0.07 m in Gazebo's x-forward frame is 7 cm to the right."""
    p = load_description_profile(FIXTURES / "multisense_sl_drcsim.urdf")
    assert p.left.fx_px == pytest.approx(400 / math.tan(1.3962634 / 2), abs=1e-6)
    assert p.T.tolist() == pytest.approx([-0.07, 0.0, 0.0], abs=1e-12)
    assert p.left.frame_id == "left_camera_optical_frame" and p.simulation.noise_stddev == 0.007
    findings = lint_description(FIXTURES / "multisense_sl_drcsim.urdf")
    assert not [f for f in findings if f.severity in ("error", "warning")]


@pytest.mark.parametrize("text, why", [
    # PR2/pr2_common pr2_description/urdf/sensors/wge100_camera.gazebo.xacro: a macro that nothing calls
    ('<robot xmlns:xacro="http://ros.org/wiki/xacro"><xacro:macro name="wge100_camera_gazebo_v0" params="name">'
     '<gazebo reference="${name}_frame"><sensor name="${name}_sensor" type="camera"/></gazebo></xacro:macro></robot>',
     "only defines xacro macros (wge100_camera_gazebo_v0)"),
    # the same macro's body: Gazebo 0.x <sensor:camera> (pre-SDF)
    ('<robot xmlns:sensor="http://playerstage.sourceforge.net/gazebo/xmlschema/#sensor"><link name="a_frame"/>'
     '<gazebo reference="a_frame"><sensor:camera name="a"><imageSize>640 480</imageSize></sensor:camera></gazebo>'
     '</robot>', "Gazebo 0.x"),
])
def test_pr2_era_descriptions_exit_2_naming_why(text: str, why: str, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "cam.urdf.xacro"
    path.write_text(text)
    assert main(["profile", "from-urdf", str(path), "-o", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and why in err, err
