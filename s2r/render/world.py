"""The PyBullet world of one render job: textured meshes (quads, boxes) placed in the left optical frame.

Meshes are written as small OBJ files with explicit texture coordinates, so a texture's pixel (col, row)
lands exactly where intended: ``u = col / width``, ``v = 1 - row / height`` (OpenGL's v runs upwards).
TinyRenderer culls back faces: a face is visible from the side its right-hand-rule normal points to, so
quads are written from corners listed top-left, top-right, bottom-right, bottom-left AS SEEN BY THE VIEWER.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from s2r.render._pybullet import p
from s2r.render.camera import client, pose_to_pybullet

__all__ = ["Surface", "box_faces", "set_world", "write_mesh"]

FloatArray = NDArray[np.float64]

#: One textured quad: four corners (4, 3) in the object frame, listed TL, TR, BR, BL as seen from the front,
#: and the texture rectangle (u0, v0, u1, v1) in [0, 1] that covers it (u0, v0 = top-left).
Quad = tuple[FloatArray, tuple[float, float, float, float]]


@dataclass(frozen=True)
class Surface:
    """A textured mesh placed in the world (the left optical frame, metres).

    Attributes:
        mesh_path: OBJ file written by :func:`write_mesh`.
        texture_path: PNG texture.
        T_world_obj: 4x4 pose of the mesh's frame in the world.
    """

    mesh_path: str
    texture_path: str
    T_world_obj: FloatArray


def write_mesh(path: str | Path, quads: Sequence[Quad]) -> str:
    """Write quads as an OBJ mesh (two front-facing triangles each, explicit UVs); returns the absolute path."""
    lines: list[str] = []
    for k, (corners, (u0, v0, u1, v1)) in enumerate(quads):
        c = np.asarray(corners, dtype=np.float64).reshape(4, 3)
        lines += [f"v {x:.9f} {y:.9f} {z:.9f}" for x, y, z in c]
        # OBJ v runs upwards from the texture's bottom row; (u0, v0) is the texture's top-left.
        for u, v in ((u0, v0), (u1, v0), (u1, v1), (u0, v1)):
            lines.append(f"vt {u:.9f} {1.0 - v:.9f}")
        normal = np.cross(c[2] - c[0], c[1] - c[0])
        normal = normal / np.linalg.norm(normal)
        lines.append(f"vn {normal[0]:.9f} {normal[1]:.9f} {normal[2]:.9f}")
        a, b, cc, d = (4 * k + i for i in range(1, 5))
        lines.append(f"f {a}/{a}/{k + 1} {cc}/{cc}/{k + 1} {b}/{b}/{k + 1}")
        lines.append(f"f {a}/{a}/{k + 1} {d}/{d}/{k + 1} {cc}/{cc}/{k + 1}")
    out = Path(path).resolve()
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(out)


def box_faces(size_m: tuple[float, float, float], *, inward: bool = False) -> list[Quad]:
    """The six faces of a box centred on its frame (size in metres), outward- (or inward-) facing.

    Each face takes one tile of a 3x2 texture atlas, so a single non-repeating texture covers the box.
    """
    hx, hy, hz = (s / 2.0 for s in size_m)
    corners = np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])

    def idx(sx: int, sy: int, sz: int) -> int:
        return (sx > 0) * 4 + (sy > 0) * 2 + (sz > 0)

    # Faces as (TL, TR, BR, BL) seen from OUTSIDE the box.
    faces = [
        [idx(-1, -1, -1), idx(1, -1, -1), idx(1, 1, -1), idx(-1, 1, -1)],  # -z face
        [idx(1, -1, 1), idx(-1, -1, 1), idx(-1, 1, 1), idx(1, 1, 1)],  # +z face
        [idx(-1, -1, 1), idx(-1, -1, -1), idx(-1, 1, -1), idx(-1, 1, 1)],  # -x face
        [idx(1, -1, -1), idx(1, -1, 1), idx(1, 1, 1), idx(1, 1, -1)],  # +x face
        [idx(-1, -1, 1), idx(1, -1, 1), idx(1, -1, -1), idx(-1, -1, -1)],  # -y face (top, y down)
        [idx(-1, 1, -1), idx(1, 1, -1), idx(1, 1, 1), idx(-1, 1, 1)],  # +y face (bottom)
    ]
    quads: list[Quad] = []
    for k, face in enumerate(faces):
        order = [face[1], face[0], face[3], face[2]] if inward else face
        col, row = k % 3, k // 3
        quads.append((corners[order], (col / 3.0, row / 2.0, (col + 1) / 3.0, (row + 1) / 2.0)))
    return quads


_STATE: dict[str, object] = {"key": None, "bodies": []}


def set_world(surfaces: Sequence[Surface]) -> None:
    """Make the PyBullet world hold exactly ``surfaces`` at their poses.

    Bodies are reused when the same meshes and textures were loaded by the previous call in this
    process (board views only move the board), otherwise the world is rebuilt.
    """
    cid = client()
    key = (os.getpid(), cid, tuple((s.mesh_path, s.texture_path) for s in surfaces))  # forks rebuild
    if _STATE["key"] != key:
        p.resetSimulation(physicsClientId=cid)
        textures: dict[str, int] = {}
        bodies: list[int] = []
        for s in surfaces:
            shape = p.createVisualShape(p.GEOM_MESH, fileName=s.mesh_path, physicsClientId=cid)
            body = p.createMultiBody(baseMass=0, baseVisualShapeIndex=shape, physicsClientId=cid)
            if s.texture_path not in textures:
                textures[s.texture_path] = p.loadTexture(s.texture_path, physicsClientId=cid)
            p.changeVisualShape(body, -1, textureUniqueId=textures[s.texture_path], physicsClientId=cid)
            bodies.append(body)
        _STATE["key"], _STATE["bodies"] = key, bodies
    bodies_now: list[int] = _STATE["bodies"]  # type: ignore[assignment]
    for body, s in zip(bodies_now, surfaces, strict=True):
        pos, quat = pose_to_pybullet(s.T_world_obj)
        p.resetBasePositionAndOrientation(body, pos, quat, physicsClientId=cid)
