"""``s2r render boards | scene``: synthetic calibration sets and ground-truth depth scenes (PyBullet or MuJoCo)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from s2r.cli._common import (
    ProgressBar,
    add_force,
    add_jobs,
    add_json,
    argparse_type,
    check_jobs,
    load_profile,
    parse_distances,
    parse_pattern,
    print_json,
)
from s2r.errors import RenderError
from s2r.fileio import atomic_write_text, read_text_file

if TYPE_CHECKING:
    from s2r.sensor.model import SensorModel

__all__ = ["RENDERER_CHOICES", "SCENE_CHOICES", "add_renderer", "register", "renderer_choice"]

#: Renderer names (equal to ``s2r.render.backend.RENDERERS``; repeated so the CLI starts without pybullet).
RENDERER_CHOICES = ("pybullet", "mujoco")

#: Scene names (equal to ``s2r.render.SCENES``; repeated here so the CLI imports pybullet only when rendering).
SCENE_CHOICES = ("planes", "slanted", "span", "room")


def _common(parser: argparse.ArgumentParser, *, scene_alias: bool = False) -> None:
    parser.add_argument("profile", help="profile name or path")
    parser.add_argument("-o", "--output", "--out", dest="out", required=True, metavar="DIR",
                        help="output folder (must be empty unless --force); --out is kept as an alias")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same output")
    parser.add_argument("--supersample", type=int, default=None, metavar="S",
                        help="render at S x size and average down (default 2 with PyBullet, whose TinyRenderer has no "
                             "anti-aliasing; 1 with MuJoCo, whose filtered textures are as accurate at 1x)")
    parser.add_argument("--noise", type=float, default=0.0, metavar="SIGMA",
                        help="image noise: sigma of additive Gaussian noise in the grey image, grey levels of the "
                        "8-bit range, before rounding (the sensor model's image_noise_dn; default 0)")
    parser.add_argument("--right-gain", type=float, default=1.0, metavar="G",
                        help="right camera gain relative to the left (default 1.0)")
    add_jobs(parser, default=None, help="worker processes (default: all cores)")
    parser.add_argument("--sensor-model", type=Path, default=None, metavar="FILE",
                        help="blur and grey-level noise of this sensor.yaml (s2r sensor fit) on both images; default "
                        "the profile's own sensor: section")
    add_renderer(parser, scene_alias=scene_alias)
    add_force(parser)
    add_json(parser)


def add_renderer(parser: argparse.ArgumentParser, *, scene_alias: bool = False) -> None:
    """Add ``--renderer``, ``--world SCENE.xml`` (``--scene`` too when ``scene_alias``) and ``--world-camera``."""
    parser.add_argument("--renderer", choices=RENDERER_CHOICES, default="pybullet",
                        help="pybullet (default: TinyRenderer, flat light) or mujoco (MuJoCo's OpenGL renderer, "
                             "headless through EGL or OSMesa; pip install 's2r[mujoco]')")
    names = ["--world", "--scene"] if scene_alias else ["--world"]
    parser.add_argument(*names, dest="world", type=Path, default=None, metavar="SCENE.xml",
                        help="with --renderer mujoco: render inside this MJCF world (its lights, materials and "
                             "objects) with the boards and surfaces inserted")
    parser.add_argument("--world-camera", default=None, metavar="CAM",
                        help="with --world: the left camera takes this MJCF camera's pose (default: the world's "
                             "origin looking along +x, z up)")


def _supersample(args: argparse.Namespace) -> int:
    """``--supersample``, or the renderer's default: 2 for PyBullet, 1 for MuJoCo."""
    if args.supersample is not None:
        return int(args.supersample)
    return 1 if args.renderer == "mujoco" else 2


def renderer_choice(args: argparse.Namespace) -> Any:
    """The :class:`s2r.render.backend.RendererChoice` of ``--renderer`` / ``--world`` / ``--world-camera``."""
    from s2r.render.backend import RendererChoice

    world = None if args.world is None else str(args.world)
    return RendererChoice(args.renderer, world, args.world_camera)


def register(sub: Any) -> None:
    """Add ``render boards`` and ``render scene``."""
    parser = sub.add_parser("render", help="render calibration boards or ground-truth depth scenes (PyBullet or "
                                           "MuJoCo)")
    render_sub = parser.add_subparsers(dest="render_command", required=True, metavar="WHAT")

    p_boards = render_sub.add_parser("boards", help="a stereo chessboard calibration set with true poses",
                                     description="Writes DIR/left/NN.png, DIR/right/NN.png and DIR/truth.yaml.")
    _common(p_boards, scene_alias=True)
    p_boards.add_argument("--views", type=int, default=20, metavar="N", help="number of views (default 20)")
    p_boards.add_argument("--pattern", type=argparse_type(parse_pattern), default=(9, 6), metavar="COLSxROWS",
                          help="inner corners (default 9x6)")
    p_boards.add_argument("--square", type=float, default=0.025, metavar="M", help="square size in metres")
    p_boards.add_argument("--target", type=Path, default=None, metavar="TARGET.yaml",
                          help="render a ChArUco board or Kalibr AprilGrid/checkerboard described by this file "
                               "(instead of --pattern); copied into DIR as target.yaml")
    p_boards.add_argument("--cut-share", type=float, default=None, metavar="F",
                          help="share of views cut by the image edge (default 0.4 for ChArUco/AprilGrid, else 0)")
    p_boards.set_defaults(func=_cmd_boards)

    p_scene = render_sub.add_parser(
        "scene", help="textured scenes with ground-truth depth and rectified disparity",
        description="Writes DIR/left/NN.png, right/NN.png, depth/NN.npy (float32 m, NaN = nothing hit), "
        "disparity/NN.npy (float32 px, rectified left image), depth_rect/NN.npy and scene.yaml.")
    _common(p_scene)
    p_scene.add_argument("--scene", choices=SCENE_CHOICES, default="planes", help="scene type (default planes)")
    p_scene.add_argument("--distances", type=argparse_type(parse_distances), default=(0.5, 1.0, 2.0, 3.0, 5.0),
                         metavar="D1,D2,...",
                         help="distances in metres (default 0.5,1,2,3,5)")
    p_scene.set_defaults(func=_cmd_scene)


def _sensor(args: argparse.Namespace) -> SensorModel | None:
    """The --sensor-model file's model, or None (the profile's own section then applies)."""
    if args.sensor_model is None:
        return None
    from s2r.sensor.files import load_sensor_model

    return load_sensor_model(args.sensor_model)


def _cmd_boards(args: argparse.Namespace) -> int:
    from s2r.render import render_board_set

    check_jobs(args.jobs, RenderError)
    profile = load_profile(args.profile)
    target = None
    if args.target is not None:
        from s2r.targets import load_target

        target = load_target(args.target)
    if args.cut_share is not None and not 0.0 <= args.cut_share <= 1.0:
        raise RenderError(f"--cut-share must be 0..1, got {args.cut_share}", field="--cut-share", hint="e.g. 0.4")
    bar = ProgressBar(enabled=None if not args.quiet else False)
    result = render_board_set(
        profile, args.out, views=args.views, pattern=args.pattern, square_m=args.square, seed=args.seed,
        supersample=_supersample(args), noise_sigma=args.noise, jobs=args.jobs, force=args.force, progress=bar,
        right_gain=args.right_gain, target=target, cut_share=args.cut_share, renderer=renderer_choice(args),
        sensor=_sensor(args),
    )
    if args.target is not None:
        atomic_write_text(result.out_dir / "target.yaml", read_text_file(args.target), force=True,
                          root=result.out_dir)
    if args.json:
        print_json({"out_dir": result.out_dir, "views": len(result.poses), "truth": result.truth_path})
    else:
        what = target.describe() if target is not None else f"{args.pattern[0]}x{args.pattern[1]} board"
        print(f"wrote {len(result.poses)} stereo views of a {what} to {result.out_dir} "
              f"(truth: {result.truth_path.name})")
    return 0


def _cmd_scene(args: argparse.Namespace) -> int:
    from s2r.render import check_output_dir, render_scene, write_scene

    check_jobs(args.jobs, RenderError)
    profile = load_profile(args.profile)
    check_output_dir(args.out, force=args.force)
    bar = ProgressBar(enabled=None if not args.quiet else False)
    frames = render_scene(
        profile, scene=args.scene, distances_m=args.distances, supersample=_supersample(args), seed=args.seed,
        noise_sigma=args.noise, jobs=args.jobs, progress=bar, right_gain=args.right_gain,
        renderer=renderer_choice(args), sensor=_sensor(args),
    )
    out = write_scene(frames, args.out, force=args.force)
    if args.json:
        print_json({"out_dir": out, "frames": [f.name for f in frames], "scene": args.scene})
    else:
        print(f"wrote {len(frames)} {args.scene} frame(s) with ground-truth depth and disparity to {out}")
    return 0
