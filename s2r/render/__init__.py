"""Camera simulation: boards and ground-truth depth scenes, drawn by PyBullet (default) or MuJoCo (the only
importers of pybullet and, in :mod:`s2r.render.mujoco.backend`, of mujoco; :mod:`s2r.render.backend` is the seam
between them).

- :func:`render_board_set`: a stereo chessboard calibration set (left/, right/, truth.yaml) through a profile.
- :func:`render_scene` / :func:`write_scene`: textured scenes with exact depth and rectified disparity.
The render world is the profile's LEFT optical frame (z forward, x right, y down, metres).

Layout (imports run one way, top imports bottom):

- :mod:`s2r.render.boards` -- calibration sets: the board poses (``poses``), file-described targets (``targets``)
  and the rendered sets (``sets``); ``scenes`` with ``layouts`` -- ground-truth depth scenes.
- ``rig`` (a profile's stereo rig and the per-view job), ``sensor`` (a profile camera emulated: supersampling,
  lens distortion through :mod:`s2r.lens`, the sensor model), ``cubemap`` (wide lenses), ``parallel``, ``outputs``.
- ``backend`` -- the renderer seam; :mod:`s2r.render.mujoco` (MuJoCo backend and ``--world`` files) behind it.
- PyBullet: ``camera`` (cameras from a profile, the PinholeView every backend returns), ``world`` (meshes, the
  Surface every scene is made of), ``_pybullet`` (its quiet import); ``textures``.
"""

from s2r.render.boards.sets import BoardSet, render_board_set
from s2r.render.layouts import SCENES
from s2r.render.outputs import check_output_dir
from s2r.render.scenes import SceneFrame, render_scene, write_scene

__all__ = ["SCENES", "BoardSet", "SceneFrame", "check_output_dir", "render_board_set", "render_scene", "write_scene"]
