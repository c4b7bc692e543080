"""``s2r profile export-mujoco``: an MJCF camera pair that renders like a profile."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path
from typing import Any

from s2r.cli._common import add_force, add_json, load_profile, print_json
from s2r.fileio import atomic_write_text, check_output_free

__all__ = ["register"]

logger = logging.getLogger("s2r")


def register(profile_sub: Any) -> None:
    """Add ``s2r profile export-mujoco``."""
    p_exp: argparse.ArgumentParser = profile_sub.add_parser(
        "export-mujoco", help="an MJCF body with two cameras that renders like a profile (MuJoCo)",
        description="A complete <mujoco> file (load it, or <include> it in your scene): one body (x forward, y left, "
        "z up; the left camera at its origin) holding the left and right cameras with resolution, sensorsize, "
        "focalpixel and principalpixel (fx != fy and off-centre principal points survive) and the stereo pose. "
        "MJCF has no lens distortion: a warning names the residual in pixels.")
    p_exp.add_argument("profile", help="profile name or path")
    p_exp.add_argument("--body", default="s2r_stereo", metavar="NAME",
                       help="name of the body (cameras are NAME_left and NAME_right; default s2r_stereo)")
    p_exp.add_argument("-o", "--output", type=Path, required=True, help="MJCF file to write")
    add_force(p_exp)
    add_json(p_exp)
    p_exp.set_defaults(func=_cmd_export_mujoco)


def _cmd_export_mujoco(args: argparse.Namespace) -> int:
    from s2r.sources.export.mujoco import export_mujoco

    check_output_free(args.output, force=args.force)
    profile = load_profile(args.profile)
    text, warnings = export_mujoco(profile, body=args.body)
    for warning in warnings:
        logger.warning("%s", warning)
    atomic_write_text(args.output, text, force=args.force)
    if args.json:
        print_json({"output": args.output, "body": args.body, "cameras": [f"{args.body}_left", f"{args.body}_right"],
                    "warnings": warnings})
    else:
        print(f"wrote {args.output} (body {args.body}: cameras {args.body}_left, {args.body}_right; "
              f"{len(warnings)} warning(s))")
    return 0
