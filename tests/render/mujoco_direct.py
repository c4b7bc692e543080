"""An independent MuJoCo board renderer for the round-trip tests (shares no code with s2r).

A hand-written MJCF scene holds a chessboard (a thin box with a textured quad on its front face, on a mocap body)
and a stereo camera pair (hand-written, or pulled in with ``<include>``). Boards are placed in front of the left
camera at seeded poses and rendered by MuJoCo's own ``mujoco.Renderer``, one PNG pair per view, in the layout
``s2r calibrate`` reads (``left/NN.png``, ``right/NN.png``).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

os.environ.setdefault("MUJOCO_GL", "egl")

#: Board: 9x7 inner corners (10 x 8 squares), 20 mm squares, one square of white margin.
PATTERN, SQUARE_M, TEXELS = (9, 7), 0.02, 64
#: Board poses: distance range (m) from the left camera, largest tilt about the board's x and y axes (deg).
DISTANCE_M, TILT_DEG = (0.3, 0.7), 40.0


def board_png(path: Path) -> tuple[float, float]:
    """Write the board texture (grey PNG, 1 square margin); return its width and height in metres (the board's
    centre is the centre of its inner-corner grid)."""
    cols, rows = PATTERN[0] + 1, PATTERN[1] + 1
    j, i = np.meshgrid(np.arange(cols * TEXELS) // TEXELS, np.arange(rows * TEXELS) // TEXELS)
    squares = np.where((i + j) % 2 == 0, 25, 230).astype(np.uint8)
    img = np.pad(squares, TEXELS, constant_values=230)
    cv2.imwrite(str(path), img)
    return (cols + 2) * SQUARE_M, (rows + 2) * SQUARE_M


def board_xml(texture: Path, size_m: tuple[float, float]) -> str:
    """MJCF assets and a mocap body ``board``: its frame has x to the board's right, y down, z into the board;
    the textured quad (both windings) sits on the front face of a 4 mm box."""
    w, h = size_m[0] / 2, size_m[1] / 2
    verts = f"{-w} {-h} 0 {w} {-h} 0 {w} {h} 0 {-w} {h} 0"
    return f"""
  <asset>
    <texture name="board" type="2d" file="{texture}"/>
    <material name="board" texture="board" specular="0" shininess="0" reflectance="0"/>
    <mesh name="board_face" vertex="{verts}" texcoord="0 0 1 0 1 1 0 1" face="0 1 2 0 2 3 0 2 1 0 3 2"
          inertia="shell"/>
  </asset>
  <worldbody>
    <body name="board" mocap="true">
      <geom type="mesh" mesh="board_face" material="board" contype="0" conaffinity="0"/>
      <geom type="box" size="{w} {h} 0.002" pos="0 0 0.0021" rgba="0.3 0.3 0.3 1" contype="0" conaffinity="0"/>
    </body>
  </worldbody>"""


def scene_xml(cameras: str, texture: Path, size_m: tuple[float, float], *, width: int, height: int) -> str:
    """A complete scene: flat bright headlight, the board, and ``cameras`` (MJCF text placed as is)."""
    return f"""<mujoco model="board_scene">
  <visual>
    <global offwidth="{width}" offheight="{height}"/>
    <headlight ambient="0.95 0.95 0.95" diffuse="0 0 0" specular="0 0 0"/>
  </visual>
{board_xml(texture, size_m)}
{cameras}
</mujoco>
"""


def _camera(model: object, data: object, name: str) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                              NDArray[np.float64]]:
    """(K, R_world_optical, p_world) of a MuJoCo camera defined by sensorsize + focal/principal or their pixel forms."""
    m: Any = model
    cam = m.camera(name).id
    W, H = (float(v) for v in m.cam_resolution[cam])
    pixels = m.cam_intrinsic[cam] * np.array([W, H, W, H]) / np.tile(m.cam_sensorsize[cam], 2)
    K = np.array([[pixels[0], 0.0, (W - 1) / 2 - pixels[2]], [0.0, pixels[1], (H - 1) / 2 - pixels[3]], [0, 0, 1]])
    d: Any = data
    return K, d.cam_xmat[cam].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0]), d.cam_xpos[cam].copy()


def _inside(cams: list[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]],
            corners_world: NDArray[np.float64], size: tuple[int, int]) -> bool:
    for K, R, p in cams:
        X = (corners_world - p) @ R
        if np.any(X[:, 2] <= 0.1):
            return False
        uv = X[:, :2] / X[:, 2:] @ K[:2, :2].T + K[:2, 2]
        if np.any(uv < 15) or np.any(uv[:, 0] > size[0] - 16) or np.any(uv[:, 1] > size[1] - 16):
            return False
    return True


def board_poses(model: object, data: object, left: str, right: str, *, views: int, seed: int,
                size_m: tuple[float, float]) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Board (position, rotation matrix) in the world, seeded: the board's centre aimed at a 4x3 grid of image
    regions of the left camera at DISTANCE_M, tilted up to TILT_DEG, kept only where the whole board is inside
    both images (the board frame: x right, y down, z away from the camera, like the optical frame)."""
    rng = np.random.default_rng(seed)
    cams = [_camera(model, data, left), _camera(model, data, right)]
    m: Any = model
    W, H = (int(v) for v in m.cam_resolution[m.camera(left).id])
    K, R_left, p_left = cams[0]
    w, h = size_m[0] / 2, size_m[1] / 2
    outline = np.array([[-w, -h, 0.0], [w, -h, 0.0], [w, h, 0.0], [-w, h, 0.0]])
    poses: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
    for k in range(views):
        gx, gy = (k % 4 + 0.5) / 4, ((k // 4) % 3 + 0.5) / 3
        for _ in range(400):
            u, v = (gx + rng.uniform(-0.12, 0.12)) * W, (gy + rng.uniform(-0.15, 0.15)) * H
            d = rng.uniform(*DISTANCE_M)
            ray = np.linalg.solve(K, np.array([u, v, 1.0]))
            R_opt = Rotation.from_euler("xyz", rng.uniform(-TILT_DEG, TILT_DEG, 3) * np.array([1.0, 1.0, 0.3]),
                                        degrees=True).as_matrix()
            pos, R = p_left + R_left @ (ray * d), R_left @ R_opt
            if _inside(cams, outline @ R.T + pos, (W, H)):
                poses.append((pos, R))
                break
    return poses


def render_views(xml_path: Path, out_dir: Path, *, left: str, right: str, views: int, seed: int,
                 size_m: tuple[float, float]) -> int:
    """Render ``views`` board poses (a board of ``size_m``) through cameras ``left`` and ``right`` of ``xml_path``
    into ``out_dir``.

    Returns the number of views written."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(xml_path))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    width, height = (int(v) for v in model.cam_resolution[model.camera(left).id])
    renderer = mujoco.Renderer(model, height, width)
    for side in ("left", "right"):
        (out_dir / side).mkdir(parents=True, exist_ok=True)
    poses = board_poses(model, data, left, right, views=views, seed=seed, size_m=size_m)
    for k, (pos, R) in enumerate(poses):
        data.mocap_pos[0] = pos
        q = Rotation.from_matrix(R).as_quat()
        data.mocap_quat[0] = [q[3], q[0], q[1], q[2]]
        mujoco.mj_forward(model, data)
        for side, name in (("left", left), ("right", right)):
            renderer.update_scene(data, camera=name)
            rgb = renderer.render()
            cv2.imwrite(str(out_dir / side / f"{k:02d}.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    renderer.close()
    return len(poses)
