"""Ground-truth depth scenes rendered through a profile: images, depth and rectified disparity.

Ground truth in the rectified left image is exact: each rectified pixel's ray ``R1^T P1^-1 (u, v, 1)`` is mapped
into the wide pinhole render (or the cube map) of the left camera (R1, P1 from
``s2r.rectification.stereo_rectification(profile, alpha=0.0)``, exactly what the depth pipeline uses), the
render's inverse depth is sampled bilinearly there (exact on planar facets) and converted to the rectified
frame's z: ``Z_rect = Z_left * (R1[2] . (x, y, 1))``. Disparity is ``fx' B / Z_rect - doffs`` (doffs 0 with
CALIB_ZERO_DISPARITY). Depth edges and background are NaN.
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from s2r.fileio import OutputBatch, npy_bytes
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback
from s2r.rectification import stereo_rectification
from s2r.render.backend import RendererChoice, check_renderer, render_workers
from s2r.render.boards.poses import BoardGeometry
from s2r.render.boards.sets import BORDER_SQUARES, board_surface
from s2r.render.layouts import check_distances, scene_layouts
from s2r.render.outputs import clear_numbered, encode_png, numbered_names, remove_stale_numbered
from s2r.render.parallel import run_jobs
from s2r.render.rig import (
    StereoJob,
    check_render_options,
    clip_planes,
    finish_image,
    render_stereo,
    render_stereo_images,
    stereo_setups,
)
from s2r.render.sensor import Capture
from s2r.render.world import Surface
from s2r.sensor.model import SensorModel

__all__ = ["SceneFrame", "render_boards_at", "render_scene", "write_scene"]

F32 = NDArray[np.float32]


@dataclass(frozen=True)
class SceneFrame:
    """One rendered stereo frame with ground truth.

    Attributes:
        name: frame name (``"00"``, ...).
        left, right: (H, W, 3) uint8 BGR images as rendered by each camera (with its distortion).
        depth_m: (H, W) float32 z in metres along the LEFT optical axis, left image, NaN where nothing was hit.
        disparity_rect_px: (H, W) float32 true disparity in the RECTIFIED left image, NaN unknown.
        depth_rect_m: (H, W) float32 true depth along the rectified left axis, rectified left image, NaN unknown.
        description: scene, distance and surfaces (plain values), plus the rectification used.
    """

    name: str
    left: np.ndarray
    right: np.ndarray
    depth_m: np.ndarray
    disparity_rect_px: np.ndarray
    depth_rect_m: np.ndarray
    description: dict[str, Any]


@dataclass(frozen=True)
class _SceneJob:
    stereo: StereoJob
    R1: NDArray[np.float64]
    P1: NDArray[np.float64]
    size: tuple[int, int]
    fb: float  # fx' * B, pixels * metres
    doffs: float


def rectified_inverse_depth(left: Capture, R1: NDArray[np.float64], P1: NDArray[np.float64],
                            size: tuple[int, int]) -> F32:
    """(H, W) inverse depth (1/m) along the rectified left axis at every rectified left pixel; NaN unknown."""
    u, v = np.meshgrid(np.arange(size[0], dtype=np.float64), np.arange(size[1], dtype=np.float64))
    rays = np.linalg.inv(P1[:3, :3]) @ np.vstack([u.ravel(), v.ravel(), np.ones(u.size)])  # rectified frame
    rays = R1.T @ rays  # left optical frame
    x, y = (rays[0] / rays[2]).reshape(u.shape), (rays[1] / rays[2]).reshape(u.shape)
    factor = R1[2, 0] * x + R1[2, 1] * y + R1[2, 2]
    inv_left = left.inverse_z_at(x, y)
    return np.asarray(inv_left / factor, dtype=np.float32)


def _render_frame(job: _SceneJob) -> tuple[NDArray[np.uint8], NDArray[np.uint8], F32, F32, F32]:
    left, right = render_stereo(job.stereo)
    inv_rect = rectified_inverse_depth(left, job.R1, job.P1, job.size)
    rng = np.random.default_rng([job.stereo.seed, job.stereo.index])
    return (
        finish_image(left.rgb, gain=1.0, noise_sigma=job.stereo.noise_sigma, rng=rng, sensor=job.stereo.sensor),
        finish_image(right.rgb, gain=job.stereo.right_gain, noise_sigma=job.stereo.noise_sigma, rng=rng,
                     sensor=job.stereo.sensor),
        left.depth_m(),
        (1.0 / inv_rect).astype(np.float32),
        (np.float32(job.fb) * inv_rect - np.float32(job.doffs)).astype(np.float32),
    )


def render_scene(
    profile: StereoProfile, *, scene: str = "planes", distances_m: Sequence[float] = (0.5, 1.0, 2.0, 3.0, 5.0),
    supersample: int = 2, seed: int = 0, noise_sigma: float = 0.0, jobs: int | None = None,
    progress: ProgressCallback | None = None, right_gain: float = 1.0, sensor: SensorModel | None = None,
    renderer: RendererChoice | None = None,
) -> list[SceneFrame]:
    """Render ``scene`` ("planes", "slanted", "span" or "room") through ``profile`` with exact ground truth.

    "planes": one fronto-parallel speckle plane per distance (metres, left z) filling the view; "slanted":
    one slanted plane through (0, 0, d) per distance; "span": one plane through (0, 0, d) per distance tilted
    so its depth grows by ``SPAN_RATIO`` (1.5) across the image width, sampling every sub-pixel phase; "room":
    one frame of a textured box room (back wall 0.5 m beyond the farthest distance) with a textured box at each
    distance. See the module docstring for how the rectified ground truth is computed. ``right_gain`` scales
    the right image's grey levels; ``sensor`` (default the profile's own ``sensor:`` section) blurs and adds noise
    to both images (:mod:`s2r.sensor`). ``renderer`` picks the backend (default PyBullet).
    """
    renderer = renderer or RendererChoice()
    check_renderer(renderer)
    check_render_options(supersample=supersample, noise_sigma=noise_sigma, right_gain=right_gain)
    sensor = profile.sensor if sensor is None else sensor
    near, far = clip_planes(profile)
    distances = check_distances(distances_m, near, far)
    rect = stereo_rectification(profile, alpha=0.0)
    left_setup, right_setup = stereo_setups(profile, supersample=supersample)
    rect_info = {"alpha": 0.0, "fx_px": rect.fx_px, "baseline_m": rect.baseline_m, "doffs_px": rect.doffs_px}
    with tempfile.TemporaryDirectory(prefix="s2r-scene-") as tmp:
        layouts = scene_layouts(profile, Path(tmp), scene=scene, distances_m=distances, seed=seed)
        jobs_list = [
            _SceneJob(StereoJob(left_setup, right_setup, surfaces, noise_sigma, right_gain, seed, k, renderer,
                                sensor),
                      rect.R1, rect.P1, rect.image_size, rect.fx_px * rect.baseline_m, rect.doffs_px)
            for k, (surfaces, _) in enumerate(layouts)
        ]
        results = run_jobs(_render_frame, jobs_list, jobs=render_workers(renderer, jobs), progress=progress,
                           label=f"render {scene}")
    frames = []
    for name, (_, desc), (left, right, depth, depth_rect, disp) in zip(numbered_names(len(layouts)), layouts,
                                                                      results, strict=True):
        description = {**desc, "profile": profile.name, "renderer": renderer.name, "supersample": supersample,
                       "seed": seed, "noise_sigma": noise_sigma, "right_gain": right_gain, "rectification": rect_info,
                       **({} if sensor is None else {"sensor": sensor.model_dump(mode="json", exclude_none=True)})}
        frames.append(SceneFrame(name, left, right, depth, disp, depth_rect, description))
    return frames


def render_boards_at(
    profile: StereoProfile, poses: Sequence[NDArray[np.float64]], *, pattern: tuple[int, int], square_m: float,
    supersample: int = 2, seed: int = 0, noise_sigma: float = 0.0, jobs: int | None = None,
    progress: ProgressCallback | None = None, sensor: SensorModel | None = None,
    renderer: RendererChoice | None = None,
) -> list[tuple[NDArray[np.uint8], NDArray[np.uint8]]]:
    """Render a chessboard (``pattern`` inner corners, ``square_m`` squares, the calibration boards' margin) at each
    pose ``T_left_board`` (4x4, board frame -> LEFT optical frame, metres; origin at the first inner corner, x along
    the columns, y along the rows) through ``profile``: one (left, right) BGR uint8 pair per pose (``sensor``, default
    the profile's own ``sensor:`` section: its blur and noise on both images; drawn by ``renderer``, default
    PyBullet)."""
    renderer = renderer or RendererChoice()
    check_renderer(renderer)
    check_render_options(supersample=supersample, noise_sigma=noise_sigma)
    sensor = profile.sensor if sensor is None else sensor
    board = BoardGeometry((int(pattern[0]), int(pattern[1])), float(square_m), BORDER_SQUARES)
    left_setup, right_setup = stereo_setups(profile, supersample=supersample)
    with tempfile.TemporaryDirectory(prefix="s2r-boards-at-") as tmp:
        mesh, texture = board_surface(Path(tmp), board)
        jobs_list = [StereoJob(left_setup, right_setup, (Surface(mesh, texture, np.asarray(T, np.float64)),),
                               noise_sigma, 1.0, seed, k, renderer, sensor) for k, T in enumerate(poses)]
        return list(run_jobs(render_stereo_images, jobs_list, jobs=render_workers(renderer, jobs), progress=progress,
                          label="render boards"))


def write_scene(frames: Sequence[SceneFrame], out_dir: str | Path, *, force: bool = False) -> Path:
    """Write frames as ``left/NN.png``, ``right/NN.png``, ``depth/NN.npy`` (float32 m, NaN),
    ``disparity/NN.npy`` (float32 px, rectified left), ``depth_rect/NN.npy`` and ``scene.yaml``.

    Refuses a folder that holds files unless ``force``. Returns the folder.
    """
    subdirs = ("left", "right", "depth", "disparity", "depth_rect")
    out = clear_numbered(out_dir, subdirs, force=force)
    entries = []
    with OutputBatch(force=True, root=out) as batch:  # the whole scene, or nothing
        for f in frames:
            encode_png(out / "left" / f"{f.name}.png", f.left, batch=batch)
            encode_png(out / "right" / f"{f.name}.png", f.right, batch=batch)
            for folder, array in (("depth", f.depth_m), ("disparity", f.disparity_rect_px),
                                  ("depth_rect", f.depth_rect_m)):
                batch.add_bytes(out / folder / f"{f.name}.npy", npy_bytes(np.asarray(array, dtype=np.float32)))
            entries.append({"name": f.name, "left": f"left/{f.name}.png", "right": f"right/{f.name}.png",
                            "depth": f"depth/{f.name}.npy", "disparity": f"disparity/{f.name}.npy",
                            "depth_rect": f"depth_rect/{f.name}.npy", "description": f.description})
        text = yaml.safe_dump({"format": "s2r-render-scene", "schema_version": 1, "frames": entries},
                              sort_keys=False)
        batch.add_text(out / "scene.yaml", "# s2r rendered scene: ground truth in metres and pixels\n" + text)
        written = batch.publish()
    remove_stale_numbered(out, subdirs, keep=written)
    return out
