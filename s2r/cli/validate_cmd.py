"""``s2r validate SIM [REAL]``: is the simulated camera a faithful twin of the real one?

Exit codes: 0 every figure within tolerance, 1 something is not (listed), 2 bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import sys
from typing import Any

from s2r.cli._common import (
    ProgressBar,
    add_force,
    add_json,
    argparse_type,
    load_profile,
    parse_distances,
    parse_pattern,
    print_json,
)
from s2r.errors import ValidateError
from s2r.fileio import prepare_output_dir

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``validate``."""
    parser = sub.add_parser(
        "validate", help="compare a sim profile with a real one (or self-check one profile)",
        description="Parameters, projection difference, depth resolution, recovered calibration and depth "
        "accuracy of a sim profile against a real one, with the edits that make the sim match. With one "
        "profile: its self-check (recovered calibration and depth accuracy against theory). Exit 0 all within "
        "tolerance, 1 otherwise, 2 bad input.")
    parser.add_argument("sim", metavar="SIM", help="sim profile name or path (or the one profile to self-check)")
    parser.add_argument("real", metavar="REAL", nargs="?", help="real profile name or path")
    parser.add_argument("-o", "--output", "--report", dest="report", metavar="DIR",
                        help="write DIR/validation.html (self-contained); --report is kept as an alias")
    parser.add_argument("--tolerances", metavar="FILE", help="YAML file of tolerance overrides (key: number)")
    parser.add_argument("--quick", action="store_true",
                        help="fewer board views (1x) and planes, no slanted plane (about 34 s of CPU time for two "
                        "profiles)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the rendered boards and textures")
    parser.add_argument("--jobs", type=int, default=None, metavar="N", help="parallel processes (default: cores)")
    parser.add_argument("--preset", default="profile",
                        help="depth pipeline preset for both profiles (profile, seed-sgbm, fast, bm, ros-default)")
    parser.add_argument("--distances", metavar="M,M,...", help="plane distances in metres (default by mode)")
    parser.add_argument("--recording", metavar="DIR", help="real stereo chessboard pairs (left/ right/ or leftNN/"
                        "rightNN): measure the real camera on them and the sim on the same boards at the same poses")
    parser.add_argument("--pattern", type=argparse_type(parse_pattern), default=(9, 6),
                        help="--recording board's inner corners COLSxROWS (default 9x6)")
    parser.add_argument("--square", type=float, default=0.025, help="--recording board's square size, m (0.025)")
    from s2r.cli.render_cmd import add_renderer

    add_renderer(parser, scene_alias=True)
    add_json(parser)
    add_force(parser)
    parser.set_defaults(func=_cmd_validate)


def _cmd_validate(args: argparse.Namespace) -> int:
    from s2r.validate.report import write_validation_report
    from s2r.validate.run import FULL, QUICK, validate
    from s2r.validate.summary import summary_lines
    from s2r.validate.tolerances import load_tolerances

    if args.jobs is not None and args.jobs < 1:
        raise ValidateError(f"must be at least 1, got {args.jobs}", field="--jobs")
    if args.seed < 0:  # numpy's generators take non-negative seeds only (was an internal error)
        raise ValidateError(f"must be 0 or more, got {args.seed}", field="--seed", hint="e.g. 0")
    tolerances = load_tolerances(args.tolerances)
    sim = load_profile(args.sim)
    real = None if args.real is None else load_profile(args.real)
    from s2r.depth.pipeline import check_side_by_side  # OpenCV loads only when a command needs it

    check_side_by_side(sim, path=args.sim)  # a vertical rig: one line now, not a confusing depth range later
    if real is not None:
        check_side_by_side(real, path=args.real)
    settings = dataclasses.replace(QUICK if args.quick else FULL, seed=args.seed, preset=args.preset,
                                   renderer=args.renderer, scene_path=None if args.world is None else str(args.world),
                                   scene_camera=args.world_camera)
    if args.renderer != "pybullet" or args.world is not None:
        from s2r.cli.render_cmd import renderer_choice
        from s2r.render.backend import check_renderer

        check_renderer(renderer_choice(args), probe_gl=True)  # MuJoCo missing, no GL, a bad world file: one line now
    if args.distances is not None:
        try:
            settings = dataclasses.replace(settings, distances_m=parse_distances(args.distances))
        except ValueError as exc:
            raise ValidateError(str(exc), field="--distances") from None
    else:  # the default planes a short-range rig cannot see are dropped with a warning, not a refusal
        from s2r.validate.run import distances_in_view

        settings = dataclasses.replace(settings, distances_m=distances_in_view(
            [p for p in (sim, real) if p is not None], settings.preset, settings.distances_m))
    recording = _recording(args, real is not None)
    if args.report:
        prepare_output_dir(args.report, force=args.force)  # fail before the work, not after
    quiet = args.quiet or args.json
    result = validate(sim, real, tolerances=tolerances, settings=settings, jobs=args.jobs,
                      progress=None if quiet else ProgressBar(), recording=recording)
    if args.real is not None:  # the "write them" command names the real profile as the user did (a path works)
        result.edits = [dataclasses.replace(e, where=e.where.replace(f"export-gazebo {e.target} ",
                                                                     f"export-gazebo {shlex.quote(args.real)} ", 1))
                        if e.parameter == "sensor XML" else e for e in result.edits]
    if args.json:
        print_json(result.as_dict())
    else:
        print("\n".join(summary_lines(result)))
    if args.report:
        path = write_validation_report(result, args.report, force=True)
        print(f"report: {path}", file=sys.stderr if args.json else sys.stdout)
    return 0 if result.passed else 1


def _recording(args: argparse.Namespace, pair: bool) -> Any:
    """The --recording spec (checked before any work), or None."""
    from pathlib import Path

    from s2r.validate.run import RecordingSpec

    if args.recording is None:
        return None
    if not pair:
        raise ValidateError("--recording compares a sim with a real camera", field="--recording",
                            hint="pass SIM REAL profiles")
    if not Path(args.recording).is_dir():
        raise ValidateError("recording folder not found", path=args.recording, field="--recording",
                            hint="pass a folder with left/ and right/ or leftNN/rightNN images")
    if not args.square > 0:
        raise ValidateError(f"must be positive metres, got {args.square}", field="--square", hint="e.g. 0.025")
    return RecordingSpec(str(args.recording), tuple(args.pattern), float(args.square))
