"""``s2r validate SIM [REAL]``: is the simulated camera a faithful twin of the real one?

Exit codes: 0 every figure within tolerance, 1 something is not (listed), 2 bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import shlex
import sys
from typing import Any

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
from s2r.cli._recording import add_recording_arguments, spec_from_args
from s2r.errors import S2RError, ValidateError
from s2r.fileio import prepare_output_dir

__all__ = ["register"]

logger = logging.getLogger(__name__)


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
    add_jobs(parser, default=None, help="parallel processes (default: cores)")
    parser.add_argument("--preset", default="profile",
                        help="depth pipeline preset for both profiles (profile, seed-sgbm, fast, bm, ros-default)")
    parser.add_argument("--distances", metavar="M,M,...", help="plane distances in metres (default by mode)")
    parser.add_argument("--recording", metavar="SRC", help="the real camera's chessboard recording: a folder (left/ "
                        "right/, leftNN/rightNN, or left/ depth/ for device depth; any existing path as it is), or "
                        "'left=GLOB,right=GLOB', 'left=DIR,depth=DIR', 'bag=BAG,left-topic=T,right-topic=T|depth-topic="
                        "T' (quote a value holding commas: left=\"a,b/\"); measured with Intel's metrics per distance "
                        "bin beside the sim. Or give the real recording with the recording options below (videos too)")
    parser.add_argument("--sim-recording", metavar="SRC", help="the sim camera's own recording (same forms as "
                        "--recording, e.g. a Gazebo or MuJoCo run); without it the sim renders the recovered poses")
    parser.add_argument("--pattern", type=argparse_type(parse_pattern), default=(9, 6),
                        help="--recording board's inner corners COLSxROWS (default 9x6)")
    parser.add_argument("--square", type=float, default=0.025, help="--recording board's square size, m (0.025)")
    parser.add_argument("--sim-left", metavar="CAM", help="SIM a robot description (URDF / xacro / SDF / MJCF): its "
                        "left camera (sensor, camera or link name), as s2r profile from-description --left takes it "
                        "(--left/--right here are the real recording's images)")
    parser.add_argument("--sim-right", metavar="CAM", help="SIM a robot description: its right camera")
    parser.add_argument("--roles-as-given", action="store_true",
                        help="compare even when SIM is not a simulated profile or REAL is one (provenance.origin); "
                        "e.g. two sim variants")
    parser.add_argument("--sensor-model", metavar="FILE",
                        help="sensor.yaml (s2r sensor fit): the SIM camera's blur and noise on every sim render; "
                        "default each profile's own sensor: section")
    add_recording_arguments(parser, positional=None, what="the real camera's chessboard stereo recording (instead "
                                                          "of --recording SRC)")
    from s2r.cli.render_cmd import add_renderer

    add_renderer(parser, scene_alias=True)
    add_json(parser)
    add_force(parser)
    parser.set_defaults(func=_cmd_validate)


def _cmd_validate(args: argparse.Namespace) -> int:
    from s2r.validate.run import FULL, QUICK, validate
    from s2r.validate.summary import summary_lines
    from s2r.validate.tolerances import load_tolerances

    check_jobs(args.jobs, ValidateError)
    if args.seed < 0:  # numpy's generators take non-negative seeds only (was an internal error)
        raise ValidateError(f"must be 0 or more, got {args.seed}", field="--seed", hint="e.g. 0")
    tolerances = load_tolerances(args.tolerances)
    sim = _load_sim(args.sim, left=args.sim_left, right=args.sim_right)
    if args.sensor_model is not None:
        from s2r.sensor.files import load_sensor_model

        sim = sim.model_copy(update={"sensor": load_sensor_model(args.sensor_model)})
    if sim.sensor is not None and not args.quiet:
        print(f"sim renders with the sensor model: {sim.sensor.describe()}", file=sys.stderr)
    real = None if args.real is None else load_profile(args.real)
    from s2r.depth.pipeline import check_side_by_side  # OpenCV loads only when a command needs it

    check_side_by_side(sim, path=args.sim)  # a vertical rig: one line now, not a confusing depth range later
    if real is not None:
        check_side_by_side(real, path=args.real)
        if not args.roles_as_given:
            _check_roles(sim, real, sim_path=args.sim, real_path=args.real)
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
    if recording is not None and real is not None:  # every input opened and checked before the first render
        from s2r.validate.recording.compare import check_recording_opens

        check_recording_opens(real, recording.folder, option="--recording", preset=settings.preset)
        if recording.sim is not None:
            check_recording_opens(sim, recording.sim, option="--sim-recording", preset=settings.preset)
    if args.report:
        prepare_output_dir(args.report, force=args.force)  # fail before the work, not after
    quiet = args.quiet or args.json
    bar = None if quiet else ProgressBar()
    if bar is not None:
        bar(0, 100, "validate %")  # a first line at once: in a CI log the first stage takes tens of seconds
    result = validate(sim, real, tolerances=tolerances, settings=settings, jobs=args.jobs,
                      progress=bar, recording=recording)
    if args.real is not None:  # the "write them" command names the real profile as the user did (a path works)
        result.edits = [_named_as_given(e, args.real) for e in result.edits]
    if args.json:
        print_json(result.as_dict())
    else:
        print("\n".join(summary_lines(result)))
    if args.report:
        from s2r.validate.report import write_validation_report  # here: matplotlib loads only for a report

        path = write_validation_report(result, args.report, force=True)
        print(f"report: {path}", file=sys.stderr if args.json else sys.stdout)
    return 0 if result.passed else 1


def _named_as_given(edit: Any, real_path: str) -> Any:
    """An export edit (``export-gazebo`` / ``export-mujoco``) naming the real profile as the user did, so the
    command runs when REAL is a file of theirs (its internal name is no profile the registry knows)."""
    if edit.parameter not in ("sensor XML", "MJCF cameras"):
        return edit
    where = edit.where
    for export in ("export-gazebo", "export-mujoco"):
        where = where.replace(f"{export} {edit.target} ", f"{export} {shlex.quote(real_path)} ", 1)
    return dataclasses.replace(edit, where=where)


def _load_sim(name_or_path: str, *, left: str | None = None, right: str | None = None) -> Any:
    """The SIM profile: a profile name or file, or a robot description (URDF / xacro / SDF / MJCF) read as
    ``s2r profile from-description FILE [--left CAM --right CAM]`` would, so ``validate cameras.xml real.yaml``
    works."""
    from s2r.formats.detect import is_robot_description

    if not is_robot_description(name_or_path):
        if left is not None or right is not None:
            raise ValidateError("--sim-left/--sim-right choose the cameras of a robot description, and SIM is a "
                                "profile", field="--sim-left/--sim-right",
                                hint="drop them, or pass the description file as SIM")
        return load_profile(name_or_path)
    if (left is None) != (right is None):
        raise ValidateError("--sim-left and --sim-right name the pair together", field="--sim-left/--sim-right",
                            hint="pass both, e.g. --sim-left left_cam --sim-right right_cam")
    from s2r.sources.profile_builder import load_description_profile

    try:
        profile = load_description_profile(name_or_path, left=left, right=right)
    except S2RError as error:  # the loader names from-description's options; validate's are --sim-left/--sim-right
        if error.hint and "--left NAME --right NAME" in error.hint:
            raise type(error)(error.message, path=error.path, field=error.field,
                              hint=error.hint.replace("--left NAME --right NAME", "--sim-left NAME --sim-right NAME")
                              ) from error
        raise
    logger.warning("%s: a robot description: SIM is the profile s2r profile from-description derives from it "
                   "(%s convention)", name_or_path, profile.provenance.convention)
    return profile


_ORIGIN_WORDS = {"sim": "a simulated camera (from a robot description)", "real": "a calibrated real camera",
                 "nominal": "a real camera's nominal profile (factory or datasheet)"}


def _check_roles(sim: Any, real: Any, *, sim_path: str, real_path: str) -> None:
    """Refuse SIM and REAL in each other's slots, judged by each profile's ``provenance.origin``.

    A swapped call would label the real camera "sim" and advise editing the hardware towards the simulator.
    """
    sim_origin, real_origin = sim.provenance.origin, real.provenance.origin
    if sim_origin == "sim" and real_origin != "sim":
        return
    if sim_origin != "sim" and real_origin == "sim":
        raise ValidateError(
            f"the roles look swapped: SIM {sim_path} is {_ORIGIN_WORDS[sim_origin]} and REAL {real_path} is "
            f"{_ORIGIN_WORDS[real_origin]}", field="SIM REAL",
            hint=f"give the simulated profile first: s2r validate {shlex.quote(real_path)} {shlex.quote(sim_path)}; "
            "--roles-as-given keeps this order")
    wrong, path, origin = ("REAL", real_path, real_origin) if sim_origin == "sim" else ("SIM", sim_path, sim_origin)
    raise ValidateError(
        f"{wrong} {path} is {_ORIGIN_WORDS[origin]} (provenance.origin: {origin}), as is the other profile",
        field="SIM REAL", hint="pass a sim profile as SIM and a real one as REAL, or --roles-as-given to compare "
        "these two anyway")


def _real_recording(args: argparse.Namespace) -> Any:
    """The real recording: ``--recording SRC`` or the shared recording options (one of them), or None."""
    from s2r.quality.source import RecordingSource, check_source, parse_source

    spec = spec_from_args(args, positional=None)
    if spec.kind == "none":
        return None if args.recording is None else parse_source(args.recording, option="--recording")
    if args.recording is not None:
        raise ValidateError("give the real recording once", field="--recording",
                            hint=f"--recording SRC or {spec.kind} options, not both")
    return check_source(RecordingSource(recording=spec), option="--recording")


def _recording(args: argparse.Namespace, pair: bool) -> Any:
    """The --recording / --sim-recording spec (checked before any work), or None."""
    from s2r.quality.source import parse_source
    from s2r.validate.run import RecordingSpec

    real = _real_recording(args)
    if real is None:
        if args.sim_recording is not None:
            raise ValidateError("--sim-recording is compared with a real recording", field="--sim-recording",
                                hint="pass --recording SRC too")
        return None
    if not pair:
        raise ValidateError("--recording compares a sim with a real camera", field="--recording",
                            hint="pass SIM REAL profiles")
    if args.sim_recording is not None:
        parse_source(args.sim_recording, option="--sim-recording")
    if not args.square > 0:
        raise ValidateError(f"must be positive metres, got {args.square}", field="--square", hint="e.g. 0.025")
    return RecordingSpec(real, tuple(args.pattern), float(args.square), args.sim_recording)
