"""Camera simulation: boards and ground-truth depth scenes, drawn by PyBullet (default) or MuJoCo (the only
importers of pybullet and, in ``_mujoco``, of mujoco; :mod:`s2r.render.backend` is the seam between them).

- :func:`render_board_set`: a stereo chessboard calibration set (left/, right/, truth.yaml) through a profile.
- :func:`render_scene` / :func:`write_scene`: textured scenes with exact depth and rectified disparity.
The render world is the profile's LEFT optical frame (z forward, x right, y down, metres).
"""

from s2r.render.boards import BoardSet, render_board_set
from s2r.render.layouts import SCENES
from s2r.render.outputs import check_output_dir
from s2r.render.scenes import SceneFrame, render_scene, write_scene

__all__ = ["SCENES", "BoardSet", "SceneFrame", "check_output_dir", "render_board_set", "render_scene", "write_scene"]
