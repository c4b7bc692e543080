"""``s2r depth-quality PROFILE``: Intel's depth-quality metrics of a recording (stereo pairs or device depth).

Exit codes: 0 figures computed, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
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
from s2r.fileio import check_output_free, prepare_output_dir

if TYPE_CHECKING:
    from s2r.profile import StereoProfile
    from s2r.quality.run import QualityResult
    from s2r.quality.source import RecordingSource

__all__ = ["register"]

#: Frames shown with their images in the HTML report (the tables list every frame).
REPORT_FRAMES = 40


def register(sub: Any) -> None:
    """Add ``s2r depth-quality``."""
    parser = sub.add_parser(
        "depth-quality", help="Intel's depth-quality metrics of a recording (board or flat wall)",
        description="Z accuracy, plane-fit RMS, sub-pixel RMS, fill rate (and temporal noise when a pose repeats) "
        "inside a chessboard's region, against the board's PnP plane, per frame and per distance bin, as Intel's "
        "camera depth testing methodology defines them. Depth from stereo pairs through the pipeline (any "
        "recording: a folder, --left/--right, --bag with --right-topic, --video, --left-video/--right-video) or "
        "from the device (--depth: uint16 mm PNG, 0 = no data, or float32 metres .npy, registered to the left "
        "image). --wall: a flat wall without a board (central ROI; refused when it is not a plane). Mismatched "
        "pixels are counted (outliers %) and left out of the RMS figures; a frame that cannot be scored says why.")
    add_profile_positional(parser, help="profile name or YAML path (or give it as --profile)")
    add_recording_inputs(parser)
    parser.add_argument("--preset", default="profile", choices=PRESETS, help="matcher preset for stereo pairs")
    parser.add_argument("--num-disparities", type=int, help="disparity range in px for stereo (multiple of 16)")
    parser.add_argument("--pattern", type=argparse_type(parse_pattern), help="chessboard INNER corners, e.g. 9x6")
    parser.add_argument("--square", type=float, help="chessboard square size in metres")
    parser.add_argument("--wall", action="store_true", help="flat-wall mode: no board, central ROI")
    parser.add_argument("--distance", type=float, help="flat-wall distance in metres (gives Z accuracy)")
    parser.add_argument("--roi", type=float, default=0.8, help="flat-wall ROI: share of width and height (0.8)")
    parser.add_argument("--depth-scale", type=float, default=0.001, help="metres per count of 16-bit depth")
    parser.add_argument("-o", "--output", "--report", dest="report", metavar="DIR",
                        help="write DIR/depth_quality.html (--report is kept as an alias)")
    add_json(parser)
    add_force(parser)
    parser.set_defaults(func=_cmd_depth_quality)


def _device(args: argparse.Namespace) -> bool:
    return args.depth is not None or args.depth_topic is not None


def _source(args: argparse.Namespace) -> RecordingSource:
    """The recording named by the options (checked by :func:`_check_args`): stereo pairs from any recording form,
    or left images with device depth."""
    from s2r.cli._recording import spec_from_args
    from s2r.quality.source import RecordingSource

    if not _device(args):
        return RecordingSource(recording=spec_from_args(args), depth_scale_m=args.depth_scale)
    return RecordingSource(left=args.left, depth=args.depth, bag=None if args.bag is None else str(args.bag),
                           left_topic=args.left_topic, depth_topic=args.depth_topic, max_dt_s=args.max_dt,
                           depth_scale_m=args.depth_scale)


def _check_device(args: argparse.Namespace) -> None:
    """Device depth: left images + --depth, or --bag with --left-topic + --depth-topic; no stereo form beside it."""
    others = [flag for flag, value in (("--right", args.right), ("--right-topic", args.right_topic),
                                       ("--video", args.video), ("--left-video", args.left_video),
                                       ("--right-video", args.right_video), ("FOLDER", args.recording)) if value]
    if others:
        raise DepthError("give exactly one depth source", field="--depth/" + others[0],
                         hint="stereo pairs (a recording) or device depth (--depth / --depth-topic), not both")
    if args.bag is None and (args.left_topic or args.depth_topic):
        raise DepthError("topics need --bag", field="--left-topic", hint="pass --bag BAG")
    if args.bag is not None and not args.left_topic:
        raise DepthError("a bag needs --left-topic", field="--left-topic", hint="e.g. /camera/infra1/image_rect_raw")
    if args.bag is None and args.left is None and not args.wall:
        raise DepthError("missing left images", field="--left", hint="pass --left DIR|GLOB")


def _check_args(args: argparse.Namespace) -> None:
    if _device(args):
        _check_device(args)
    elif args.left is not None and args.right is None:
        raise DepthError("give exactly one depth source", field="--right/--depth",
                         hint="--right DIR|GLOB (stereo through the pipeline) or --depth DIR|GLOB (device depth)")
    else:
        from s2r.cli._recording import spec_from_args

        spec_from_args(args).check(error=DepthError)
    if not args.wall and (args.pattern is None or args.square is None):
        raise DepthError("board mode needs the board", field="--pattern/--square",
                         hint="pass --pattern COLSxROWS (inner corners) and --square METRES, or --wall")
    if args.square is not None and not args.square > 0:
        raise DepthError(f"must be positive metres, got {args.square}", field="--square", hint="e.g. 0.025")
    if args.distance is not None and not args.distance > 0:
        raise DepthError(f"must be positive metres, got {args.distance}", field="--distance", hint="e.g. 1.5")
    if not 0 < args.max_dt < float("inf"):
        raise DepthError(f"must be positive seconds, got {args.max_dt}", field="--max-dt", hint="e.g. 0.01")
    if not 0 < args.depth_scale < float("inf"):
        raise DepthError(f"must be positive, got {args.depth_scale}", field="--depth-scale", hint="0.001 for mm")


def _measure(args: argparse.Namespace, profile: StereoProfile, source: RecordingSource) -> QualityResult:
    from s2r.quality.run import measure_board_views, measure_wall_views
    from s2r.quality.source import open_source

    if not args.wall and args.left is not None:  # a wrong --pattern named in a second, before every frame's search
        check_left_board(args.left, args.pattern)
    opened = open_source(profile, source, preset=args.preset, num_disparities=args.num_disparities)
    bar = ProgressBar(enabled=False if (args.quiet or args.json) else None)
    keep = REPORT_FRAMES if args.report else 0
    if args.wall:
        return measure_wall_views(profile, opened.views, fb_px_m=opened.fb_px_m,
                                  source=f"{opened.description}, flat wall", roi_fraction=args.roi,
                                  distance_m=args.distance, progress=bar, total=opened.total, keep_images=keep)
    return measure_board_views(profile, opened.views, pattern=args.pattern, square_m=args.square,
                               fb_px_m=opened.fb_px_m, source=opened.description, total=opened.total,
                               visible_m=opened.visible_m, progress=bar, keep_images=keep)


def _cmd_depth_quality(args: argparse.Namespace) -> int:
    from s2r.quality.report import quality_lines, write_quality_report

    name = profile_argument(args, command="depth-quality")  # first: with --profile the positional may be the FOLDER
    _check_args(args)
    source = _source(args)
    profile = load_profile(name)
    if args.report:
        prepare_output_dir(args.report, force=args.force)
        check_output_free(Path(args.report) / "depth_quality.html", force=args.force)
    result = _measure(args, profile, source)
    if args.json:
        from s2r.quality.report import verdict

        print_json({**result.as_dict(), "verdict": verdict(result).as_dict()})
    else:
        print("\n".join(quality_lines(result)))
    if args.report:
        path = write_quality_report(result, args.report, force=True)
        print(f"report: {path}", file=sys.stderr if args.json else sys.stdout)
    return 0
