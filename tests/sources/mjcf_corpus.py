"""A corpus of MJCF stereo scenes written for these tests: every intrinsic form, nested bodies with every pose form,
degree and radian compilers, Euler sequences, default classes, frames and includes.

Each scene is a rig whose two cameras look the same way side by side (the right one on the right), so that
``s2r profile from-description`` writes it; MuJoCo (tests/sources/mjcf_oracle.py) is the anchor for every number.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["SCENES", "Scene", "write_scene"]


@dataclass(frozen=True)
class Scene:
    """Files of one scene (``main`` plus includes) and its camera pair."""

    name: str
    main: str
    left: str = "left"
    right: str = "right"
    includes: dict[str, str] = field(default_factory=dict)


def write_scene(folder: Path, scene: Scene) -> Path:
    """Write the scene's files under ``folder``; the main file's path."""
    for rel, text in scene.includes.items():
        target = folder / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
    path = folder / "scene.xml"
    path.write_text(scene.main, encoding="utf-8")
    return path


# A camera head whose cameras look along the body's +x with image right = body -y (xyaxes "0 -1 0 0 0 1").
_HEAD = '''<camera name="left" pos="0 {b} 0" xyaxes="0 -1 0 0 0 1" {k}/>
        <camera name="right" pos="0 -{b} 0" xyaxes="0 -1 0 0 0 1" {k}/>'''

SCENES = [
    Scene("fovy_world", '''<mujoco><worldbody>
      <camera name="left" pos="-0.05 0 1" resolution="640 480"/>
      <camera name="right" pos="0.05 0 1" resolution="640 480"/>
    </worldbody></mujoco>'''),
    Scene("fovy_no_resolution_offscreen", '''<mujoco><visual><global offwidth="800" offheight="600"/></visual>
      <worldbody><body name="head" pos="0 0 1.2">''' + _HEAD.format(b="0.06", k='fovy="70"') + '''</body>
      </worldbody></mujoco>'''),
    Scene("sensor_focal_metres_principal_metres", '''<mujoco><worldbody><body name="head" pos="0.3 0 0.8">'''
          + _HEAD.format(b="0.0375", k='resolution="1280 720" sensorsize="0.00576 0.00324" focal="0.0036 0.0035" '
                         'principal="0.0001 -0.00005"') + '''</body></worldbody></mujoco>'''),
    Scene("sensor_focalpixel_principalpixel", '''<mujoco><worldbody><body name="head" pos="0 0 1">'''
          + _HEAD.format(b="0.025", k='resolution="640 480" sensorsize="0.0064 0.0048" focalpixel="500 400" '
                         'principalpixel="10 -5"') + '''</body></worldbody></mujoco>'''),
    Scene("pixel_wins_over_length_per_axis", '''<mujoco><worldbody><body name="head" pos="0 0 1">'''
          + _HEAD.format(b="0.03", k='resolution="752 480" sensorsize="0.0045 0.0029" focal="0.003 0.003" '
                         'focalpixel="470.5 0" principal="0.0001 0.0002" principalpixel="0 -3.25"')
          + '''</body></worldbody></mujoco>'''),
    Scene("nested_every_pose_form_degrees", '''<mujoco><compiler angle="degree"/><worldbody>
      <body name="base" pos="1 -2 0.3" quat="2 0 0 1"><joint type="free"/><geom size="0.1"/>
        <body name="torso" pos="0.1 0 0.5" axisangle="0 1 0 -10">
          <body name="neck" pos="0 0 0.3" euler="5 -3 20">
            <frame pos="0.02 0 0.05" zaxis="0.1 0 1">
              <body name="head" pos="0.05 0 0" xyaxes="1 0.1 0 -0.1 1 0">'''
          + _HEAD.format(b="0.04", k='fovy="58" resolution="848 480"') + '''</body></frame></body></body></body>
    </worldbody></mujoco>'''),
    Scene("radian_eulerseq_zyx_intrinsic", '''<mujoco><compiler angle="radian" eulerseq="zyx"/><worldbody>
      <body name="mast" pos="0 0 1.5" euler="0.4 0.2 -0.1">
        <body name="head" pos="0.1 0 0" axisangle="1 1 0 0.3">'''
          + _HEAD.format(b="0.05", k='fovy="45" resolution="640 400"') + '''</body></body></worldbody></mujoco>'''),
    Scene("eulerseq_mixed_extrinsic", '''<mujoco><compiler eulerseq="XyZ"/><worldbody>
      <body name="mast" pos="0 0 1.5" euler="30 -20 45">
        <frame euler="10 0 -5"><body name="head" pos="0.1 0 0">'''
          + _HEAD.format(b="0.05", k='fovy="45" resolution="640 400"') + '''</body></frame></body>
    </worldbody></mujoco>'''),
    Scene("camera_euler_and_quat_forms", '''<mujoco><compiler angle="radian"/><worldbody>
      <body name="head" pos="0 0 1" euler="0 0 0.3">
        <camera name="left" pos="0.02 0.035 0" euler="1.5707963267948966 -1.5707963267948966 0" resolution="640 480"/>
        <camera name="right" pos="0.02 -0.035 0" quat="0.5 0.5 -0.5 -0.5" resolution="640 480"/>
      </body></worldbody></mujoco>'''),
    Scene("defaults_nested_childclass_class", '''<mujoco>
      <default><camera fovy="50" resolution="640 480"/>
        <default class="rig"><camera sensorsize="0.0048 0.0036" focalpixel="610 605" principalpixel="2.5 -1.5"
            xyaxes="0 -1 0 0 0 1"/>
          <default class="rig_right"><camera pos="0 -0.045 0"/></default>
        </default>
      </default>
      <worldbody><body name="head" pos="0 0 1" childclass="rig">
        <camera name="left" pos="0 0.045 0"/>
        <frame childclass="rig_right"><camera name="right"/></frame>
      </body></worldbody></mujoco>'''),
    Scene("default_orientation_overridden_by_quat", '''<mujoco>
      <default><camera euler="0 0 90" fovy="60" resolution="640 480"/></default>
      <worldbody><body name="head" pos="0 0 1">
        <camera name="left" pos="0 0.05 0" quat="0.5 0.5 -0.5 -0.5"/>
        <camera name="right" pos="0 -0.05 0" xyaxes="0 -1 0 0 0 1"/>
      </body></worldbody></mujoco>'''),
    Scene("includes_nested_folders", '''<mujoco><include file="parts/settings.xml"/>
      <worldbody><body name="robot" pos="0 0 0.5"><include file="parts/head.xml"/></body></worldbody></mujoco>''',
          includes={
              "parts/settings.xml": '''<mujoco><compiler angle="radian"/>
                 <default><default class="cam"><camera fovy="42" resolution="1024 768"/></default></default>
                 </mujoco>''',
              "parts/head.xml": '''<mujoco><body name="head" pos="0.1 0 0.4" euler="0 0.1 0">
                 <include file="parts/eyes.xml"/></body></mujoco>''',
              "parts/eyes.xml": '''<mujoco><camera name="left" class="cam" pos="0 0.06 0" xyaxes="0 -1 0 0 0 1"/>
                 <camera name="right" class="cam" pos="0 -0.06 0" xyaxes="0 -1 0 0 0 1"/></mujoco>''',
          }),
    Scene("frames_in_frames_worldbody", '''<mujoco><compiler angle="radian"/><worldbody>
      <frame pos="0.5 0 1" euler="0 0 0.2"><frame pos="0 0.1 0" axisangle="0 1 0 0.1"><frame quat="1 0 0 0.05">
        <camera name="left" pos="0 0.04 0" xyaxes="0 -1 0 0 0 1" fovy="55" resolution="960 540"/></frame>
        <camera name="right" pos="0 -0.04 0" quat="0.49875 0.5 -0.5 -0.50125" fovy="55" resolution="960 540"/>
      </frame></frame></worldbody></mujoco>'''),
    Scene("menagerie_layout_two_worldbodies", '''<mujoco model="scene"><include file="robot.xml"/>
      <statistic center="0 0 0.1" extent="0.6"/>
      <worldbody><light pos="0 0 1"/><geom name="floor" size="0 0 0.05" type="plane"/>
        <body name="stand2" pos="0.4 0 0.3" euler="0 0 3.14159265"><camera name="right" class="eye" pos="0 -0.03 0"/>
        </body></worldbody></mujoco>''', includes={"robot.xml": '''<mujoco model="robot">
        <compiler angle="radian" autolimits="true"/><option timestep="0.005"/>
        <default><default class="robot"><joint damping="1"/>
          <default class="eye"><camera fovy="40" resolution="1280 800" xyaxes="0 -1 0 0 0 1"/></default></default>
        </default>
        <asset><material name="m" rgba="1 1 1 1"/></asset>
        <worldbody><body name="stand" pos="0.4 0 0.3" euler="0 0 3.14159265">
          <camera name="left" class="eye" pos="0 0.03 0"/></body></worldbody>
        <sensor><framepos name="p" objtype="body" objname="stand"/></sensor></mujoco>'''}),
    Scene("cameras_on_separate_bodies", '''<mujoco><worldbody>
      <body name="bar" pos="0 0 1" axisangle="0 0 1 15">
        <body name="lmount" pos="0 0.06 0" quat="1 0 0 0.01"><camera name="left" quat="0.5 0.5 -0.5 -0.5" fovy="60"
            resolution="640 480"/></body>
        <body name="rmount" pos="0 -0.06 0"><camera name="right" quat="0.5 0.5 -0.5 -0.5" fovy="60"
            resolution="640 480"/></body></body></worldbody></mujoco>'''),
    Scene("targetbody_mode", '''<mujoco><worldbody>
      <body name="target" pos="2 0.3 0.4"/>
      <body name="head" pos="0 0 1">
        <camera name="left" pos="0 0.05 0" mode="targetbody" target="target" fovy="60" resolution="640 480"/>
        <camera name="right" pos="0 -0.05 0" mode="targetbody" target="target" fovy="60" resolution="640 480"/>
      </body></worldbody></mujoco>'''),
    Scene("track_mode", '''<mujoco><worldbody>
      <body name="cart" pos="0 0 0.2"><joint type="slide" axis="1 0 0"/><geom size="0.1"/>
        <camera name="left" pos="-0.5 0.05 1" xyaxes="0 -1 0 0.5 0 0.8" mode="track" resolution="640 480"/>
        <camera name="right" pos="-0.5 -0.05 1" xyaxes="0 -1 0 0.5 0 0.8" mode="trackcom" resolution="640 480"/>
      </body></worldbody></mujoco>'''),
]
