"""``s2r lint``, ``s2r profile from-urdf`` and ``s2r profile export-gazebo``: robot descriptions <-> profiles."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

from s2r.cli._common import add_force, add_json, load_profile, print_json
from s2r.errors import SourceError
from s2r.fileio import atomic_write_text, check_output_free

__all__ = ["CONVENTION_CHOICES", "EXPORT_FORMAT_CHOICES", "parse_env_values", "parse_xacro_args", "register"]

#: ``s2r.sources.CONVENTIONS`` and ``EXPORT_FORMATS``, repeated here so that building the parser does not import
#: s2r.sources (the robot-description readers load only when a description command runs; a test keeps them equal).
CONVENTION_CHOICES = ("gazebo-classic", "gz-sim", "exact")
EXPORT_FORMAT_CHOICES = ("urdf", "sdf", "gz-sim")

EXIT_OK, EXIT_FINDINGS = 0, 1
logger = logging.getLogger("s2r.cli")


def parse_xacro_args(items: list[str]) -> dict[str, str]:
    """``["name:=value", ...]`` -> mapping; SourceError naming the bad item otherwise."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition(":=")
        if not sep or not name:
            raise SourceError(f"cannot read xacro argument {item!r}", field="NAME:=VALUE",
                              hint="write xacro arguments as name:=value after the file")
        out[name] = value
    return out


def parse_env_values(items: list[str]) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` (``--env``) -> mapping; SourceError naming the bad item otherwise."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.replace("_", "a").isalnum() or not name.isascii():
            raise SourceError(f"cannot read --env {item!r}", field="--env",
                              hint="write --env NAME=VALUE with a variable name of letters, digits and '_'")
        out[name] = value
    return out


def _add_description_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", type=Path, help="robot description: .urdf, .xacro / .urdf.xacro, .sdf, .world or a "
                   "MuJoCo MJCF model (<mujoco> root)")
    p.add_argument("xacro_args", nargs="*", metavar="NAME:=VALUE", help="xacro arguments, right after FILE")
    p.add_argument("--arg", dest="xacro_more", action="append", default=[], metavar="NAME:=VALUE",
                   help="a xacro argument anywhere on the line (repeatable)")
    p.add_argument("--env", dest="env_values", action="append", default=[], metavar="NAME=VALUE",
                   help="a value xacro's $(env NAME) / $(optenv NAME default) see, e.g. JACKAL_BB2=1 (repeatable; "
                   "the machine's environment is never read)")
    p.add_argument("--package-path", type=Path, action="append", default=[], metavar="DIR",
                   help="folder searched for $(find pkg) (repeatable; then ROS_PACKAGE_PATH)")
    p.add_argument("--left", default=None, help="left camera (sensor, sensor/camera, camera or link name)")
    p.add_argument("--right", default=None, help="right camera")
    p.add_argument("--keyframe", default=None, metavar="N",
                   help="MJCF: read the bodies at this <keyframe> (index or name) instead of the initial state")


def register(sub: Any, profile_sub: Any) -> None:
    """Add ``s2r lint`` and ``s2r profile from-description`` (alias ``from-urdf``) / ``export-gazebo``."""
    p_lint: argparse.ArgumentParser = sub.add_parser(
        "lint", help="check a robot description's stereo cameras for common mistakes",
        description="Findings with severity, file:line and the fix. Exit 1 on any error-level finding.")
    _add_description_options(p_lint)
    p_lint.add_argument("--camera-info", type=Path, default=None, metavar="FILE",
                        help="a published camera_info (ROS YAML or rostopic echo text) to check against the file")
    add_json(p_lint)
    p_lint.set_defaults(func=_cmd_lint)

    for command in ("from-description", "from-urdf"):
        _add_from_description(profile_sub, command)
    p_exp: argparse.ArgumentParser = profile_sub.add_parser(
        "export-gazebo", help="Gazebo sensor XML that makes a simulated camera match a profile",
        description="Sensor blocks and the baseline joint/poses; warnings say what the format cannot express.")
    p_exp.add_argument("profile", help="profile name or path")
    p_exp.add_argument("--format", dest="fmt", choices=EXPORT_FORMAT_CHOICES, default="urdf",
                       help="urdf (Gazebo classic, two sensors), sdf (classic multicamera) or gz-sim")
    p_exp.add_argument("-o", "--output", type=Path, required=True, help="XML file to write")
    p_exp.add_argument("--noise", type=float, default=None, metavar="SIGMA",
                       help="Gaussian image noise stddev of the sensor (intensities 0..1); default --sensor-model's "
                       "or the profile's sensor: image_noise_dn / 255, else simulation.noise_stddev; none without "
                       "one (a calibration's RMS is not sensor noise)")
    p_exp.add_argument("--sensor-model", type=Path, default=None, metavar="FILE",
                       help="sensor.yaml from s2r sensor fit: its image noise becomes the sensor's <noise>")
    p_exp.add_argument("--parent-link", default=None, metavar="LINK",
                       help="urdf: mount the rig on this robot link with a fixed joint (edit its origin)")
    add_force(p_exp)
    p_exp.set_defaults(func=_cmd_export)

    p_regen: argparse.ArgumentParser = profile_sub.add_parser(
        "regenerate-sim", help="regenerate the shipped sim profiles from urdf/",
        description="Rewrite profiles/sim/*.yaml from the shipped robot descriptions (byte-reproducible).")
    p_regen.add_argument("--check", action="store_true", help="only compare; exit 1 when a file is out of date")
    p_regen.set_defaults(func=_cmd_regenerate)


def _add_from_description(profile_sub: Any, command: str) -> None:
    """``s2r profile from-description`` (and its older name ``from-urdf``, the same command)."""
    p_from: argparse.ArgumentParser = profile_sub.add_parser(
        command, help="a sim profile from a robot description (URDF / xacro / SDF / MuJoCo MJCF)"
        if command == "from-description" else "the same as from-description (its older name)",
        description="Two camera sensors (or one multicamera, or two MJCF cameras) to a sim stereo profile in a "
        "stated convention.")
    _add_description_options(p_from)
    p_from.add_argument("-o", "--output", type=Path, required=True, help="profile YAML to write")
    p_from.add_argument("--convention", choices=CONVENTION_CHOICES, default=None,
                        help="pixel convention of the intrinsics (default: inferred from the simulator the file "
                        "loads: gz-sim systems -> gz-sim, gazebo_ros plugins -> gazebo-classic; else gazebo-classic; "
                        "MJCF: exact, the only one)")
    p_from.add_argument("--name", default=None, help="profile name (default: the description file's name)")
    p_from.add_argument("--allow-bad-baseline", action="store_true",
                        help="write a pair lint calls an error (baseline along the optical axis, right camera on "
                        "the left) with a warning instead of refusing it")
    p_from.add_argument("--optical-links", action="store_true", help=argparse.SUPPRESS)
    add_force(p_from)
    add_json(p_from)
    p_from.set_defaults(func=_cmd_from_urdf)


def _cmd_lint(args: argparse.Namespace) -> int:
    from s2r.sources.lint.rules import lint_description

    info = None
    if args.camera_info is not None:
        from s2r.formats.ros_read import read_camera_info

        info = read_camera_info(args.camera_info)
    xacro_args = parse_xacro_args(args.xacro_args + args.xacro_more)
    findings = lint_description(args.file, camera_info=info, xacro_args=xacro_args, package_paths=args.package_path,
                                left=args.left, right=args.right, env=parse_env_values(args.env_values),
                                keyframe=args.keyframe)
    errors = sum(f.severity == "error" for f in findings)
    if args.json:
        print_json({"file": str(args.file), "errors": errors, "findings": [f.as_dict() for f in findings]})
    else:
        for finding in findings:
            print(finding.one_line())
        counts = {s: sum(f.severity == s for f in findings) for s in ("error", "warning", "info")}
        print(f"{args.file}: {counts['error']} error(s), {counts['warning']} warning(s), {counts['info']} info")
    return EXIT_FINDINGS if errors else EXIT_OK


def _cmd_from_urdf(args: argparse.Namespace) -> int:
    from s2r.formats.s2r_yaml import dump_profile
    from s2r.sources.profile_builder import load_description_profile

    check_output_free(args.output, force=args.force)
    if args.optical_links:
        logger.warning("--optical-links is ignored: the optical axes come from the sensor poses (Gazebo renders "
                       "along the camera frame's +x whatever the link is called)")
    profile = load_description_profile(
        args.file, convention=args.convention, left=args.left, right=args.right,
        xacro_args=parse_xacro_args(args.xacro_args + args.xacro_more), package_paths=args.package_path, name=args.name,
        allow_bad_baseline=args.allow_bad_baseline, env=parse_env_values(args.env_values), keyframe=args.keyframe)
    dump_profile(profile, args.output, force=args.force)
    if args.json:
        print_json({"output": str(args.output), "profile": profile})
        return EXIT_OK
    left = profile.left
    t = profile.T
    print(f"wrote {args.output}: {profile.name} ({profile.provenance.convention}) {left.width_px}x{left.height_px} "
          f"fx {left.fx_px:.3f} fy {left.fy_px:.3f} cx {left.cx_px:.2f} cy {left.cy_px:.2f}, baseline "
          f"{profile.baseline_m:.4f} m, T = ({t[0]:+.4f}, {t[1]:+.4f}, {t[2]:+.4f})")
    return EXIT_OK


def _cmd_export(args: argparse.Namespace) -> int:
    from s2r.sources.export.gazebo import export_gazebo

    check_output_free(args.output, force=args.force)
    profile = load_profile(args.profile)
    if args.sensor_model is not None:
        from s2r.sensor.files import load_sensor_model

        profile = profile.model_copy(update={"sensor": load_sensor_model(args.sensor_model)})
    text, warnings = export_gazebo(profile, fmt=args.fmt, noise=args.noise, parent_link=args.parent_link)
    for warning in warnings:
        logger.warning("%s", warning)
    atomic_write_text(args.output, text, force=args.force)
    print(f"wrote {args.output} ({args.fmt}, {len(warnings)} warning(s))", file=sys.stdout)
    return EXIT_OK


def _cmd_regenerate(args: argparse.Namespace) -> int:
    from s2r.formats.s2r_yaml import profile_to_yaml
    from s2r.sources.shipped import REPO_ROOT, shipped_profiles

    stale = 0
    for path, profile in shipped_profiles().items():
        text = profile_to_yaml(profile)
        if path.exists() and path.read_text(encoding="utf-8") == text:
            continue
        stale += 1
        if not args.check:
            atomic_write_text(path, text, force=True)
        print(f"{'stale' if args.check else 'wrote'} {path.relative_to(REPO_ROOT)}")
    return EXIT_FINDINGS if args.check and stale else EXIT_OK
