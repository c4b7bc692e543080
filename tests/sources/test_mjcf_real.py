"""Cameras of real MJCF models, as short excerpts written here (the body chains, joints, defaults and cameras; meshes,
geoms and inertias left out, ``<compiler boundmass>`` keeps MuJoCo compiling the massless bodies):

- mujoco_menagerie ``aloha/aloha.xml``: two world cameras facing each other and a D405 wrist camera on each arm
  (radian compiler, Euler angles, joint classes); no pair of them is a stereo rig, and from-description says why.
- mujoco_menagerie ``robotstudio_so101/so101.xml``: the wrist camera with ``sensorsize`` and ``focal`` (1200 px).
- a VR teleoperation rig (two eye cameras on a mocap head, no resolution), a soccer humanoid's stereo head (two
  eyes on the pitch link) and an insect model's two divergent eyes, from public repositories' MJCF.

Each camera's intrinsics and world pose are checked against MuJoCo (1e-6), and each pair is either written (right
camera on the right) or refused in one line naming why.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file
from s2r.sources import load_description
from s2r.sources.kinematics import KinematicTree
from s2r.sources.loader import optical_pose
from tests.sources.mjcf_oracle import camera_truth

_ARM = '''<body name="{s}/base_link" childclass="vx300s" pos="{x} -0.019 0.02" {q}>
  <body name="{s}/shoulder_link" pos="0 0 0.079"><joint name="{s}/waist" class="waist"/>
   <body name="{s}/upper_arm_link" pos="0 0 0.04805"><joint name="{s}/shoulder"/>
    <body name="{s}/upper_forearm_link" pos="0.05955 0 0.3"><joint name="{s}/elbow"/>
     <body name="{s}/lower_forearm_link" pos="0.2 0 0"><joint name="{s}/forearm_roll" class="forearm_roll"/>
      <body name="{s}/wrist_link" pos="0.1 0 0"><joint name="{s}/wrist_angle"/>
       <body name="{s}/gripper_link" pos="0.069744 0 0"><joint name="{s}/wrist_rotate" class="forearm_roll"/>
        <body name="{s}/gripper_base" euler="0 1.57 -1.57" pos="0.035 0 0">
         <camera name="wrist_cam_{s}" pos="0 -0.0824748 -0.0095955" fovy="58" mode="fixed" euler="2.70525955359 0 0"/>
        </body></body></body></body></body></body></body></body>'''
ALOHA = ('''<mujoco model="aloha"><compiler angle="radian" autolimits="true" boundmass="0.001" boundinertia="1e-6"/>
  <default><default class="vx300s"><joint axis="0 1 0"/>
    <default class="waist"><joint axis="0 0 1"/></default>
    <default class="forearm_roll"><joint axis="1 0 0"/></default></default></default>
  <worldbody>
    <camera name="teleoperator_pov" pos="0 -1.354 0.685" xyaxes="1 0 0 0 0.2 .8"/>
    <camera name="collaborator_pov" pos="0 1.5 0.8" xyaxes="-1 0 0 0 -0.2 .8"/>
    ''' + _ARM.format(s="left", x="-0.469", q="") + _ARM.format(s="right", x="0.469", q='quat="0 0 0 1"')
         + "</worldbody></mujoco>")
SO101 = '''<mujoco model="so101"><compiler angle="radian" autolimits="true" boundmass="0.001" boundinertia="1e-6"/>
  <worldbody><body name="base" pos="0 0 0" quat="1 0 0 0">
   <body name="shoulder" pos="0.0388353 0 0.0624" quat="0 0 -1 0"><joint axis="0 0 1" name="shoulder_pan"/>
    <body name="upper_arm" pos="-0.0303992 -0.0182778 -0.0542" quat="1 -1 -1 -1"><joint axis="0 0 1"/>
     <body name="lower_arm" pos="-0.11257 -0.028 0" quat="1 0 0 1"><joint axis="0 0 1"/>
      <body name="wrist" pos="-0.1349 0.0052 0" quat="1 0 0 -1"><joint axis="0 0 1"/>
       <body name="gripper" pos="5.55112e-17 -0.0611 0.0181" quat="0.0172091 -0.0172091 0.706897 0.706897">
        <joint axis="0 0 1"/>
        <body name="camera_mount"><camera name="wrist_cam" mode="fixed" pos="0.0 0.055 -0.045" euler="-0.57 0 0"
          resolution="1920 1080" sensorsize="0.00576 0.00324" focal="0.0036 0.0036"/></body>
  </body></body></body></body></body></body></worldbody></mujoco>'''
VR_RIG = '''<mujoco><worldbody><body name="head" mocap="true" pos="0 0 1.6">
  <camera name="left_eye" pos="-0.032 0 0" fovy="90"/><camera name="right_eye" pos=" 0.032 0 0" fovy="90"/>
  </body></worldbody></mujoco>'''
SOCCER_HEAD = '''<mujoco><compiler boundmass="0.001" boundinertia="1e-6"/><worldbody>
  <body name="base_link" pos="0 0 0.6"><freejoint/>
   <body name="head_yaw_link" pos="0 0 0.3"><joint name="head_yaw_joint" axis="0 0 1"/>
    <body name="head_pitch_link" pos="0 0 0.05"><joint name="head_pitch_joint" axis="0 1 0"/>
     <camera name="left_eye" pos="0.1 0.03 0.05" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"/>
     <camera name="right_eye" pos="0.1 -0.03 0.05" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"/>
  </body></body></body></worldbody></mujoco>'''
INSECT = '''<mujoco><worldbody><body name="thorax" pos="0 0 0.1"><body name="head" pos="0.012 0 0">
  <camera name="left_eye" pos="0.003 0.006 0.002" xyaxes="0 -1 0  0.342 0 0.940" fovy="90" mode="fixed"/>
  <camera name="right_eye" pos="0.003 -0.006 0.002" xyaxes="0 1 0  0.342 0 0.940" fovy="90" mode="fixed"/>
  </body></body></worldbody></mujoco>'''

#: (model, left, right, expected: the baseline in metres, or the words of the refusal)
PAIRS: list[tuple[str, str | None, str | None, float | str]] = [
    (ALOHA, "teleoperator_pov", "collaborator_pov", "[baseline-axis] baseline along the optical axis"),
    (ALOHA, "wrist_cam_left", "wrist_cam_right", "[baseline-axis] baseline along the optical axis"),
    (SO101, None, None, "found 1 camera(s): wrist_cam"),
    (VR_RIG, "left_eye", "right_eye", 0.064),
    (SOCCER_HEAD, "left_eye", "right_eye", 0.06),
    (INSECT, "left_eye", "right_eye", "the right camera is turned 180.0 deg from the left"),
]


def _world_optical(path: Path, name: str) -> np.ndarray:
    description = load_description(path)
    spec = next(c for c in description.cameras if c.name == name)
    T_root_link, _ = KinematicTree(description).pose_in_root(spec.link)
    return np.asarray(T_root_link @ optical_pose(spec))


@pytest.mark.parametrize(("model", "left", "right", "expected"), PAIRS,
                         ids=["aloha_povs", "aloha_wrists", "so101", "vr_rig", "soccer_head", "insect"])
def test_real_cameras_match_mujoco(model: str, left: str | None, right: str | None, expected: float | str,
                                   tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "model.xml"
    path.write_text(model, encoding="utf-8")
    for spec in load_description(path).cameras:
        truth = camera_truth(path, spec.name)
        assert spec.lens is not None and (spec.width, spec.height) == (truth.width, truth.height)
        got = (spec.lens.fx, spec.lens.fy, spec.lens.cx - 0.5, spec.lens.cy - 0.5)
        np.testing.assert_allclose(got, (truth.fx, truth.fy, truth.cx, truth.cy), rtol=1e-6)
        np.testing.assert_allclose(_world_optical(path, spec.name), truth.T_world_optical, atol=1e-6)
    out = tmp_path / "sim.yaml"
    names = ["--left", left, "--right", right] if left and right else []
    code = main(["profile", "from-description", str(path), *names, "-o", str(out)])
    err = capsys.readouterr().err
    if isinstance(expected, float):
        assert code == 0, err
        profile = load_profile_file(out)
        assert profile.T[0] < 0 and profile.baseline_m == pytest.approx(expected, abs=1e-9)
    else:
        last = err.strip().splitlines()[-1]  # after the warnings (joints on the path, no resolution): one line
        assert code == 2 and last.startswith("error: ") and expected in last, err
        assert not out.exists()


def test_so101_wrist_camera_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "so101.xml"
    path.write_text(SO101, encoding="utf-8")
    camera = load_description(path).cameras[0]
    assert camera.lens is not None and (camera.lens.fx, camera.lens.fy) == pytest.approx((1200.0, 1200.0), rel=1e-12)
    assert (camera.lens.cx - 0.5, camera.lens.cy - 0.5) == pytest.approx((959.5, 539.5), rel=1e-12)


def test_aloha_keyframe_moves_the_wrist_cameras_as_mujoco(tmp_path: Path) -> None:
    """Joint axes from the arm's classes (childclass vx300s, class waist / forearm_roll): a keyframe with every joint
    turned places both wrist cameras where MuJoCo does."""
    qpos = "0.3 -0.5 0.8 0.2 -0.7 1.1 -0.2 0.4 -0.6 0.1 0.9 -1.3"
    path = tmp_path / "aloha.xml"
    path.write_text(ALOHA.replace("</mujoco>", f'<keyframe><key name="reach" qpos="{qpos}"/></keyframe></mujoco>'),
                    encoding="utf-8")
    description = load_description(path, keyframe="reach")
    tree = KinematicTree(description)
    for spec in description.cameras:
        truth = camera_truth(path, spec.name, keyframe=0)
        T_root_link, _ = tree.pose_in_root(spec.link)
        np.testing.assert_allclose(T_root_link @ optical_pose(spec), truth.T_world_optical, atol=1e-6)
