"""Synthetic stereo calibration sets: chessboard views rendered through a profile, with their true poses.

Output layout (what ``s2r calibrate`` reads): ``left/NN.png``, ``right/NN.png`` (BGR, the profile's image
size, its distortion applied) and ``truth.yaml`` holding the profile used, the board and every pose as
``T_left_board`` (board frame -> LEFT optical frame, metres; see :mod:`s2r.render.boards.poses` for the board frame).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from s2r.errors import RenderError
from s2r.fileio import OutputBatch
from s2r.profile import StereoProfile
from s2r.progress import ProgressCallback
from s2r.render.backend import RendererChoice, check_renderer, render_workers
from s2r.render.boards.poses import BoardGeometry, sample_board_poses
from s2r.render.boards.targets import TargetLayout, cut_views, target_layout
from s2r.render.outputs import check_output_dir, clear_numbered, encode_png, numbered_names, remove_stale_numbered
from s2r.render.parallel import run_jobs
from s2r.render.rig import StereoJob, check_render_options, render_stereo_images, stereo_setups
from s2r.render.textures import checkerboard_texture, write_png
from s2r.render.world import Surface, write_mesh
from s2r.sensor.model import SensorModel
from s2r.targets import MAX_SQUARE_M, AnyTarget, CheckerboardTarget

#: Share of views cut by the image edge for targets identified corner by corner (ChArUco, AprilGrid).
DEFAULT_CUT_SHARE = 0.4

__all__ = ["BORDER_SQUARES", "BoardSet", "board_surface", "render_board_set"]

#: Light margin around the squares, in squares (a quiet zone for the chessboard detector).
BORDER_SQUARES = 1.0
#: Texture resolution per board square (checker edges fall on texel boundaries, so they are exact).
TEXELS_PER_SQUARE = 64


@dataclass(frozen=True)
class BoardSet:
    """A rendered calibration set on disk.

    Attributes:
        out_dir: the set's folder.
        left_paths, right_paths: the view images, in view order.
        truth_path: ``truth.yaml``.
        poses: 4x4 ``T_left_board`` per view (board frame -> left optical frame, metres).
    """

    out_dir: Path
    left_paths: list[Path]
    right_paths: list[Path]
    truth_path: Path
    poses: list[np.ndarray]


def board_surface(tmp_dir: Path, board: BoardGeometry, layout: TargetLayout | None = None) -> tuple[str, str]:
    """Write the board's texture (PNG) and mesh (OBJ, board frame) into ``tmp_dir``; return their paths
    (``layout``: a file-described target's texture and extent instead of the chessboard)."""
    texture = checkerboard_texture(board.pattern, texels_per_square=TEXELS_PER_SQUARE,
                                   border_squares=board.border_squares) if layout is None else layout.texture
    x0, y0, x1, y1 = board.extent_m if layout is None else layout.extent_m
    corners = np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])
    mesh = write_mesh(tmp_dir / "board.obj", [(corners, (0.0, 0.0, 1.0, 1.0))])
    return mesh, write_png(tmp_dir / "board.png", texture)


#: Most views one render call draws: calibration needs 10-50; a billion would render for days.
MAX_VIEWS = 1000


def _check_board(pattern: tuple[int, int], square_m: float, views: int) -> None:
    if len(pattern) != 2 or min(pattern) < 2:
        raise RenderError(f"pattern must be two counts of inner corners >= 2, got {pattern}", field="pattern",
                          hint="e.g. --pattern 9x6")
    if not 0 < square_m <= MAX_SQUARE_M:
        raise RenderError(f"square size must be 0-{MAX_SQUARE_M:g} m, got {square_m}", field="square_m",
                          hint="e.g. --square 0.025")
    if not 1 <= views <= MAX_VIEWS:
        raise RenderError(f"views must be 1-{MAX_VIEWS}, got {views}", field="views", hint="e.g. --views 20")


def _truth(profile: StereoProfile, board: BoardGeometry, names: list[str], poses: list[NDArray[np.float64]],
           options: dict[str, Any], target: AnyTarget | None = None, cut: list[bool] | None = None) -> str:
    data = {
        "format": "s2r-render-boards",
        "schema_version": 1,
        "board_frame": "origin at the first inner corner, x along pattern columns, y along rows, z into the board",
        "pattern": list(board.pattern),
        "square_m": board.square_m,
        "border_squares": board.border_squares,
        **options,
        "profile": profile.model_dump(mode="json", exclude_none=True),
        "views": [
            {"name": n, "left": f"left/{n}.png", "right": f"right/{n}.png", "T_left_board": T.tolist()}
            for n, T in zip(names, poses, strict=True)
        ],
    }
    if target is not None:  # T_left_board is then the target's own frame (s2r.targets), cut views marked
        data["board_frame"] = "the target's frame (s2r.targets): " + target.describe()
        data["target"] = target.model_dump(mode="json")
        data["views_cut_by_edge"] = [n for n, c in zip(names, cut or [], strict=False) if c]
    return "# s2r rendered calibration set: ground truth (metres, OpenCV optical frames)\n" + yaml.safe_dump(
        data, sort_keys=False, width=120)


def render_board_set(
    profile: StereoProfile, out_dir: str | Path, *, views: int = 20, pattern: tuple[int, int] = (9, 6),
    square_m: float = 0.025, seed: int = 0, supersample: int = 2, noise_sigma: float = 0.0,
    jobs: int | None = None, force: bool = False, progress: ProgressCallback | None = None,
    right_gain: float = 1.0, target: AnyTarget | None = None, cut_share: float | None = None,
    sensor: SensorModel | None = None,
    renderer: RendererChoice | None = None, temporary: bool = False,
) -> BoardSet:
    """Render a stereo calibration set of ``views`` chessboard views through ``profile`` into ``out_dir``.

    Args:
        profile: the stereo profile whose cameras (K, distortion, size, extrinsics, clip planes) render.
        out_dir: output folder; refused if it holds files unless ``force``.
        views: number of board poses.
        pattern: inner corners (columns, rows).
        square_m: square size in metres.
        seed: pose sampling and noise seed (same seed, same set).
        supersample: render at this factor and average down (TinyRenderer has no anti-aliasing).
        noise_sigma: image noise, grey levels: sigma in the grey image before rounding (the one meaning:
            :func:`s2r.render.rig.finish_image`).
        jobs: worker processes (default the usable cores, ``s2r.executor.usable_cores``; 1 renders in this process).
        force: reuse a non-empty ``out_dir`` (replaces the set's own numbered files).
        progress: ``callback(done, total, label)``.
        right_gain: exposure/gain of the right camera relative to the left.
        target: a file-described board (ChArUco, Kalibr AprilGrid or checkerboard) instead of ``pattern``.
        cut_share: share of views moved so the image edge cuts the board (default 0.4 with a ChArUco or
            AprilGrid target, whose corners are identified one by one; 0 otherwise).
        sensor: a sensor model whose blur and grey-level noise both images get (:mod:`s2r.sensor`); default
            the profile's own ``sensor:`` section (none: perfect images).
        renderer: the backend that draws (default PyBullet; :mod:`s2r.render.backend`).
        temporary: a set read back at once and deleted (``validate``'s): its PNGs stored uncompressed
            (:data:`s2r.render.outputs.STORED_PNG`: the same pixels, 2.5x the bytes, 6x less CPU) and not synced.
    """
    renderer = renderer or RendererChoice()
    check_renderer(renderer)
    _check_board(pattern, square_m, views)
    sensor = profile.sensor if sensor is None else sensor
    check_render_options(supersample=supersample, noise_sigma=noise_sigma, right_gain=right_gain)
    board = BoardGeometry((int(pattern[0]), int(pattern[1])), float(square_m), BORDER_SQUARES)
    layout = None if target is None else target_layout(target)
    if layout is not None:
        board = layout.geometry
        if cut_share is None:
            cut_share = 0.0 if isinstance(target, CheckerboardTarget) else DEFAULT_CUT_SHARE
    check_output_dir(out_dir, force=force)
    poses = sample_board_poses(profile, board, views=views, seed=seed)
    cut: list[bool] = [False] * len(poses)
    if layout is not None and target is not None and cut_share:
        poses, cut = cut_views(profile, poses, layout.corners_grid(target), share=cut_share, seed=seed)
    out = clear_numbered(out_dir, ("left", "right"), force=force)
    names = numbered_names(views)
    left_setup, right_setup = stereo_setups(profile, supersample=supersample)
    with tempfile.TemporaryDirectory(prefix="s2r-boards-") as tmp:
        mesh, texture = board_surface(Path(tmp), board, layout)
        jobs_list = [
            StereoJob(left_setup, right_setup, (Surface(mesh, texture, T),), noise_sigma, right_gain, seed, k,
                      renderer, sensor)
            for k, T in enumerate(poses)
        ]
        images = run_jobs(render_stereo_images, jobs_list, jobs=render_workers(renderer, jobs), progress=progress,
                          label="render boards")
    options: dict[str, Any] = {"supersample": supersample, "seed": seed, "noise_sigma": noise_sigma,
                               "right_gain": right_gain, "renderer": renderer.name}
    if sensor is not None:
        options["sensor"] = sensor.model_dump(mode="json", exclude_none=True)
    if layout is not None:
        poses = [T @ layout.T_grid_target for T in poses]  # the truth in the target's own frame
    with OutputBatch(force=True, root=out, durable=not temporary) as batch:  # the whole set, or nothing
        left_paths = [encode_png(out / "left" / f"{name}.png", left, batch=batch, stored=temporary)
                      for name, (left, _) in zip(names, images, strict=True)]
        right_paths = [encode_png(out / "right" / f"{name}.png", right, batch=batch, stored=temporary)
                       for name, (_, right) in zip(names, images, strict=True)]
        truth_path = batch.add_text(out / "truth.yaml", _truth(profile, board, names, poses, options, target, cut))
        batch.publish()
    remove_stale_numbered(out, ("left", "right"), keep=left_paths + right_paths)
    return BoardSet(out, left_paths, right_paths, truth_path, [np.asarray(T) for T in poses])
