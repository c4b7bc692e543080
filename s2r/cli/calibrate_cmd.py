"""``s2r calibrate``: chessboard images (folders, globs, ROS bags) to a real profile with quality figures."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import Any

from s2r.cli._common import ProgressBar, add_force, add_jobs, add_json, check_jobs, parse_pattern, print_json
from s2r.cli._recording import add_recording_arguments, spec_from_args
from s2r.errors import CalibrationError, terminal_safe
from s2r.fileio import OutputBatch, check_output_free, discard_on_failure, prepare_output_dir
from s2r.limits import MAX_SQUARE_M

__all__ = ["register"]

EXIT_OK = 0
#: s2r.lens.models.DEFAULT_LENS (repeated so the CLI does not import the solver at start-up).
DEFAULT_LENS = "k1k2p1p2"


def register(sub: Any) -> None:
    """Add ``s2r calibrate``."""
    p: argparse.ArgumentParser = sub.add_parser(
        "calibrate", help="calibrate a stereo rig (or one camera) from chessboard images or a ROS bag",
        description="Chessboard calibration into a real s2r profile, with per-view errors, outliers, "
                    "standard deviations, coverage and an optional HTML report.")
    p.add_argument("--pattern", default=None,
                   help="chessboard inner corners COLSxROWS, e.g. 9x6 (required unless --target)")
    p.add_argument("--square", type=float, default=None,
                   help="square edge in metres, e.g. 0.025 (required unless --target: every length scales with it)")
    p.add_argument("-o", "--output", type=Path, default=None, help="profile YAML to write (required)")
    p.add_argument("--name", default=None, help="profile name (default: the output file's stem)")
    p.add_argument("--report", type=Path, default=None, help="write an HTML report into this folder")
    add_jobs(p, default=None, help="detection and resampling processes (default: all cores)")
    p.add_argument("--distortion", choices=("k1k2p1p2", "k1k2", "plumb_bob", "rational", "equidistant"),
                   default="k1k2p1p2",
                   help="distortion terms to solve (default k1k2p1p2: k3 fixed at 0, as ROS camera_calibration; "
                        "equidistant = --lens fisheye)")
    p.add_argument("--target", type=Path, default=None, metavar="TARGET.yaml",
                   help="board described by a file: Kalibr aprilgrid / checkerboard, or charuco (partial views used)")
    p.add_argument("--lens", choices=("pinhole", "fisheye"), default="pinhole",
                   help="projection model: pinhole (OpenCV's k1..k6 models) or fisheye (equidistant k1..k4)")
    p.add_argument("--max-error", type=float, default=None, metavar="PX",
                   help="drop views whose RMS exceeds PX (default: a robust median/MAD threshold)")
    p.add_argument("--fix-intrinsics", action="store_true",
                   help="ROS's way: each camera's intrinsics from its own views, held fixed in the stereo solve "
                        "(default: one joint solve of both cameras, the extrinsics and every board pose)")
    p.add_argument("--refine-joint", action="store_true", help=argparse.SUPPRESS)  # the default now
    p.add_argument("--swap", action="store_true",
                   help="exchange left and right (when s2r finds the right camera to the left of the left one)")
    p.add_argument("--mono", action="store_true", help="calibrate one camera into a camera-only profile")
    add_recording_arguments(p, positional="input", what="chessboard views (--mono: --left GLOB or FOLDER)")
    p.add_argument("--blur-ratio", type=float, default=0.35, metavar="R",
                   help="video/stream inputs: skip a frame whose sharpness (variance of the Laplacian) is below R "
                        "times the median of the frames before (default 0.35; 0 keeps the absolute floor only)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the corner cache")
    add_json(p)
    add_force(p)
    p.set_defaults(func=run)


def _lens_and_target(args: argparse.Namespace, pattern: tuple[int, int]) -> tuple[str, Any]:
    """``(lens, target or None)``: a target file, or the --pattern chessboard when the lens is a fisheye."""
    lens = "fisheye" if args.distortion == "equidistant" else args.lens
    if lens == "fisheye" and args.distortion not in (DEFAULT_LENS, "equidistant"):
        raise CalibrationError(f"--distortion {args.distortion} is a pinhole model; a fisheye lens solves the "
                               "equidistant k1..k4", field="--distortion", hint="drop --distortion or --lens")
    if args.target is not None:
        from s2r.targets import load_target

        return lens, load_target(args.target)
    if lens == "fisheye":
        from s2r.targets import CheckerboardTarget

        return lens, CheckerboardTarget(target_type="checkerboard", targetCols=pattern[0], targetRows=pattern[1],
                                        rowSpacingMeters=args.square, colSpacingMeters=args.square)
    return lens, None


def _required_board(args: argparse.Namespace) -> None:
    """Every missing required option in one message: the output, and for a chessboard ``--pattern`` and
    ``--square`` (a ``--target`` file has both). No silent board: every length scales with the square."""
    missing = []
    if args.target is None and args.pattern is None:
        missing.append("--pattern COLSxROWS (the chessboard's INNER corners, e.g. 9x6 for a board of 10x7 squares)")
    if args.target is None and args.square is None:
        missing.append("--square METRES (one square's edge: every length scales with it, e.g. 0.025 for 25 mm)")
    if args.output is None:
        missing.append("-o FILE (the profile YAML to write)")
    if missing:
        raise CalibrationError(f"missing required option{'s' if len(missing) > 1 else ''}: " + ", ".join(missing),
                               hint="or describe the board with --target FILE" if args.target is None and
                               len(missing) > int(args.output is None) else None)


def _check_args(args: argparse.Namespace) -> tuple[int, int]:
    _required_board(args)
    if args.target is not None and args.pattern is None:
        args.pattern = "9x6"  # unused: the target file describes the board
    if args.target is not None and args.square is None:
        args.square = 0.025  # unused: the target file gives its spacing
    try:
        pattern = parse_pattern(args.pattern)
    except ValueError as exc:
        raise CalibrationError(str(exc), field="--pattern") from None
    if not args.square > 0:
        raise CalibrationError(f"square size must be positive, got {args.square}", field="--square",
                               hint="give the square edge in metres, e.g. 0.025")
    if not args.square <= MAX_SQUARE_M:
        raise CalibrationError(f"square size {args.square:g} m is over {MAX_SQUARE_M:g} m", field="--square",
                               hint="--square is the square edge in metres; for 25 mm give --square 0.025")
    check_jobs(args.jobs, CalibrationError)
    if not 0 < args.max_dt < float("inf"):
        raise CalibrationError(f"--max-dt must be positive seconds, got {args.max_dt}", field="--max-dt",
                               hint="e.g. --max-dt 0.01")
    if not 0 <= args.blur_ratio < 1:
        raise CalibrationError(f"must be in [0, 1), got {args.blur_ratio}", field="--blur-ratio", hint="e.g. 0.35")
    if args.max_error is not None and not 0 < args.max_error < float("inf"):
        raise CalibrationError("--max-error must be positive", field="--max-error", hint="e.g. --max-error 1.0")
    if not args.mono:
        spec_from_args(args, positional="input").check(error=CalibrationError)
    return pattern


def run(args: argparse.Namespace) -> int:
    """Run ``s2r calibrate``; returns the exit code."""
    pattern = _check_args(args)
    lens, target = _lens_and_target(args, pattern)
    out = check_output_free(args.output, force=args.force)
    if args.report is not None:
        prepare_output_dir(args.report, force=args.force)
    name = args.name or re.sub(r"[^A-Za-z0-9_.\-]", "_", out.stem) or "calibrated"
    common: dict[str, Any] = {
        "pattern": pattern, "square_m": args.square, "name": name, "distortion": args.distortion,
        "max_error_px": args.max_error, "jobs": args.jobs,
        "progress": ProgressBar(enabled=not (args.quiet or args.json)),
        "cache_dir": None if args.no_cache else out.with_name(out.name + ".corners"),
    }
    if common["cache_dir"] is not None and not (common["cache_dir"].exists() or common["cache_dir"].is_symlink()):
        discard_on_failure(common["cache_dir"])  # a failed run leaves no OUT.yaml.corners/ it created
    try:
        result = _solve(args, pattern, lens, target, common)
    except CalibrationError as exc:
        from s2r.calib.solve.solvers.rig import SwappedCamerasError

        if not isinstance(exc, SwappedCamerasError) or not args.swap:
            raise
        raise CalibrationError(exc.message, field=exc.field, path=exc.path,
                               hint="--swap already exchanged the images, so they were right as given: run without "
                               "--swap") from None
    from s2r.formats.s2r_yaml import profile_to_yaml

    with OutputBatch(force=args.force) as batch:  # the profile and its report, both or neither
        batch.add_text(out, profile_to_yaml(result.profile))
        if args.report is not None:
            from s2r.calib.report import write_calibration_report

            write_calibration_report(result, args.report / "index.html", batch=batch)
        batch.publish()
    if args.json:
        print_json({**result.figures(), "board": _board_of(args, target, pattern), "output": str(out),
                    "report": None if args.report is None else str(args.report / "index.html")})
    else:
        _print_summary({**result.figures(), "board": _board_of(args, target, pattern)}, out)
        if args.report is not None:
            print(f"report: {args.report / 'index.html'}")
    return EXIT_OK


def _board_of(args: argparse.Namespace, target: Any, pattern: tuple[int, int]) -> str:
    """The board used, in words (stated by the summary, the JSON and the report)."""
    if target is not None and args.target is not None:
        return f"{target.describe()} (from {args.target})"
    return f"chessboard {pattern[0]}x{pattern[1]} inner corners, {args.square * 1000:g} mm squares"


def _pm(value: float, sd: float | None, digits: int = 2) -> str:
    """``value±std`` with the std in 2 significant digits (never a misleading ±0.00); ``±?`` when unknown."""
    if sd is None:
        return f"{value:.{digits}f}±?"
    return f"{value:.{digits}f}±{sd:.2g}"


def _solve(args: argparse.Namespace, pattern: Any, lens: str, target: Any, common: dict[str, Any]) -> Any:
    """The calibration the arguments ask for: ``--mono`` (files), a bag, a video (any frame stream) or stereo image
    files, each with the chessboard or the ``--target``."""
    if args.mono:
        return _run_mono(args, target, lens, common)
    spec = spec_from_args(args, positional="input").check(error=CalibrationError)
    kw = dict(common)
    if target is not None:
        kw = {k: v for k, v in common.items() if k not in ("square_m",)}
        kw.update(target=target, lens=lens,
                  distortion=DEFAULT_LENS if args.distortion == "equidistant" else args.distortion)
    if spec.kind == "bag" and not _plain_bag(spec):
        return _run_stream(args, spec, kw)  # a librealsense recording: its IR pair, found without topics
    if spec.kind == "bag":
        from s2r.calib.solve.pipelines.stereo_bag import calibrate_stereo_bag

        return calibrate_stereo_bag(args.bag, left_topic=args.left_topic, right_topic=args.right_topic,
                                    max_dt_s=args.max_dt, every=args.every, max_frames=args.max_frames,
                                    fix_intrinsics=args.fix_intrinsics, swap=args.swap, **kw)
    if spec.kind in ("video", "videos"):
        return _run_stream(args, spec, kw)
    from s2r.calib.detect.inputs import find_stereo_pairs

    pairs = _thinned(find_stereo_pairs(args.input, left_glob=args.left, right_glob=args.right), args)
    if target is None:
        from s2r.calib.detect.board_size import check_board_size

        check_board_size(pairs.left, pattern)  # a wrong --pattern named in a second, before the full search
    else:
        from s2r.calib.solve.pipelines.target_stereo import calibrate_stereo_target

        kw.pop("pattern")
        return calibrate_stereo_target(pairs.left, pairs.right, names=pairs.names, unpaired=pairs.unpaired,
                                       fix_intrinsics=args.fix_intrinsics, swap=args.swap, **kw)
    from s2r.calib.detect.pairs import PairDetection

    detection = PairDetection(pairs.left, pairs.right, names=pairs.names, unpaired=pairs.unpaired,
                              swap=args.swap, pattern=pattern, jobs=args.jobs, cache_dir=common["cache_dir"],
                              progress=common["progress"])
    try:  # the workers detect while the solver loads (about 0.2 s of a first run)
        from s2r.calib.solve.pipelines.stereo import calibrate_detected_pairs
    except BaseException:
        detection.cancel()
        raise
    solve = {k: v for k, v in common.items() if k not in ("pattern", "cache_dir")}
    return calibrate_detected_pairs(detection, fix_intrinsics=args.fix_intrinsics, **solve)


def _plain_bag(spec: Any) -> bool:
    """Whether the bag is read through rosbags by topic (not a librealsense recording)."""
    from s2r.recordings import open_recording
    from s2r.recordings.bagsource import BagFrames

    return isinstance(open_recording(spec, error=CalibrationError), BagFrames)


def _thinned(pairs: Any, args: argparse.Namespace) -> Any:
    """``pairs`` (a PairSet) with ``--every`` / ``--max-frames`` applied."""
    from dataclasses import replace

    keep = slice(0, None if args.max_frames is None else args.max_frames * args.every, args.every)
    return replace(pairs, left=pairs.left[keep], right=pairs.right[keep], names=pairs.names[keep])


def _run_stream(args: argparse.Namespace, spec: Any, kw: dict[str, Any]) -> Any:
    """Calibrate from a video (or two): frames streamed, blurred ones and still repeats counted, not kept."""
    from s2r.calib.solve.pipelines.stereo_stream import calibrate_stereo_stream
    from s2r.fileio import sha256_file
    from s2r.profile import SourceFile
    from s2r.recordings import open_recording

    source = open_recording(spec, grey=True, error=CalibrationError)
    files = {"video": [spec.video], "bag": [spec.bag]}.get(spec.kind, [spec.left_video, spec.right_video])
    hashed = [SourceFile(path=str(f), sha256=sha256_file(f)) for f in files]
    return calibrate_stereo_stream(source, sources=hashed, blur_ratio=args.blur_ratio,
                                   fix_intrinsics=args.fix_intrinsics, swap=args.swap, **kw)


def _run_mono(args: argparse.Namespace, target: Any, lens: str, common: dict[str, Any]) -> Any:
    """Calibrate one camera from image files (a folder or ``--left GLOB``)."""
    from s2r.calib.detect.inputs import find_mono_images

    if any(getattr(args, k) is not None for k in ("bag", "video", "left_video", "right_video")):
        raise CalibrationError("--mono reads image files only", field="--mono",
                               hint="export the frames to a folder first, or give --left GLOB")
    images = find_mono_images(args.input, image_glob=args.left)
    images = images[:None if args.max_frames is None else args.max_frames * args.every:args.every]
    if target is None:
        from s2r.calib.detect.board_size import check_board_size
        from s2r.calib.solve.pipelines.mono import calibrate_mono

        check_board_size(images, common["pattern"])
        return calibrate_mono(images, **common)
    from s2r.calib.solve.pipelines.target_mono import calibrate_mono_target

    kw = {k: v for k, v in common.items() if k not in ("pattern", "square_m")}
    kw.update(target=target, lens=lens,
              distortion=DEFAULT_LENS if args.distortion == "equidistant" else args.distortion)
    return calibrate_mono_target(images, **kw)


def _print_summary(figures: dict[str, Any], out: Path) -> None:
    q = figures["quality"] or {}
    verdict = figures.get("verdict")
    if verdict:
        flagged = [r["text"] for r in verdict["reasons"] if r["level"] != "good"]
        print(f"verdict: {verdict['level'].upper()}" + (f" ({'; '.join(flagged)})" if flagged else ""))
    print(f"wrote {out}: {q.get('views_used')} views used, {len(figures['dropped'])} skipped or dropped, "
          f"lens model {q.get('distortion_terms')}")
    if figures.get("board"):
        print(f"  board: {figures['board']}")
    cams = [("camera", figures["camera"])] if "camera" in figures else [("left", figures["left"]),
                                                                         ("right", figures["right"])]
    for label, cam in cams:
        std = cam["std"] or {}
        print(f"  {label:<6} fx {_pm(cam['fx_px'], std.get('fx_px'))}  fy {_pm(cam['fy_px'], std.get('fy_px'))}  "
              f"cx {_pm(cam['cx_px'], std.get('cx_px'))}  cy {_pm(cam['cy_px'], std.get('cy_px'))} px")
    if "baseline_m" in figures:
        t = figures["translation_m"]
        b_std = figures["baseline_std_m"]
        print(f"  T ({t[0] * 1000:+.2f}, {t[1] * 1000:+.2f}, {t[2] * 1000:+.2f}) mm, baseline "
              f"{_pm(figures['baseline_m'] * 1000, None if b_std is None else b_std * 1000)} mm, RMS left "
              f"{q.get('rms_left_px', 0):.3f} right {q.get('rms_right_px', 0):.3f} stereo "
              f"{q.get('rms_stereo_px', 0):.3f} px, epipolar {q.get('epipolar_rms_px', 0):.3f} px")
    else:
        print(f"  RMS {q.get('rms_left_px', 0):.3f} px")
    _print_honest(figures)
    models = figures.get("model_comparison")
    if models:
        print("  held-out error by lens model: " + ", ".join(
            f"{m['model']}{'*' if m['chosen'] else ''} {m['heldout_px']:.3f}" for m in models["models"])
            + " px (* used)")
    _print_frames(figures.get("frames"))
    for d in figures["dropped"]:
        if figures.get("frames") and "consecutive frame(s)" in d["reason"]:
            continue  # a still board's run of frames: counted on the frames line
        rms = "" if d.get("rms_px") is None else f" ({d['rms_px']:.3f} px)"
        print(f"  skipped {terminal_safe(d['name'])}{rms}: {terminal_safe(d['reason'])}")
    for g in figures.get("rejected_corner_groups") or []:
        print(f"  corners left out of {terminal_safe(g['name'])}: {g['left']} left, {g['right']} right "
              f"({terminal_safe(g['reason'])})")


def _print_frames(frames: dict[str, Any] | None) -> None:
    """A stream input's frame counts: read, used as views, and why the others were not kept."""
    if not frames:
        return
    reasons = ", ".join(f"{n} {kind}" for kind, n in frames["not_kept"].items()) or "none"
    print(f"  frames: {frames['read']} read, {frames['views_used']} used as views; not kept: {reasons} (repeat: a "
          "still board, one view; blurred: variance of the Laplacian under the floor of 15 or under "
          f"{frames['blur_ratio']:g} x the median of the frames before)")


def _print_honest(figures: dict[str, Any]) -> None:
    """The stereo held-out error, RMS over all corners beside the inlier RMS, and where each std comes from."""
    if figures.get("rms_all_px") is not None and figures.get("corners_total"):
        q = figures["quality"] or {}
        print(f"  RMS {q.get('rms_stereo_px', 0):.3f} px over the inlier corners, {figures['rms_all_px']:.3f} px over "
              f"all {figures['corners_total']} ({figures['corners_rejected']} rejected as outliers)")
    warp = figures.get("board_warp")
    if warp:
        sd = [f"±{v:.2g}" if v is not None else "±?" for v in warp["warp_std_mm"]]
        print(f"  board bend x {warp['warp_mm'][0]:+.3f}{sd[0]} mm, y {warp['warp_mm'][1]:+.3f}{sd[1]} mm "
              f"({warp['decision']})")
    mono = figures.get("heldout")
    if mono:
        _print_mono_honest(mono)
    held = figures.get("stereo_heldout")
    if not held:
        return
    print(f"  stereo held-out error {held['heldout_px']:.3f} px on pairs left out of the fit ({held['folds']} folds; "
          f"{held['heldout_all_px']:.3f} px with the {held['corners_rejected']} of {held['corners_total']} corners "
          "left out as detector blunders)")
    params = held["parameters"]
    jk = [n for n, p in params.items() if p["std_source"] == "jackknife"]
    print(f"  std: the larger of the covariance and the {held['folds']}-fold jackknife; jackknife for "
          + (", ".join(jk) if jk else "none") + " (both in --json)")


def _print_mono_honest(held: dict[str, Any]) -> None:
    """One camera: the held-out error over views left out, and where each std comes from."""
    print(f"  held-out error {held['heldout_px']:.3f} px over the corners of views left out ({held['folds']} folds, "
          f"one board pose per view; {held['heldout_all_px']:.3f} px over all, {held['corners_rejected']} of "
          f"{held['corners_total']} corners in views beyond the training threshold)")
    jk = [n for n, p in held["parameters"].items() if p["std_source"] == "jackknife"]
    print(f"  std: the larger of the covariance and the {held['folds']}-fold jackknife; jackknife for "
          + (", ".join(jk) if jk else "none") + " (both in --json)")
