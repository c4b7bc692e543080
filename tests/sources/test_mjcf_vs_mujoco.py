"""The MJCF reader against MuJoCo itself: fx fy cx cy within 1e-6 relative, T within 1e-6 m, R within 1e-6, on the
written corpus (through ``s2r profile from-description``) and on seeded random scenes (through the loader)."""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from s2r.cli import main
from s2r.formats.s2r_yaml import load_profile_file as load_profile
from s2r.sources import load_description, stereo_pair
from tests.sources.mjcf_corpus import SCENES, Scene, write_scene
from tests.sources.mjcf_oracle import Truth, pair_truth
from tests.sources.mjcf_random import random_scene

REL = 1e-6


@pytest.fixture(autouse=True)
def _library_logs() -> Iterator[None]:
    """Library calls here log through the root logger (a CLI run in an earlier test left its own stream behind)."""
    logger = logging.getLogger("s2r")
    saved = logger.handlers[:], logger.propagate
    logger.handlers[:], logger.propagate = [], True
    yield
    logger.handlers[:], logger.propagate = saved


def _close(value: float, truth: float, what: str) -> None:
    assert abs(value - truth) <= REL * max(1.0, abs(truth)), f"{what}: {value!r} vs MuJoCo {truth!r}"


def _intrinsics(values: tuple[float, float, float, float], truth: Truth, what: str) -> None:
    for name, v, t in zip(("fx", "fy", "cx", "cy"), values, (truth.fx, truth.fy, truth.cx, truth.cy), strict=True):
        _close(v, t, f"{what} {name}")


@pytest.mark.parametrize("scene", SCENES, ids=[s.name for s in SCENES])
def test_corpus_profile_matches_mujoco(scene: Scene, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_scene(tmp_path, scene)
    out = tmp_path / "sim.yaml"
    assert main(["profile", "from-description", str(path), "--left", scene.left, "--right", scene.right,
                 "-o", str(out)]) == 0
    warnings = capsys.readouterr().err
    profile = load_profile(out)
    left, right, T_left_right = pair_truth(path, scene.left, scene.right)
    for cam, truth, side in ((profile.left, left, "left"), (profile.right, right, "right")):
        assert (cam.width_px, cam.height_px) == (truth.width, truth.height)
        _intrinsics((cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px), truth, side)
    T_right_left = np.linalg.inv(T_left_right)
    np.testing.assert_allclose(profile.T, T_right_left[:3, 3], atol=1e-6)
    np.testing.assert_allclose(profile.R, T_right_left[:3, :3], atol=1e-6)
    assert profile.T[0] < 0, "the right camera is on the right (T_x = -baseline)"
    assert profile.provenance.convention == "exact"
    assert ("offscreen buffer size 800x600" in warnings) == (scene.name == "fovy_no_resolution_offscreen")
    assert ("moves with the simulation state" in warnings) == scene.name.endswith("_mode")


@pytest.mark.parametrize("seed", range(60))
def test_random_scene_matches_mujoco(seed: int, tmp_path: Path) -> None:
    """Random body trees (every pose form, frames, both angle units, random Euler sequences, default classes and
    every intrinsic form): each camera's intrinsics and the pair's relative pose equal MuJoCo's."""
    path = tmp_path / "scene.xml"
    path.write_text(random_scene(seed), encoding="utf-8")
    description = load_description(path)
    assert [c.name for c in description.cameras] == ["cam_a", "cam_b"]
    pair = stereo_pair(description, left="cam_a", right="cam_b")
    a, b, T_left_right = pair_truth(path, "cam_a", "cam_b")
    for spec, truth in ((pair.left, a), (pair.right, b)):
        assert spec.lens is not None and (spec.width, spec.height) == (truth.width, truth.height)
        _intrinsics((spec.lens.fx, spec.lens.fy, spec.lens.cx - 0.5, spec.lens.cy - 0.5), truth, spec.name)
        assert math.isclose(spec.hfov_rad, 2 * math.atan(truth.width / (2 * truth.fx)), rel_tol=REL)
    np.testing.assert_allclose(pair.T_left_right, T_left_right, atol=1e-6)
    if "<keyframe>" in path.read_text(encoding="utf-8"):
        moved = stereo_pair(load_description(path, keyframe="pose"), left="cam_a", right="cam_b")
        _, _, T_key = pair_truth(path, "cam_a", "cam_b", keyframe=0)
        np.testing.assert_allclose(moved.T_left_right, T_key, atol=1e-6)


KEYFRAMES = """<mujoco><compiler angle="degree"/>
  <worldbody>
    <body name="target" mocap="true" pos="3 0 1"/>
    <body name="robot" pos="0 0 0.5"><freejoint/><geom size="0.1"/>
      <body name="neck" pos="0.1 0 0.4"><joint name="yaw" axis="0 0 1" ref="10"/><geom size="0.05"/>
        <body name="head" pos="0.05 0 0.1"><joint name="lift" type="slide" axis="0 0 1"/>
          <joint name="pitch" axis="0 1 0" pos="0 0 -0.05"/><geom size="0.05"/>
          <camera name="left" pos="0.05 0.04 0" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"/>
          <camera name="right" pos="0.05 -0.04 0" xyaxes="0 -1 0 0 0 1" fovy="60" resolution="640 480"/>
          <camera name="aim" pos="0.05 0 0.05" mode="targetbody" target="target" resolution="640 480"/>
        </body>
        <camera name="follow" pos="-1 0 0.5" xyaxes="0 -1 0 0.4 0 0.9" mode="track" resolution="640 480"/>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="home"/>
    <key name="look" qpos="0.2 -0.1 0.6 0.9 0 0 0.3 0.7 0.05 -0.4" mpos="2 1 1.5" mquat="1 0 0 0"/>
  </keyframe>
</mujoco>"""


@pytest.mark.parametrize("key", ["0", "look", "1"])
def test_keyframes_match_mujoco(key: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Free, hinge (with a reference angle, in degrees), slide and anchored hinge joints, a mocap target, track and
    targetbody cameras: every camera pair placed at a keyframe as MuJoCo places it."""
    path = tmp_path / "scene.xml"
    path.write_text(KEYFRAMES, encoding="utf-8")
    index = {"0": 0, "look": 1, "1": 1}[key]
    description = load_description(path, keyframe=key)
    for left, right in (("left", "right"), ("left", "aim"), ("left", "follow"), ("follow", "aim")):
        pair = stereo_pair(description, left=left, right=right)
        _, _, T_left_right = pair_truth(path, left, right, keyframe=index)
        np.testing.assert_allclose(pair.T_left_right, T_left_right, atol=1e-6)
    out = tmp_path / "sim.yaml"
    assert main(["profile", "from-description", str(path), "--left", "left", "--right", "right", "--keyframe", key,
                 "-o", str(out)]) == 0
    assert main(["lint", str(path), "--left", "left", "--right", "follow", "--keyframe", key]) in (0, 1)
    report = capsys.readouterr().out
    assert f"[movable-joint] joint '<body head>' (slide) lies between the camera links; it is taken at keyframe {key}" \
        in report
    assert f"camera 'follow': camera mode 'track' moves with the simulation state: read at keyframe {key}" in report


def test_unknown_keyframe_lists_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scene.xml"
    path.write_text(KEYFRAMES, encoding="utf-8")
    assert main(["profile", "from-description", str(path), "--left", "left", "--right", "right", "--keyframe",
                 "sit", "-o", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err
    assert "no keyframe 'sit'; keyframes: 0 (home), 1 (look)" in err and err.count("\n") == 1
