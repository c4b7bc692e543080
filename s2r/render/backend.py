"""The renderer seam: one small interface that PyBullet and MuJoCo both implement.

Everything above it (board layouts and poses, scene layouts, supersampling, lens distortion, ground-truth depth,
noise, outputs) exists once; a backend only draws an ideal pinhole view of a world of textured meshes:

- ``set_world(surfaces)``: hold exactly these :class:`~s2r.render.world.Surface` (OBJ mesh + PNG texture + pose in
  the render world, the profile's LEFT optical frame: x right, y down, z forward, metres);
- ``render(view)``: ``(rgb, z)`` of a :class:`~s2r.render.camera.PinholeView`: (H, W, 3) uint8 RGB and (H, W)
  float32 metric z along the view's optical axis, NaN where nothing was hit.

A :class:`RendererChoice` names the backend (and, for MuJoCo, the user's own MJCF world the boards are inserted
into); it is picklable, so every render job carries it into worker processes.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.render.camera import PinholeView, depth_buffer_to_z, render_pinhole
from s2r.render.world import Surface, set_world

__all__ = ["RENDERERS", "Backend", "RendererChoice", "check_renderer", "get_backend", "render_workers"]

#: Renderer names accepted by ``--renderer``; the first is the default.
RENDERERS = ("pybullet", "mujoco")


class Backend(Protocol):
    """What a renderer provides (see the module docstring for frames and units)."""

    def set_world(self, surfaces: Sequence[Surface]) -> None:
        """Hold exactly ``surfaces`` at their poses."""

    def render(self, view: PinholeView) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """``(rgb, z)`` of ``view``: uint8 RGB and float32 metric z along the optical axis (NaN: nothing hit)."""


@dataclass(frozen=True)
class RendererChoice:
    """Which renderer draws, picklable.

    Attributes:
        name: ``"pybullet"`` (TinyRenderer, flat shading) or ``"mujoco"`` (MuJoCo's OpenGL renderer).
        scene_path: MuJoCo only: the user's MJCF world (its lights, materials, objects) the surfaces are added to.
        scene_camera: MuJoCo only, with a scene: the scene camera whose pose (at the model's initial state) the
            left camera takes; None: the left camera at the scene's origin looking along the scene's +x, +z up.
    """

    name: str = "pybullet"
    scene_path: str | None = None
    scene_camera: str | None = None


def render_workers(choice: RendererChoice, jobs: int | None) -> int | None:
    """Worker processes for render jobs: ``jobs`` for PyBullet, 1 for MuJoCo (it renders in this process: a GL
    context does not survive a fork, and the GL implementation already spreads one frame over the cores)."""
    return 1 if choice.name == "mujoco" else jobs


def check_renderer(choice: RendererChoice, *, probe_gl: bool = False) -> None:
    """Raise RenderError naming the option when the renderer or its scene cannot be used (``probe_gl``: also try
    to create an offscreen GL context, in a child process, as callers that fork render workers must)."""
    if choice.name not in RENDERERS:
        raise RenderError(f"unknown renderer {choice.name!r}", field="--renderer",
                          hint=f"use one of {', '.join(RENDERERS)}")
    if choice.scene_path is not None:
        if choice.name != "mujoco":
            raise RenderError("a scene file needs the MuJoCo renderer", field="--world", hint="add --renderer mujoco")
        if not Path(choice.scene_path).is_file():
            raise RenderError("no such MJCF scene file", path=choice.scene_path, field="--world",
                              hint="pass an existing MuJoCo XML file")
    if choice.scene_camera is not None and choice.scene_path is None:
        raise RenderError("a scene camera needs a scene file", field="--world-camera", hint="add --world SCENE.xml")
    if choice.name == "mujoco":
        from s2r.render.mujoco.backend import check_scene

        # MuJoCo missing, no GL, a bad scene or camera: one line before any work
        check_scene(choice.scene_path, choice.scene_camera, probe_gl=probe_gl)


class PybulletBackend:
    """PyBullet's TinyRenderer (flat, ambient-only shading), one DIRECT connection per process."""

    def set_world(self, surfaces: Sequence[Surface]) -> None:
        """Hold exactly ``surfaces`` (bodies reused when only poses changed)."""
        set_world(surfaces)

    def render(self, view: PinholeView) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """``(rgb, z)`` of ``view``; z from the OpenGL depth buffer, NaN at the far plane."""
        rgb, buffer = render_pinhole(view)
        return rgb, depth_buffer_to_z(buffer, view.near, view.far).astype(np.float32)


_BACKENDS: dict[tuple[int, RendererChoice], Backend] = {}


def get_backend(choice: RendererChoice | None = None) -> Backend:
    """This process's backend for ``choice`` (default PyBullet), created on first use (a forked worker makes
    its own: a GL context does not survive a fork)."""
    choice = choice or RendererChoice()
    key = (os.getpid(), choice)
    if key not in _BACKENDS:
        if any(pid != key[0] for pid, _ in _BACKENDS):
            _BACKENDS.clear()
        if choice.name == "mujoco":
            from s2r.render.mujoco.backend import MujocoBackend

            _BACKENDS[key] = MujocoBackend(choice.scene_path, choice.scene_camera)
        elif choice.name == "pybullet":
            _BACKENDS[key] = PybulletBackend()
        else:
            check_renderer(choice)
    return _BACKENDS[key]
