"""``s2r depth PROFILE <recording> -o OUT --to files|ros2|ros1``: depth of every frame of a recording, streamed.

The positionals and the stream options of ``s2r depth`` live here; the command itself is :mod:`.depth_cmd`.
"""

from __future__ import annotations

import argparse
import logging
import re
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from s2r.cli._common import ProgressBar, positional_is_profile, print_json
from s2r.errors import DepthError

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.depth.stream import DepthFrame

__all__ = ["add_stream_arguments", "check_target_options", "recording_given", "run_stream", "split_inputs"]

log = logging.getLogger(__name__)

_RECORDING_OPTIONS = ("recording", "left", "right", "bag", "video", "left_video", "right_video")


def add_stream_arguments(parser: argparse.ArgumentParser) -> None:
    """``--to``, ``--namespace``, ``--depth-encoding``, ``--points``, ``--pcd``."""
    group = parser.add_argument_group("stream outputs (a recording, or --to ros1/ros2 for any input)")
    group.add_argument("--to", choices=("files", "ros2", "ros1"), default="files",
                       help="files (default): depth/NAME.png + .npy, disparity/NAME.npy, color/NAME.png, frames.csv; "
                       "ros2: a ROS 2 bag folder (mcap); ros1: a ROS 1 .bag")
    group.add_argument("--namespace", default="/stereo", help="bags: topic namespace (default /stereo)")
    group.add_argument("--depth-encoding", choices=("32FC1", "16UC1"), default="32FC1",
                       help="bags: depth image as float metres (32FC1, default) or uint16 millimetres (16UC1)")
    group.add_argument("--points", action="store_true",
                       help="bags: PointCloud2 on NAMESPACE/points2; files: points/NAME.ply (as --ply)")
    group.add_argument("--pcd", action="store_true", help="files: also points/NAME.pcd (binary PCD)")


def _is_image(text: str) -> bool:
    from s2r.recordings.pairing import IMAGE_SUFFIXES

    return Path(text).suffix.lower() in IMAGE_SUFFIXES


def split_inputs(args: argparse.Namespace) -> None:
    """Read the positionals: ``PROFILE [LEFT RIGHT | FOLDER]``; with ``--profile`` or ``--rectified`` they are only
    the inputs, and two image files alone are ``LEFT RIGHT`` with ``$S2R_PROFILE`` (the older order)."""
    items = [str(v) for v in args.inputs]
    if args.profile is not None and items and positional_is_profile(items[0], args.profile, command="depth"):
        items.pop(0)  # the same profile twice; another one is refused, never read as an image or a recording
    older = len(items) == 2 and all(_is_image(v) for v in items)
    if args.profile is None and not args.rectified and items and not older:
        args.profile = items.pop(0)
    args.pair_left = args.pair_right = args.recording = None
    if len(items) > 2:
        raise DepthError(f"too many inputs: {' '.join(items)}", field="PROFILE",
                         hint="give PROFILE LEFT RIGHT, or PROFILE FOLDER, or PROFILE and --bag/--video/--left ...")
    if len(items) == 2:
        args.pair_left, args.pair_right = Path(items[0]), Path(items[1])
    elif len(items) == 1:
        if _is_image(items[0]):
            raise DepthError("one image given; a pair needs LEFT and RIGHT", path=items[0], field="LEFT RIGHT",
                             hint="pass PROFILE LEFT RIGHT")
        args.recording = Path(items[0])


def recording_given(args: argparse.Namespace) -> bool:
    """Whether any recording input (FOLDER or a recording option) was given."""
    return any(getattr(args, name, None) is not None for name in _RECORDING_OPTIONS)


def _frames(args: argparse.Namespace, pipeline: StereoPipeline) -> tuple[Any, str, Any]:
    """The frames to stream, a description of them and their source (None for the --left-dir pairs or the one
    pair, which skip nothing)."""
    from s2r.depth.sequence import pair_frames, pair_images

    if args.left_dir is not None:
        return pair_frames(pair_images(args.left_dir, args.right_dir)), f"{args.left_dir} + {args.right_dir}", None
    if args.pair_left is not None:
        return pair_frames([(args.pair_left, args.pair_right)]), f"{args.pair_left} + {args.pair_right}", None
    from s2r.cli._recording import recording_from_args

    size = None if args.resize else pipeline.profile.image_size
    source = recording_from_args(args, expected_size=size, error=DepthError, positional="recording")
    return source.frames(), source.describe(), source


def _warn_skipped(described: str, skipped: list[str]) -> None:
    """Say how many inputs had no partner and were skipped, naming the first few."""
    from s2r.recordings import NAMED_SKIPPED

    if skipped:
        more = f" and {len(skipped) - NAMED_SKIPPED} more" if len(skipped) > NAMED_SKIPPED else ""
        log.warning("%s: %d input image(s) had no partner and were skipped (no depth for them): %s%s", described,
                    len(skipped), ", ".join(skipped[:NAMED_SKIPPED]), more)


#: A global ROS graph-resource namespace (ROS 1 and ROS 2 naming rules): "/" or "/a/b_2" (no empty or digit-led parts).
_ROS_NAMESPACE = re.compile(r"/|(/[A-Za-z][A-Za-z0-9_]*)+")


def check_target_options(args: argparse.Namespace) -> None:
    """Refuse an option of another ``--to`` target: it would be ignored."""
    files = args.to == "files"
    misplaced = ([("--pcd", args.pcd), ("--ply", args.ply)] if not files else
                 [("--depth-encoding", args.depth_encoding != "32FC1"), ("--namespace", args.namespace != "/stereo")])
    for option, given in misplaced:
        if given:
            raise DepthError(f"does not apply to --to {args.to}", field=option, hint=f"drop {option}")
    if not _ROS_NAMESPACE.fullmatch(args.namespace):
        raise DepthError(f"{args.namespace!r} is not a ROS namespace", field="--namespace",
                         hint="'/' then names of letters, digits and _ each starting with a letter, e.g. /stereo or "
                              "/robot1/front_stereo")


def _check_output(args: argparse.Namespace) -> None:
    """Refuse an output that is or holds an input (the folder, a bag, a video), or lies inside a bag folder: even
    ``--force`` must never replace the recording it reads."""
    out = args.output.resolve()
    for option in ("recording", "bag", "video", "left_video", "right_video", "left", "right"):
        given = getattr(args, option, None)
        if given is None or any(ch in str(given) for ch in "*?["):
            continue
        source = Path(given).resolve()
        if out == source or out in source.parents or (option == "bag" and source in out.parents):
            flag = "FOLDER" if option == "recording" else "--" + option.replace("_", "-")
            raise DepthError(f"the output is the input ({flag} {given}) or overlaps it", path=args.output,
                             field="--output", hint="choose an -o outside the recording")


def run_stream(args: argparse.Namespace, pipeline: StereoPipeline) -> int:
    """Stream the input through the pipeline into the ``--to`` writer; publish whole; print a summary."""
    from s2r.depth.stream import STAMP_SYNTHESIZED
    from s2r.depth.writers import StreamOptions, open_writer, write_stream
    from s2r.recordings import skipped_fields, skipped_inputs

    _check_output(args)
    options = StreamOptions(namespace=args.namespace, depth_encoding=args.depth_encoding,
                            points=args.points or args.ply, pcd=args.pcd, colour_range_m=args.colour_range)
    m = pipeline.profile.matcher
    depth_range = None if args.keep_out_of_range else (m.min_depth_m, m.max_depth_m)
    seen: dict[str, Any] = {}
    # the inputs are listed first: an output folder holding one (through a symlinked subfolder too) is refused
    # before --force moves it aside
    frames, described, source = _frames(args, pipeline)
    with open_writer(args.to, args.output, pipeline, force=args.force, options=options) as writer:
        stream = _noting(pipeline.stream(frames, workers=args.jobs, depth_range_m=depth_range), seen)
        count = write_stream(writer, stream, progress=ProgressBar(enabled=None if not args.quiet else False))
        published = writer.publish()
    skipped = skipped_inputs(source)
    _warn_skipped(described, skipped)
    synthesized = STAMP_SYNTHESIZED in seen.get("stamp_sources", ())
    if synthesized:
        log.warning("the input carries no time stamps (still files): stamps were synthesized, 1 s + 0.1 s per frame "
                    "(frames.csv / the bag say so)")
    stamps = "synthesized" if synthesized else _stamp_origin(seen)
    summary = {"profile": pipeline.profile.name, "preset": pipeline.preset, "to": args.to, "frames": count,
               "input": described, "output": str(args.output), "frame_id": seen.get("frame_id"),
               "stamps": stamps, "published": [str(p) for p in published],
               **skipped_fields(skipped)}
    if args.json:
        print_json(summary)
    else:
        unpaired = f", {len(skipped)} unpaired input image(s) skipped" if skipped else ""
        print(f"{pipeline.profile.name} / {pipeline.preset}: {count} frames of {described} -> {args.output} "
              f"({args.to}, frame_id {seen.get('frame_id')}, {summary['stamps']} stamps{unpaired})")
    return 0


def _stamp_origin(seen: dict[str, Any]) -> str:
    """'recorded', or 'file time' for a video without --start-stamp: its frames are stamped from the file's
    modification time, which a copy may have changed (warned, so a wrong absolute time is not taken as recorded).
    The frames' own ``stamp_source`` (frames.csv says the same per row)."""
    from s2r.recordings.frames import STAMP_FILE_TIME, STAMP_RECORDED

    if STAMP_FILE_TIME not in seen.get("stamp_sources", ()):
        return STAMP_RECORDED
    log.warning("the video's stamps start at its file's modification time (a copy may have changed it): pass "
                "--start-stamp TIME (when the recording began) for true absolute stamps")
    return STAMP_FILE_TIME


def _noting(frames: Iterator[DepthFrame], seen: dict[str, Any]) -> Iterator[DepthFrame]:
    """``frames`` unchanged, noting the frame_id the outputs carry (the first frame's rectified frame) and where
    the stamps come from (``stamp_sources``: synthesized, recorded, file time)."""
    from s2r.depth.stream import rectified_frame_id

    for frame in frames:
        seen.setdefault("frame_id", rectified_frame_id(frame.frame_id))
        seen.setdefault("stamp_sources", set()).add(frame.stamp_source)
        yield frame
