"""``s2r depth``: depth maps from a stereo pair or a sequence of pairs with any profile and preset."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from s2r.cli._common import ProgressBar, add_force, add_json, print_json
from s2r.depth.names import PRESETS, STAGES
from s2r.errors import DepthError
from s2r.fileio import check_output_free, prepare_output_dir

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``s2r depth``."""
    parser = sub.add_parser(
        "depth", help="depth maps from stereo pairs",
        description="Rectify with a profile, match with a preset, and write disparity.npy (float32 px, NaN "
        "invalid), depth.png (uint16 mm, 0 invalid), depth_color.png (JET) and optionally points.ply.")
    parser.add_argument("left", nargs="?", type=Path, help="left image (single-pair mode)")
    parser.add_argument("right", nargs="?", type=Path, help="right image (single-pair mode)")
    parser.add_argument("--profile", help="profile name or YAML path (default: $S2R_PROFILE)")
    parser.add_argument("-o", "--output", type=Path, required=True, help="output folder")
    parser.add_argument("--preset", default="profile", choices=PRESETS, help="matcher preset (default: profile)")
    parser.add_argument("--num-disparities", type=int, help="disparity range in px (multiple of 16)")
    parser.add_argument("--postprocess", help=f"comma-separated stages from {','.join(STAGES)} ('' for none); "
                        "default: the preset's")
    parser.add_argument("--alpha", type=float, default=0.0,
                        help="rectification alpha in [0, 1] (0 valid pixels only, 1 every source pixel) or -1 "
                        "(OpenCV's default)")
    parser.add_argument("--resize", action="store_true", help="accept other image sizes by rescaling intrinsics")
    parser.add_argument("--ply", action="store_true", help="also write a coloured point cloud (points.ply)")
    parser.add_argument("--left-dir", type=Path, help="folder of left images (sequence mode)")
    parser.add_argument("--right-dir", type=Path, help="folder of right images, paired by sorted names")
    parser.add_argument("--workers", type=int, default=2, help="compute threads in sequence mode (default 2)")
    add_force(parser)
    add_json(parser)
    parser.set_defaults(func=_cmd_depth)


def _pipeline(args: argparse.Namespace) -> StereoPipeline:
    from s2r.depth.pipeline import StereoPipeline  # OpenCV loads only when a depth command runs
    from s2r.depth.postprocess import check_stages

    post = None if args.postprocess is None else check_stages(args.postprocess)
    return StereoPipeline(args.profile, preset=args.preset, alpha=args.alpha, num_disparities=args.num_disparities,
                          postprocess=post, resize=args.resize)


def _cmd_depth(args: argparse.Namespace) -> int:
    sequence = args.left_dir is not None or args.right_dir is not None
    if sequence and (args.left_dir is None or args.right_dir is None):
        raise DepthError("sequence mode needs both folders", field="--left-dir/--right-dir",
                         hint="pass --left-dir and --right-dir")
    if sequence and (args.left or args.right):
        raise DepthError("give either LEFT RIGHT images or --left-dir/--right-dir, not both", field="LEFT",
                         hint="drop one of them")
    if not sequence and (args.left is None or args.right is None):
        raise DepthError("missing images", field="LEFT RIGHT", hint="pass LEFT RIGHT or --left-dir/--right-dir")
    if not (0.0 <= args.alpha <= 1.0 or args.alpha == -1.0):  # NaN fails both
        raise DepthError(f"must be between 0 and 1, or -1 for OpenCV's default scaling, got {args.alpha}",
                         field="--alpha", hint="0 keeps only valid pixels, 1 keeps every source pixel")
    pipeline = _pipeline(args)
    return _run_sequence(args, pipeline) if sequence else _run_pair(args, pipeline)


def _run_pair(args: argparse.Namespace, pipeline: StereoPipeline) -> int:
    from s2r.depth.outputs import read_image, write_outputs

    left, right = read_image(args.left), read_image(args.right)
    result = pipeline.compute(left, right)
    names = ["disparity.npy", "depth.png", "depth_color.png"] + (["points.ply"] if args.ply else [])
    for name in names:  # refuse before writing anything
        check_output_free(args.output / name, force=args.force)
    written = write_outputs(args.output, result, ply=args.ply, force=args.force)
    valid_fraction = float(result.valid.mean())
    summary: dict[str, Any] = {"profile": pipeline.profile.name, "preset": pipeline.preset,
               "num_disparities": pipeline.config.num_disparities, "postprocess": list(pipeline.postprocess),
               "valid_fraction": valid_fraction,
               "median_depth_m": float(_nanmedian(result.depth)), "outputs": [str(p) for p in written]}
    if args.json:
        print_json(summary)
    else:
        print(f"{pipeline.profile.name} / {pipeline.preset}: {100 * valid_fraction:.1f} % valid, "
              f"median depth {summary['median_depth_m']:.3f} m -> {args.output}")
    return 0


def _run_sequence(args: argparse.Namespace, pipeline: StereoPipeline) -> int:
    from s2r.depth.sequence import pair_images, run_sequence

    pairs = pair_images(args.left_dir, args.right_dir)
    prepare_output_dir(args.output, force=args.force)
    bar = ProgressBar(enabled=None if not args.quiet else False)
    frames = run_sequence(pipeline, pairs, args.output, ply=args.ply, force=args.force, workers=args.workers,
                          progress=bar)
    if args.json:
        print_json({"profile": pipeline.profile.name, "preset": pipeline.preset, "frames": frames,
                    "output": str(args.output)})
    else:
        print(f"{pipeline.profile.name} / {pipeline.preset}: {frames} frames -> {args.output}")
    return 0


def _nanmedian(values: Any) -> float:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else float("nan")
