"""``s2r depth``: depth maps from a stereo pair or a sequence of pairs with any profile and preset."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from s2r.cli._common import ProgressBar, add_force, add_jobs, add_json, check_jobs, print_json
from s2r.cli._recording import add_recording_arguments
from s2r.cli.depth_stream_cmd import (
    add_stream_arguments,
    check_target_options,
    recording_given,
    run_stream,
    split_inputs,
)
from s2r.depth.names import PRESETS, STAGES
from s2r.errors import DepthError
from s2r.fileio import OutputBatch, check_output_dir, check_output_free, prepare_output_dir

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.rectification import StereoRectification

__all__ = ["register"]

log = logging.getLogger(__name__)

#: Below this valid fraction a depth map is almost surely wrong input, not a hard scene: say so.
LOW_VALID_FRACTION = 0.01


def register(sub: Any) -> None:
    """Add ``s2r depth``."""
    parser = sub.add_parser(
        "depth", help="depth maps from stereo pairs",
        description="Rectify with a profile, match with a preset, and write depth. One pair (PROFILE LEFT RIGHT): "
        "disparity.npy (float32 px, NaN invalid), depth.png (uint16 mm, 0 invalid), depth_color.png (JET with a colour "
        "bar in metres), camera_info.yaml (ROS camera_info of the rectified left camera, the frame of every output) "
        "and optionally points.ply. A recording (PROFILE FOLDER, or --bag/--video/--left ...) is streamed into "
        "--to files (per-frame files named after the input frames, frames.csv), ros2 (a ROS 2 mcap bag folder) or "
        "ros1 (a .bag), published whole. Depth outside the profile's matcher.min_depth_m..max_depth_m is invalid "
        "unless --keep-out-of-range.")
    parser.add_argument("inputs", nargs="*", metavar="PROFILE [LEFT RIGHT | FOLDER]",
                        help="the profile (name or YAML path; default $S2R_PROFILE), then one pair of images or a "
                        "recording FOLDER (or give the recording with the options below)")
    parser.add_argument("--profile", help="the profile, as an option (then the positionals are the inputs)")
    parser.add_argument("-o", "--output", type=Path, required=True,
                        help="output folder (--to files, ros2: a ROS 2 bag folder) or file (--to ros1: a .bag)")
    parser.add_argument("--preset", default="profile", choices=PRESETS, help="matcher preset (default: profile)")
    parser.add_argument("--num-disparities", type=int, help="disparity range in px (multiple of 16)")
    parser.add_argument("--postprocess", help=f"comma-separated stages from {','.join(STAGES)} ('' for none); "
                        "default: the preset's")
    parser.add_argument("--alpha", type=float, default=None,
                        help="rectification alpha in [0, 1] (0 valid pixels only, 1 every source pixel) or -1 "
                        "(OpenCV's default); default: the preset's (seed-sgbm -1, as the seed; others 0)")
    parser.add_argument("--fov", type=float, metavar="DEG",
                        help="fisheye profiles: horizontal field of view of the rectified images in degrees "
                        "(default: OpenCV's, at most 90)")
    parser.add_argument("--resize", action="store_true", help="accept other image sizes by rescaling intrinsics")
    parser.add_argument("--ply", action="store_true", help="also write a coloured point cloud (points.ply)")
    add_stream_arguments(parser)
    parser.add_argument("--keep-out-of-range", action="store_true",
                        help="keep depths outside the profile's min_depth_m..max_depth_m (default: invalid, 0)")
    parser.add_argument("--range", metavar="NEAR,FAR", dest="colour_range",
                        help="fixed colour scale of depth_color.png in metres (the same colour is the same depth in "
                        "every frame of a sequence); default each map's own range")
    given = parser.add_argument_group("already-rectified pairs (Middlebury, rectified topics): no --profile")
    given.add_argument("--rectified", action="store_true",
                       help="the pairs are rectified already: give --f, --baseline, --cx, --cy (and --doffs)")
    given.add_argument("--f", type=float, metavar="PX", help="--rectified: focal length, pixels")
    given.add_argument("--baseline", type=float, metavar="M", help="--rectified: baseline, metres")
    given.add_argument("--cx", type=float, metavar="PX", help="--rectified: left principal point x, pixels")
    given.add_argument("--cy", type=float, metavar="PX", help="--rectified: principal point y, pixels")
    given.add_argument("--doffs", type=float, default=0.0, metavar="PX",
                       help="--rectified: right cx minus left cx, pixels (Middlebury's doffs; default 0)")
    parser.add_argument("--left-dir", type=Path, help="folder of left images (the NN_* sequence layout)")
    parser.add_argument("--right-dir", type=Path, help="folder of right images, paired by sorted names")
    add_recording_arguments(parser, positional=None)
    add_jobs(parser, default=2, help="matching threads, sequences and recordings (default 2)")
    add_force(parser)
    add_json(parser)
    parser.set_defaults(func=_cmd_depth)


def _pipeline(args: argparse.Namespace) -> StereoPipeline:
    from s2r.depth.pipeline import StereoPipeline, check_side_by_side  # OpenCV loads only when a depth command runs
    from s2r.depth.postprocess import check_stages
    from s2r.registry import load_profile

    post = None if args.postprocess is None else check_stages(args.postprocess)
    if args.rectified:
        return StereoPipeline(_given_profile(args), preset=args.preset, num_disparities=args.num_disparities,
                              postprocess=post, rectified=True)
    profile = load_profile(args.profile)
    check_side_by_side(profile, path=args.profile or "$S2R_PROFILE")  # name the file of a vertical rig
    return StereoPipeline(profile, preset=args.preset, alpha=args.alpha, num_disparities=args.num_disparities,
                          postprocess=post, resize=args.resize, fov_deg=args.fov)


def _given_profile(args: argparse.Namespace) -> Any:
    """--rectified: the profile of the pairs' geometry, at the size of the first left image."""
    from s2r.depth.outputs import read_image
    from s2r.depth.prerectified import rectified_profile
    from s2r.depth.sequence import pair_images

    missing = [o for o, v in (("--f", args.f), ("--baseline", args.baseline), ("--cx", args.cx), ("--cy", args.cy))
               if v is None]
    if missing:
        raise DepthError(f"needs {', '.join(missing)}", field="--rectified",
                         hint="e.g. --rectified --f 3740 --baseline 0.16 --cx 224.5 --cy 187 (Middlebury's calib.txt)")
    for option, given in (("--profile", args.profile), ("--resize", args.resize or None), ("--fov", args.fov),
                          ("--alpha", args.alpha)):
        if given is not None:
            raise DepthError("does not apply to already-rectified pairs", field=option, hint=f"drop {option}")
    first = args.pair_left if args.pair_left is not None else pair_images(args.left_dir, args.right_dir)[0][0]
    shape = read_image(first).shape
    return rectified_profile((shape[1], shape[0]), f_px=args.f, baseline_m=args.baseline, cx_px=args.cx,
                             cy_px=args.cy, doffs_px=args.doffs)


def _cmd_depth(args: argparse.Namespace) -> int:
    split_inputs(args)
    check_target_options(args)
    sequence = args.left_dir is not None or args.right_dir is not None
    stream = recording_given(args)
    if sequence and (args.left_dir is None or args.right_dir is None):
        raise DepthError("sequence mode needs both folders", field="--left-dir/--right-dir",
                         hint="pass --left-dir and --right-dir")
    if sum((sequence, stream, args.pair_left is not None)) > 1:
        raise DepthError("give one input: LEFT RIGHT images, a recording, or --left-dir/--right-dir", field="LEFT",
                         hint="drop the others")
    thinned = [flag for flag, on in (("--every", args.every != 1), ("--max-frames", args.max_frames is not None)) if on]
    if thinned and not stream:
        raise DepthError("applies to recordings only", field=thinned[0],
                         hint="give the frames as a recording (FOLDER, --left/--right, --bag, --video, ...) or drop it")
    if not (sequence or stream) and args.pair_left is None:
        raise DepthError("missing images", field="LEFT RIGHT",
                         hint="pass PROFILE LEFT RIGHT, or PROFILE and a recording (FOLDER, --bag, --video, ...)")
    if stream and args.rectified:
        raise DepthError("takes LEFT RIGHT or --left-dir/--right-dir, not a recording", field="--rectified",
                         hint="drop --rectified and give the recording's profile")
    _refuse_one_camera_twice(args, stream=stream)
    if args.alpha is not None and not (0.0 <= args.alpha <= 1.0 or args.alpha == -1.0):  # NaN fails both
        raise DepthError(f"must be between 0 and 1, or -1 for OpenCV's default scaling, got {args.alpha}",
                         field="--alpha", hint="0 keeps only valid pixels, 1 keeps every source pixel")
    check_jobs(args.jobs, DepthError)
    if args.fov is not None and not 10.0 <= args.fov <= 170.0:  # NaN fails too
        raise DepthError(f"must be 10-170 degrees, got {args.fov}", field="--fov", hint="e.g. --fov 90")
    args.colour_range = _colour_range(args.colour_range)
    pipeline = _pipeline(args)
    if args.fov is not None and pipeline.profile.left.distortion.model != "equidistant":  # was silently ignored
        raise DepthError(f"--fov sets the rectified field of fisheye (equidistant) profiles; {pipeline.profile.name} "
                         f"is {pipeline.profile.left.distortion.model}", field="--fov",
                         hint="drop --fov, or use --alpha to keep more of a pinhole image")
    if stream or args.to != "files":
        return run_stream(args, pipeline)
    if args.pcd:  # the older layouts have no PCD; the option must not vanish silently
        raise DepthError("writes points/NAME.pcd of a recording's frames", field="--pcd",
                         hint="give the pair as a recording (PROFILE FOLDER or --left/--right), or use --ply")
    args.ply = args.ply or args.points
    return _run_sequence(args, pipeline) if sequence else _run_pair(args, pipeline)


def _refuse_one_camera_twice(args: argparse.Namespace, *, stream: bool) -> None:
    """The same input for both cameras (LEFT RIGHT, --left-dir/--right-dir, any recording form), refused in one
    message (:func:`s2r.recordings.refuse_same_sides`) before the profile is loaded or anything is decoded."""
    from s2r.cli._recording import spec_from_args
    from s2r.recordings import refuse_same_sides

    refuse_same_sides(args.pair_left, args.pair_right, field="LEFT RIGHT", error=DepthError)
    refuse_same_sides(args.left_dir, args.right_dir, field="--left-dir/--right-dir", error=DepthError)
    if stream:
        spec_from_args(args).check(error=DepthError)


def _colour_range(text: str | None) -> tuple[float, float] | None:
    """``NEAR,FAR`` metres, 0 < NEAR < FAR, both finite; DepthError naming --range otherwise."""
    if text is None:
        return None
    try:
        near, far = (float(v) for v in text.split(","))
    except ValueError:
        raise DepthError(f"expected NEAR,FAR in metres, got {text!r}", field="--range",
                         hint="e.g. --range 0.3,5") from None
    if not (0.0 < near < far < float("inf")):  # NaN fails too
        raise DepthError(f"needs 0 < NEAR < FAR, got {text!r}", field="--range", hint="e.g. --range 0.3,5")
    return near, far


def _depth_range(args: argparse.Namespace, pipeline: StereoPipeline) -> tuple[float, float] | None:
    """The profile's working range (metres) that depth outputs are limited to; None with --keep-out-of-range."""
    m = pipeline.profile.matcher
    return None if args.keep_out_of_range else (m.min_depth_m, m.max_depth_m)


def _geometry(pipeline: StereoPipeline, rect: StereoRectification, depth_range: tuple[float, float] | None
              ) -> dict[str, Any]:
    """f, B, the principal point, Q and the depth range of the rectified left camera, for --json."""
    return {"f_px": rect.fx_px, "baseline_m": rect.baseline_m, "cx_px": float(rect.P1[0, 2]),
            "cy_px": float(rect.P1[1, 2]), "doffs_px": rect.doffs_px, "Q": rect.Q.tolist(),
            "image_size": list(rect.image_size), "depth_range_m": None if depth_range is None else list(depth_range),
            "frame": "rectified left camera (camera_info.yaml)"}


def _run_pair(args: argparse.Namespace, pipeline: StereoPipeline) -> int:
    from s2r.depth.outputs import limit_depth_range, read_image, write_camera_info, write_outputs

    left, right = read_image(args.pair_left), read_image(args.pair_right)
    check_output_dir(args.output, force=True)  # "-o FILE": a file where the output folder should be
    names = ["disparity.npy", "depth.png", "depth_color.png", "camera_info.yaml"] + (["points.ply"] if args.ply
                                                                                      else [])
    for name in names:  # refuse before computing or writing anything
        check_output_free(args.output / name, force=args.force)
    try:
        result = pipeline.compute(left, right)
    except DepthError as exc:  # size mismatch between the images or with the profile: name the image
        if exc.path is not None:
            raise
        raise DepthError(exc.message, path=args.pair_right if exc.field == "right" else args.pair_left,
                         field=exc.field,
                         hint=exc.hint) from None
    depth_range = _depth_range(args, pipeline)
    removed = 0
    if depth_range is not None:
        result, removed = limit_depth_range(result, *depth_range)
    rect = pipeline.geometry_for((left.shape[1], left.shape[0])).rectification
    if args.force:  # replaced whole: no points.ply of an earlier --ply run stays beside the new files
        prepare_output_dir(args.output, force=True)
    with OutputBatch(force=args.force, root=args.output) as batch:  # every file, or none
        written = write_outputs(args.output, result, ply=args.ply, batch=batch, colour_range_m=args.colour_range)
        written.append(write_camera_info(args.output / "camera_info.yaml", rect, name=f"{pipeline.profile.name}/"
                                         "rectified_left", batch=batch))
        batch.publish()
    valid_fraction = float(result.valid.mean())
    if valid_fraction < LOW_VALID_FRACTION:  # a silent 0 % looks like a result; it is almost always the input
        log.warning("%s: only %.1f %% of the pixels have depth: check that LEFT and RIGHT are not swapped and "
                    "are this profile's cameras, and the profile's depth range", args.pair_left, 100 * valid_fraction)
    summary: dict[str, Any] = {"profile": pipeline.profile.name, "preset": pipeline.preset,
               "num_disparities": pipeline.config.num_disparities, "postprocess": list(pipeline.postprocess),
               "valid_fraction": valid_fraction, "out_of_range_removed": removed,
               "median_depth_m": float(_nanmedian(result.depth)), **_geometry(pipeline, rect, depth_range),
               "outputs": [str(p) for p in written]}
    if args.json:
        print_json(summary)
    else:
        limits = "" if depth_range is None else (f", {removed} px outside {depth_range[0]:g}-{depth_range[1]:g} m "
                                                 "set invalid")
        print(f"{pipeline.profile.name} / {pipeline.preset}: {100 * valid_fraction:.1f} % valid{limits}, "
              f"median depth {summary['median_depth_m']:.3f} m, f {rect.fx_px:.2f} px, B {rect.baseline_m:.4f} m "
              f"-> {args.output}")
    return 0


def _run_sequence(args: argparse.Namespace, pipeline: StereoPipeline) -> int:
    from s2r.depth.outputs import read_image, write_camera_info
    from s2r.depth.sequence import pair_images, run_sequence

    for folder in (args.left_dir, args.right_dir):  # NN_depth.png there would be read as frames next time
        if args.output.resolve() == folder.resolve():
            raise DepthError("the output folder is an input folder: its depth PNGs would be read as images of "
                             "the next run", path=args.output, field="--output", hint="choose another -o folder")
    pairs = pair_images(args.left_dir, args.right_dir)
    prepare_output_dir(args.output, force=args.force)
    check_output_free(args.output / "camera_info.yaml", force=args.force)
    bar = ProgressBar(enabled=None if not args.quiet else False)
    depth_range = _depth_range(args, pipeline)
    with OutputBatch(force=args.force, root=args.output) as batch:  # the whole sequence, or nothing
        frames = run_sequence(pipeline, pairs, args.output, ply=args.ply, force=args.force, workers=args.jobs,
                              progress=bar, depth_range_m=depth_range, batch=batch,
                              colour_range_m=args.colour_range)
        # every frame has the profile's size unless --resize: then the camera_info of the first frame's size
        size = pipeline.profile.image_size
        if args.resize and pairs:
            shape = read_image(pairs[0][0]).shape
            size = (shape[1], shape[0])
        rect = pipeline.geometry_for(size).rectification
        write_camera_info(args.output / "camera_info.yaml", rect, name=f"{pipeline.profile.name}/rectified_left",
                          batch=batch)
        batch.publish()
    if args.json:
        print_json({"profile": pipeline.profile.name, "preset": pipeline.preset, "frames": frames,
                    "output": str(args.output), **_geometry(pipeline, rect, depth_range)})
    else:
        print(f"{pipeline.profile.name} / {pipeline.preset}: {frames} frames -> {args.output}")
    return 0


def _nanmedian(values: Any) -> float:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else float("nan")
