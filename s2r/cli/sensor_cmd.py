"""``s2r sensor fit | apply``: a camera's sensor model from a chessboard recording, and that model on perfect depth.

Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from s2r.cli._common import (
    ProgressBar,
    add_force,
    add_json,
    add_profile_positional,
    add_recording_inputs,
    argparse_type,
    check_left_board,
    load_profile,
    parse_pattern,
    print_json,
    profile_argument,
)
from s2r.depth.names import PRESETS
from s2r.errors import DepthError
from s2r.fileio import check_output_free

if TYPE_CHECKING:
    from s2r.profile import StereoProfile
    from s2r.sensor.fit.depth import DepthFrame
    from s2r.sensor.fit.images import BoardImage

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``sensor fit`` and ``sensor apply``."""
    parser = sub.add_parser("sensor", help="fit a camera's sensor model on a recording, or apply one to depth")
    sensor_sub = parser.add_subparsers(dest="sensor_command", required=True, metavar="WHAT")
    fit = sensor_sub.add_parser(
        "fit", help="image noise, blur, depth noise, fill and edge dropout from a chessboard recording",
        description="Measures a sensor model on a chessboard recording (the inputs depth-quality takes): image "
        "noise (grey levels) and blur (px) from the raw images, and from device depth (--depth) the disparity "
        "noise sigma_d (px) against distance, the fill rate against distance and the dropout band at depth edges; "
        "from stereo pairs (any recording: a folder, --left/--right, --bag, --video, --left-video/--right-video) "
        "the pipeline's sub-pixel RMS and fill rate. Writes sensor.yaml.")
    add_profile_positional(fit, help="the recording camera's profile (name or YAML path)")
    add_recording_inputs(fit)
    fit.add_argument("--preset", default="profile", choices=PRESETS,
                     help="matcher preset for stereo pairs (default profile)")
    fit.add_argument("--pattern", type=argparse_type(parse_pattern), required=True,
                     help="chessboard INNER corners, e.g. 9x6")
    fit.add_argument("--square", type=float, required=True, help="chessboard square size in metres")
    fit.add_argument("--depth-scale", type=float, default=0.001, help="metres per count of 16-bit depth")
    fit.add_argument("-o", "--output", dest="out", required=True, metavar="sensor.yaml", help="the fitted model")
    fit.add_argument("--profile-out", metavar="FILE", help="also write the profile with the model as its sensor:")
    add_json(fit)
    add_force(fit)
    fit.set_defaults(func=_cmd_fit)

    apply = sensor_sub.add_parser(
        "apply", help="turn perfect depth (a simulator's) into the device's with a sensor model",
        description="Adds the model's dropout at depth edges, holes against distance, disparity noise and "
        "sub-pixel quantisation to every depth file of DEPTH (uint16 PNG in --depth-scale units, 0 = no data, or "
        "float .npy metres); writes files of the same names and kinds into OUT. Seeded.")
    add_profile_positional(apply, help="the depth camera's profile: f (left, px) x baseline")
    apply.add_argument("model", metavar="SENSOR", help="sensor.yaml, or a profile with a sensor: section")
    apply.add_argument("depth", metavar="DEPTH", help="folder or quoted glob of perfect depth files")
    apply.add_argument("-o", "--output", dest="out", required=True, metavar="OUT", help="output folder")
    apply.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same output")
    apply.add_argument("--depth-scale", type=float, default=0.001, help="metres per count of 16-bit depth")
    add_json(apply)
    add_force(apply)
    apply.set_defaults(func=_cmd_apply)


def _stereo(args: argparse.Namespace) -> bool:
    """Whether the options name stereo pairs (any recording form beyond ``--left`` alone)."""
    return any(v is not None for v in (args.right, args.right_topic, args.recording, args.video, args.left_video,
                                       args.right_video))


def _check_fit_args(args: argparse.Namespace) -> None:
    device = args.depth is not None or args.depth_topic is not None
    if device and _stereo(args):
        raise DepthError("give one depth source", field="--right/--depth",
                         hint="--right (stereo pairs) or --depth (device depth), not both")
    if _stereo(args):
        from s2r.cli._recording import spec_from_args

        spec_from_args(args).check(error=DepthError)
    elif args.bag is not None:
        if not args.left_topic:
            raise DepthError("a bag needs --left-topic", field="--left-topic",
                             hint="e.g. /camera/infra1/image_rect_raw")
        if not device:
            raise DepthError("a bag needs a second topic", field="--right-topic/--depth-topic",
                             hint="--right-topic (stereo pairs) or --depth-topic (device depth)")
    elif args.left is None:
        raise DepthError("missing left images", field="--left", hint="pass --left DIR|GLOB (or a recording)")
    if args.bag is None and (args.left_topic or args.right_topic or args.depth_topic):
        raise DepthError("topics need --bag", field="--left-topic", hint="pass --bag BAG")
    if not 0 < args.square < float("inf"):
        raise DepthError(f"must be positive metres, got {args.square}", field="--square", hint="e.g. 0.025")
    if not 0 < args.max_dt < float("inf"):
        raise DepthError(f"must be positive seconds, got {args.max_dt}", field="--max-dt", hint="e.g. 0.01")
    if not 0 < args.depth_scale < float("inf"):
        raise DepthError(f"must be positive, got {args.depth_scale}", field="--depth-scale", hint="0.001 for mm")


def _recording(args: argparse.Namespace, profile: StereoProfile, *, grey: bool) -> Any:
    """The stereo recording the options name, its sizes checked against ``profile`` before decoding."""
    from s2r.cli._recording import recording_from_args

    sizes = ((profile.left.width_px, profile.left.height_px), (profile.right.width_px, profile.right.height_px))
    return recording_from_args(args, expected_size=sizes, grey=grey, error=DepthError)


def _raw_images(args: argparse.Namespace, profile: StereoProfile) -> list[BoardImage]:
    """The raw grey images of the recording's cameras (left, and right for stereo) with their boards."""
    from s2r.quality.inputs import IMAGE_SUFFIXES, list_files, read_grey
    from s2r.sensor.fit import board_image

    found = []
    if _stereo(args):
        for frame in _recording(args, profile, grey=True).frames():
            found += [board_image(frame.name, img, args.pattern) for img in (frame.left, frame.right)]
        return [f for f in found if f is not None]
    found += [board_image(p.name, read_grey(p), args.pattern)
              for p in list_files(args.left, IMAGE_SUFFIXES, option="--left")]
    return [f for f in found if f is not None]


def _stereo_frames(args: argparse.Namespace, profile: StereoProfile) -> tuple[list[DepthFrame], int]:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.quality.run import measure_board_views
    from s2r.quality.views import frame_views, stereo_fb, stereo_visible_m
    from s2r.sensor.fit import stereo_depth_frames

    pipeline = StereoPipeline(profile, preset=args.preset)
    views = frame_views(pipeline, _recording(args, profile, grey=False))
    result = measure_board_views(profile, views, pattern=args.pattern, square_m=args.square,
                                 fb_px_m=stereo_fb(pipeline), source="stereo", visible_m=stereo_visible_m(pipeline))
    return stereo_depth_frames(result.frames), len(result.frames)


def _device_frames(args: argparse.Namespace, profile: StereoProfile) -> tuple[list[DepthFrame], list[BoardImage]]:
    from s2r.quality.inputs import DEPTH_SUFFIXES, IMAGE_SUFFIXES, list_files, pair_files
    from s2r.quality.views import bag_device_views, device_fb, device_views
    from s2r.sensor.fit import fit_device_depth

    if args.bag is not None:
        views = bag_device_views(profile, args.bag, args.left_topic, args.depth_topic, max_dt_s=args.max_dt,
                                 depth_scale_m=args.depth_scale)
        total = None
    else:
        frames = pair_files(list_files(args.left, IMAGE_SUFFIXES, option="--left"),
                            list_files(args.depth, DEPTH_SUFFIXES, option="--depth"), kind="depth")
        views, total = device_views(profile, frames, depth_scale_m=args.depth_scale), len(frames)
    bar = ProgressBar(enabled=False if (args.quiet or args.json) else None)
    return fit_device_depth(views, pattern=args.pattern, square_m=args.square, fb_px_m=device_fb(profile),
                            progress=bar, total=total)


def _cmd_fit(args: argparse.Namespace) -> int:
    from s2r.formats.s2r_yaml import dump_profile
    from s2r.sensor.files import dump_sensor_model
    from s2r.sensor.fit import fit_model

    name = profile_argument(args, command="sensor fit")  # first: with --profile the positional may be the FOLDER
    _check_fit_args(args)
    profile = load_profile(name)
    if args.left is not None:  # a wrong --pattern named in a second, before every frame's search
        check_left_board(args.left, args.pattern)
    check_output_free(args.out, force=args.force)
    if args.profile_out:
        check_output_free(args.profile_out, force=args.force)
    measured = 0
    if args.depth or args.depth_topic:
        depth, images = _device_frames(args, profile)
        source = "device depth"
    else:
        images = _raw_images(args, profile)
        depth, measured = _stereo_frames(args, profile) if _stereo(args) else ([], 0)
        source = "stereo pairs through the pipeline" if measured else "images"
    fit = fit_model(images, depth, source=f"s2r sensor fit on {source} ({profile.name})", stereo_frames=measured)
    dump_sensor_model(fit.model, args.out, force=args.force)
    if args.profile_out:
        dump_profile(profile.model_copy(update={"sensor": fit.model}), args.profile_out, force=args.force)
    if args.json:
        print_json(fit.as_dict())
    else:
        print("\n".join(_fit_lines(fit.model, fit.notes)))
        print(f"wrote {args.out}" + (f" and {args.profile_out}" if args.profile_out else ""))
    return 0


def _fit_lines(model: Any, notes: dict[str, str]) -> list[str]:
    def fmt(value: float | None, unit: str) -> str:
        return "not measured" if value is None else f"{value:.3g} {unit}"

    lines = [f"image noise        {fmt(model.image_noise_dn, 'DN')}  ({notes.get('image_noise_dn', '')})",
             f"blur               {fmt(model.blur_sigma_px, 'px')}  ({notes.get('blur_sigma_px', '')})"]
    if model.subpixel_sigma_px is not None:
        lines.append(f"disparity noise    {model.subpixel_sigma_px:.3g} px at 1 m, "
                     f"{model.subpixel_growth_px_per_m:+.3g} px/m  ({notes.get('subpixel_sigma_px', '')})")
    for p in model.fill_rate_by_distance:
        few = " (FEW FRAMES)" if p.frames is not None and p.frames < 3 else ""
        lines.append(f"fill rate          {p.fill_rate_pct:5.1f} % at {p.distance_m:.2f} m, {p.frames} frames{few}")
    if "fill_rate_by_distance" in notes and model.fill_rate_by_distance:
        lines.append(f"                   ({notes['fill_rate_by_distance']})")
    if model.edge_dropout_px is not None or "edge_dropout_px" in notes:
        lines.append(f"edge dropout band  {fmt(model.edge_dropout_px, 'px')}; hole scale {model.hole_scale_px:.3g} px")
    return lines


def _cmd_apply(args: argparse.Namespace) -> int:
    from s2r.quality.inputs import DEPTH_SUFFIXES, list_files
    from s2r.quality.views import device_fb
    from s2r.sensor.depth_files import check_depth_sizes
    from s2r.sensor.files import load_sensor_model
    from s2r.sensor.fit.apply_files import apply_to_files

    if args.seed < 0:
        raise DepthError(f"must be 0 or more, got {args.seed}", field="--seed", hint="e.g. 0")
    if not 0 < args.depth_scale < float("inf"):
        raise DepthError(f"must be positive, got {args.depth_scale}", field="--depth-scale", hint="0.001 for mm")
    profile = load_profile(profile_argument(args, command="sensor apply", shift_to=None))
    model = load_sensor_model(args.model)
    sources = list_files(args.depth, DEPTH_SUFFIXES, option="DEPTH")
    check_depth_sizes(sources, size=(profile.left.width_px, profile.left.height_px))  # before any is decoded
    written = apply_to_files(model, sources, args.out, fb_px_m=device_fb(profile), seed=args.seed,
                             depth_scale_m=args.depth_scale, force=args.force)
    if args.json:
        print_json({"out_dir": args.out, "files": [str(p) for p in written], "seed": args.seed})
    else:
        print(f"wrote {len(written)} depth file(s) to {args.out}", file=sys.stdout)
    return 0
