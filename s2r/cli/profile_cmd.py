"""``s2r profile list | show | convert``: the shipped and user profiles, and format conversion."""

from __future__ import annotations

import argparse
import math
from typing import Any

from s2r.cli._common import add_json, print_json
from s2r.profile import StereoProfile
from s2r.registry import list_profiles, load_profile

__all__ = ["profile_summary", "register"]


def register(sub: Any) -> Any:
    """Add ``profile`` and its subcommands; return its subparsers so other modules can add more."""
    parser = sub.add_parser("profile", help="list, show and convert stereo profiles")
    profile_sub = parser.add_subparsers(dest="profile_command", required=True, metavar="ACTION")

    p_list = profile_sub.add_parser("list", help="profiles reachable by name")
    add_json(p_list)
    p_list.set_defaults(func=_cmd_list)

    p_show = profile_sub.add_parser("show", help="a profile with its derived figures")
    p_show.add_argument("profile", help="profile name or path")
    add_json(p_show)
    p_show.set_defaults(func=_cmd_show)
    return profile_sub


def profile_summary(profile: StereoProfile) -> dict[str, Any]:
    """The derived figures of a profile (FOV, baseline, depth range, theoretical depth error)."""
    near, far = profile.depth_range_m()
    left, right = profile.left, profile.right
    return {
        "name": profile.name,
        "origin": profile.provenance.origin,
        "convention": profile.provenance.convention,
        "image_size": list(profile.image_size),
        "left": {"fx_px": left.fx_px, "fy_px": left.fy_px, "cx_px": left.cx_px, "cy_px": left.cy_px,
                 "distortion": left.distortion.model, "hfov_deg": math.degrees(left.hfov_rad),
                 "vfov_deg": math.degrees(left.vfov_rad)},
        "right": {"fx_px": right.fx_px, "fy_px": right.fy_px, "cx_px": right.cx_px, "cy_px": right.cy_px,
                  "distortion": right.distortion.model, "hfov_deg": math.degrees(right.hfov_rad),
                  "vfov_deg": math.degrees(right.vfov_rad)},
        "baseline_m": profile.baseline_m,
        "T_m": profile.T.tolist(),
        "rotation_deg": math.degrees(profile.rotation_angle_rad),
        "matcher": profile.matcher.algorithm,
        "num_disparities": profile.matcher.num_disparities or profile.num_disparities_for(),
        "depth_range_m": [near, far],
        "depth_rms_mm": {f"{z:g}m": 1000 * float(profile.depth_rms_m(z)) for z in (0.5, 1.0, 2.0, 3.0, 5.0)},
        "depth_2pct_limit_m": profile.max_depth_within_m(0.02),
    }


def _cmd_list(args: argparse.Namespace) -> int:
    profiles = list_profiles()
    if args.json:
        print_json({name: str(path) for name, path in profiles.items()})
        return 0
    for name, path in profiles.items():
        print(f"{name:<32} {path}")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    profile = load_profile(args.profile)
    summary = profile_summary(profile)
    if args.json:
        print_json({"summary": summary, "profile": profile})
        return 0
    left, right = summary["left"], summary["right"]
    w, h = summary["image_size"]
    print(f"{profile.name}  ({summary['origin']}, {summary['convention']} pixels)  {w}x{h}")
    if profile.description:
        print(f"  {profile.description}")
    print(f"  {'':<10}{'fx':>10}{'fy':>10}{'cx':>9}{'cy':>9}{'HFOV':>8}{'VFOV':>8}  distortion")
    for label, cam in (("left", left), ("right", right)):
        print(f"  {label:<10}{cam['fx_px']:>10.3f}{cam['fy_px']:>10.3f}{cam['cx_px']:>9.2f}{cam['cy_px']:>9.2f}"
              f"{cam['hfov_deg']:>7.1f}°{cam['vfov_deg']:>7.1f}°  {cam['distortion']}")
    t = summary["T_m"]
    print(f"  baseline {1000 * summary['baseline_m']:.2f} mm   T = ({t[0]:+.4f}, {t[1]:+.4f}, {t[2]:+.4f}) m"
          f"   rotation {summary['rotation_deg']:.3f}°")
    near, far = summary["depth_range_m"]
    print(f"  matcher {summary['matcher']}, {summary['num_disparities']} disparities: sees {near:.2f}-{far:.1f} m")
    rms = "  ".join(f"{k} {v:.1f}" for k, v in summary["depth_rms_mm"].items())
    print(f"  theoretical depth RMS (mm, s=0.08 px): {rms}")
    print(f"  stays under 2 % depth error up to {summary['depth_2pct_limit_m']:.2f} m")
    return 0
