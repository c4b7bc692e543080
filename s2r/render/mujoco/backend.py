"""MuJoCo as a render backend (the only module of s2r that imports ``mujoco``).

Conventions (measured by rendering, pinned by tests/render/test_mujoco.py):

- A MuJoCo camera looks along its frame's -z with +y up: its frame is the OpenCV optical frame rotated by pi
  about x, ``R_world_mjcam = R_world_optical @ diag(1, -1, -1)``.
- A camera with ``resolution="W H"``, ``sensorsize``, ``focalpixel="fx fy"`` and ``principalpixel="px py"``
  renders OpenCV's ``K`` with that ``fx``, ``fy`` and ``cx = (W - 1) / 2 - px``, ``cy = (H - 1) / 2 - py``
  (0-based pixel centres; both offsets enter with a minus sign). The backend sets the camera's intrinsics in
  length units, ``focal = f * pixel``, ``principal = p * pixel`` with a nominal ``pixel`` pitch.
- The depth buffer (``Renderer.enable_depth_rendering``) is metric z along the optical axis (not the distance
  along the ray); the far plane means nothing was hit (NaN here).
- Clip planes are ``znear * extent`` and ``zfar * extent``: the backend sets ``znear`` / ``zfar`` from the view.

MuJoCo renders in the calling process (never in forked workers: an EGL/OSMesa context does not survive a fork,
and the GL implementation already uses every core). Headless: ``MUJOCO_GL`` is set to ``egl`` when unset and no
display exists (``osmesa`` when only OSMesa is installed, or when the GL probe finds EGL unusable and OSMesa
renders); it must be chosen before ``mujoco`` is imported.
Surfaces are the same OBJ meshes and PNG textures the PyBullet backend loads (MuJoCo reads the OBJ's texture
coordinates; faces are culled from behind, as in PyBullet).
Each surface sits on a mocap body, so moving boards between views does not recompile the model.
"""

from __future__ import annotations

import ctypes.util
import importlib.util
import logging
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from s2r.errors import RenderError, SourceError
from s2r.executor import child_environment
from s2r.render.camera import PinholeView
from s2r.render.mujoco.world import read_world
from s2r.render.world import Surface
from s2r.sources.isolation import Limits, run_limited

__all__ = ["COMPILE_LIMITS", "MAX_WORLD_M", "MujocoBackend", "check_mujoco", "check_scene", "gl_unavailable_reason",
           "load_spec", "optical_to_mujoco_quat", "scene_camera_pose"]

log = logging.getLogger("s2r.render")

FloatArray = NDArray[np.float64]
#: Optical frame -> MuJoCo camera frame (and back): a rotation by pi about x.
FLIP = np.diag([1.0, -1.0, -1.0])
#: Nominal pixel pitch (metres) of the render camera's sensor; only ratios matter.
_PIXEL_M = 1e-6
#: Depth values at or above this share of the far plane count as nothing hit.
_BACKGROUND_FRACTION = 0.999
#: The left camera at the scene's origin looking along +x with +z up (a robot's forward axis).
#: Farthest a world camera may sit from the world's origin (metres): past it float32 GL loses the scene.
MAX_WORLD_M = 1e4
#: Limits of the child process that compiles a world once before it is rendered.
COMPILE_LIMITS = Limits(cpu_s=20, memory_bytes=2 << 30, wall_s=60.0)
_DEFAULT_SCENE_POSE = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, 0.0],
                                [0.0, 0.0, 0.0, 1.0]])


_CHOSEN: dict[str, str] = {}


def _use_gl(platform: str) -> None:
    os.environ["MUJOCO_GL"] = platform
    os.environ["PYOPENGL_PLATFORM"] = platform
    _CHOSEN["platform"] = platform


def _select_gl() -> None:
    """Choose a headless GL platform before ``mujoco`` is imported (respecting a user's MUJOCO_GL or display):
    EGL, or OSMesa where it is the only one installed."""
    if _CHOSEN or os.environ.get("MUJOCO_GL") or os.environ.get("DISPLAY"):
        return
    only_osmesa = ctypes.util.find_library("EGL") is None and ctypes.util.find_library("OSMesa") is not None
    _use_gl("osmesa" if only_osmesa else "egl")


def _import_mujoco() -> Any:
    """``mujoco``, its GL platform chosen and its warnings sent to the ``s2r.render`` log (debug level) instead of
    the MUJOCO_LOG.TXT it would write into the working directory."""
    _select_gl()
    try:
        import mujoco
    except ImportError as exc:
        raise RenderError(f"MuJoCo is not installed ({exc})", field="--renderer",
                          hint="pip install 's2r[mujoco]' or use --renderer pybullet") from exc
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(lambda message: log.debug("MuJoCo: %s", message))
    return mujoco


_GL_STATUS: dict[str, str | None] = {}
_PROBE = """
import mujoco
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
mujoco.Renderer(model, 8, 8).close()
"""
_PROBE_TIMEOUT_S = 60.0


def gl_unavailable_reason() -> str | None:
    """None when MuJoCo can render offscreen here, else why not (one line).

    The probe runs in a child process: a GL context created in this process would not survive the fork of a
    worker pool started afterwards (the workers hang in EGL).
    """
    if "status" not in _GL_STATUS:
        if importlib.util.find_spec("mujoco") is None:
            _GL_STATUS["status"] = "MuJoCo is not installed (pip install 's2r[mujoco]')"
            return _GL_STATUS["status"]
        _select_gl()
        reason = _probe(os.environ.get("MUJOCO_GL", ""))
        fallback = _CHOSEN.get("platform") == "egl" and "mujoco" not in sys.modules
        if reason is not None and fallback and ctypes.util.find_library("OSMesa") is not None \
                and _probe("osmesa") is None:  # EGL installed but unusable (no device): OSMesa renders
            _use_gl("osmesa")
            reason = None
        _GL_STATUS["status"] = reason
    return _GL_STATUS["status"]


def _probe(platform: str) -> str | None:
    """Try an 8x8 offscreen render with ``MUJOCO_GL=platform`` in a child process; None or why it failed."""
    env = child_environment({**os.environ, "MUJOCO_GL": platform, "PYOPENGL_PLATFORM": platform} if platform
                            else os.environ)
    try:
        done = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                              timeout=_PROBE_TIMEOUT_S, env=env, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return " ".join(f"{type(exc).__name__}: {exc}".split())
    if done.returncode == 0:
        return None
    lines = [line for line in done.stderr.strip().splitlines() if line.strip()]
    return f"MUJOCO_GL={platform or 'default'}: {lines[-1] if lines else f'exit {done.returncode}'}"


def check_mujoco() -> None:
    """Raise RenderError when MuJoCo is missing or cannot create an offscreen GL context."""
    reason = gl_unavailable_reason()
    if reason is not None:
        raise RenderError(f"MuJoCo cannot render offscreen here ({reason})", field="--renderer",
                          hint="install the mujoco extra and EGL or OSMesa (MUJOCO_GL=egl|osmesa), or use pybullet")


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split())


def load_spec(mj: Any, scene_path: str | None) -> Any:
    """The MjSpec of ``scene_path`` as s2r read it (:func:`s2r.render.mujoco.world.read_world`: includes and assets
    confined and bounded, MuJoCo opens no file), or an empty world lit flat (ambient only)."""
    if scene_path is None:
        spec = mj.MjSpec()
        spec.visual.headlight.ambient = [1.0, 1.0, 1.0]
        spec.visual.headlight.diffuse = [0.0, 0.0, 0.0]
        spec.visual.headlight.specular = [0.0, 0.0, 0.0]
        return spec
    world = read_world(scene_path)
    try:
        return mj.MjSpec.from_string(world.xml, assets=world.assets)
    except Exception as exc:  # MuJoCo raises plain ValueError/RuntimeError for every parse problem
        raise RenderError(f"MuJoCo cannot load the scene ({_one_line(exc)})", path=scene_path, field="--world",
                          hint="check the file with MuJoCo's simulate or compile()") from exc


def _compiled_scene(mj: Any, scene_path: str) -> Any:
    """The scene's MjModel as MuJoCo compiles it; RenderError naming the file when it does not."""
    spec = load_spec(mj, scene_path)
    try:
        return spec.compile()
    except Exception as exc:  # MuJoCo raises plain ValueError for every compile problem
        raise RenderError(f"MuJoCo cannot compile the scene ({_one_line(exc)})", path=scene_path, field="--world",
                          hint="check the file") from exc


def scene_camera_pose(mj: Any, scene_path: str, camera: str) -> FloatArray:
    """4x4 pose (metres) of the OpenCV optical frame of ``camera`` in the scene's world, at the initial state."""
    model = _compiled_scene(mj, scene_path)
    cam = mj.mj_name2id(model, mj.mjtObj.mjOBJ_CAMERA, camera)
    if cam < 0:
        names = [model.camera(i).name for i in range(model.ncam)]
        raise RenderError(f"no camera named {camera!r}", path=scene_path, field="--world-camera",
                          hint=f"cameras in the scene: {', '.join(names) or 'none'}")
    data = mj.MjData(model)
    mj.mj_forward(model, data)
    T = np.eye(4)
    T[:3, :3] = data.cam_xmat[cam].reshape(3, 3) @ FLIP
    T[:3, 3] = data.cam_xpos[cam]
    if not (np.isfinite(T).all() and np.abs(T[:3, 3]).max() <= MAX_WORLD_M):
        raise RenderError(f"camera {camera!r} sits at {np.array2string(T[:3, 3], precision=3)} m: not a finite "
                          f"position within {MAX_WORLD_M:g} m of the world's origin", path=scene_path,
                          field="--world-camera", hint="fix the camera's (or its bodies') pos and quat")
    return T


def check_scene(scene_path: str | None, camera: str | None, *, probe_gl: bool) -> None:
    """Raise RenderError when MuJoCo is missing, the scene (and its camera) cannot be used, or (``probe_gl``, in a
    child process) no offscreen GL context can be created; no GL context is created in this process.

    The scene is read here (:func:`s2r.render.mujoco.world.read_world`) and compiled once in a child process under
    :data:`COMPILE_LIMITS`, so what no attribute bounds (a mesh's hull, ``<replicate>``) cannot exhaust this one."""
    mj = _import_mujoco()
    if scene_path is not None:  # first (it reads files only): in this process, so every compile sees these bytes
        read_world(scene_path)
    if probe_gl:
        check_mujoco()
    if scene_path is None:
        return
    try:
        run_limited(lambda: _check_compiles(mj, scene_path, camera), path=Path(scene_path),
                    what="compiling the world", limits=COMPILE_LIMITS, field="--world",
                    hint="a world too large to render (meshes, replicated bodies); simplify it")
    except SourceError as exc:
        raise RenderError(exc.message, path=exc.path, field=exc.field, hint=exc.hint) from None


def _check_compiles(mj: Any, scene_path: str, camera: str | None) -> None:
    """Compile the scene (and place its camera): the work :func:`check_scene` runs in a limited child."""
    if camera is not None:
        scene_camera_pose(mj, scene_path, camera)
    else:
        _compiled_scene(mj, scene_path)


def optical_to_mujoco_quat(R_world_optical: FloatArray) -> list[float]:
    """MuJoCo quaternion (w, x, y, z) of a camera whose OpenCV optical frame has orientation ``R_world_optical``."""
    q = Rotation.from_matrix(np.asarray(R_world_optical, np.float64) @ FLIP).as_quat()  # x, y, z, w
    return [float(q[3]), float(q[0]), float(q[1]), float(q[2])]


def _quat_wxyz(R: FloatArray) -> list[float]:
    q = Rotation.from_matrix(R).as_quat()
    return [float(q[3]), float(q[0]), float(q[1]), float(q[2])]


class MujocoBackend:
    """MuJoCo's offscreen OpenGL renderer behind the :class:`s2r.render.backend.Backend` interface.

    Args:
        scene_path: an MJCF world to render inside (its lights, materials and objects kept); None: an empty
            world with flat, ambient-only light (like the PyBullet backend).
        scene_camera: a camera of the scene whose pose (model's initial state) the left camera takes; None: the
            left camera at the scene's origin looking along the scene's +x with +z up. Without a scene the render
            world is MuJoCo's world.
    """

    def __init__(self, scene_path: str | None, scene_camera: str | None) -> None:
        self.mujoco = _import_mujoco()
        self.scene_path = scene_path
        self.scene_camera = scene_camera
        self.T_scene_world = _DEFAULT_SCENE_POSE.copy() if scene_path else np.eye(4)
        self._key: tuple[tuple[str, str], ...] | None = None
        self._model: Any = None
        self._data: Any = None
        self._renderers: dict[tuple[int, int], Any] = {}

    def _spec(self) -> Any:
        return load_spec(self.mujoco, self.scene_path)

    def _build(self, surfaces: Sequence[Surface]) -> None:
        """Compile the scene (or an empty world) with one mocap body per surface and one render camera."""
        mj = self.mujoco
        if self.scene_path is not None and self.scene_camera is not None:
            self.T_scene_world = scene_camera_pose(mj, self.scene_path, self.scene_camera)
        spec = self._spec()
        names: dict[str, str] = {}
        for path in dict.fromkeys([s.texture_path for s in surfaces]):
            names[path] = name = f"s2r_texture_{len(names)}"
            spec.add_texture(name=name, type=mj.mjtTexture.mjTEXTURE_2D, file=path)
            mat = spec.add_material(name=name, specular=0.0, shininess=0.0, reflectance=0.0)
            mat.textures[mj.mjtTextureRole.mjTEXROLE_RGB] = name
        meshes: dict[str, str] = {}
        for k, s in enumerate(surfaces):
            if s.mesh_path not in meshes:
                meshes[s.mesh_path] = f"s2r_mesh_{len(meshes)}"
                spec.add_mesh(name=meshes[s.mesh_path], file=s.mesh_path,
                              inertia=mj.mjtMeshInertia.mjMESH_INERTIA_SHELL)
            body = spec.worldbody.add_body(name=f"s2r_surface_{k}", mocap=True)
            body.add_geom(type=mj.mjtGeom.mjGEOM_MESH, meshname=meshes[s.mesh_path], material=names[s.texture_path],
                          contype=0, conaffinity=0, mass=0.0)
        spec.worldbody.add_camera(name="s2r_render", resolution=[64, 64], sensor_size=[64 * _PIXEL_M, 64 * _PIXEL_M],
                                  focal_pixel=[64.0, 64.0], principal_pixel=[0.0, 0.0])
        try:
            self._model = spec.compile()
        except Exception as exc:
            raise RenderError(f"MuJoCo cannot compile the render world ({_one_line(exc)})",
                              path=self.scene_path, hint="check the scene file") from exc
        self._data = mj.MjData(self._model)
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers = {}

    def set_world(self, surfaces: Sequence[Surface]) -> None:
        """Hold exactly ``surfaces``: recompile when the meshes or textures change, else move the mocap bodies."""
        key = tuple((s.mesh_path, s.texture_path) for s in surfaces)
        if key != self._key:
            self._build(surfaces)
            self._key = key
        model = self._model
        for k, s in enumerate(surfaces):
            mocap = model.body_mocapid[model.body(f"s2r_surface_{k}").id]
            T = self.T_scene_world @ np.asarray(s.T_world_obj, np.float64)
            self._data.mocap_pos[mocap] = T[:3, 3]
            self._data.mocap_quat[mocap] = _quat_wxyz(T[:3, :3])

    def _renderer(self, width: int, height: int) -> Any:
        if (width, height) not in self._renderers:
            vis = self._model.vis.global_
            vis.offwidth, vis.offheight = max(int(vis.offwidth), width), max(int(vis.offheight), height)
            try:
                self._renderers[(width, height)] = self.mujoco.Renderer(self._model, height, width)
            except Exception as exc:  # no EGL/OSMesa, no display: one line, not a GL traceback
                raise RenderError(f"MuJoCo cannot render offscreen here ({_one_line(exc)}; "
                                  f"MUJOCO_GL={os.environ.get('MUJOCO_GL')})", field="--renderer",
                                  hint="install EGL or OSMesa (MUJOCO_GL=egl|osmesa), or use --renderer pybullet"
                                  ) from exc
        return self._renderers[(width, height)]

    def _place_camera(self, view: PinholeView) -> None:
        model = self._model
        cam = model.camera("s2r_render").id
        K, w, h = view.K, view.width, view.height
        px, py = (w - 1) / 2.0 - K[0, 2], (h - 1) / 2.0 - K[1, 2]
        model.cam_resolution[cam] = [w, h]
        model.cam_sensorsize[cam] = [w * _PIXEL_M, h * _PIXEL_M]
        model.cam_intrinsic[cam] = [K[0, 0] * _PIXEL_M, K[1, 1] * _PIXEL_M, px * _PIXEL_M, py * _PIXEL_M]
        T_world_cam = np.linalg.inv(np.asarray(view.T_cam_world, np.float64))
        T = self.T_scene_world @ T_world_cam
        model.cam_pos[cam] = T[:3, 3]
        model.cam_quat[cam] = optical_to_mujoco_quat(T[:3, :3])
        model.vis.map.znear = view.near / model.stat.extent
        model.vis.map.zfar = view.far / model.stat.extent
        self.mujoco.mj_kinematics(model, self._data)
        self.mujoco.mj_camlight(model, self._data)

    def render(self, view: PinholeView) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        """``(rgb, z)`` of ``view`` (see the module docstring); z is NaN where nothing was hit."""
        if self._model is None:
            self.set_world([])
        self._place_camera(view)
        renderer = self._renderer(view.width, view.height)
        renderer.update_scene(self._data, camera="s2r_render")
        rgb = np.ascontiguousarray(renderer.render(), dtype=np.uint8)
        renderer.enable_depth_rendering()
        try:
            renderer.update_scene(self._data, camera="s2r_render")
            z = np.array(renderer.render(), dtype=np.float32)
        finally:
            renderer.disable_depth_rendering()
        z[~(z < _BACKGROUND_FRACTION * view.far)] = np.nan
        return rgb, z
