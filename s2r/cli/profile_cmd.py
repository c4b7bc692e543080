"""``s2r profile list | show | convert``: the shipped and user profiles, and format conversion."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from s2r.cli._common import add_force, add_json, load_profile, print_json
from s2r.errors import FormatError

if TYPE_CHECKING:  # the formats and the profile models load when a command runs, not when the parser is built
    from s2r.profile import MonoProfile, StereoProfile

__all__ = ["mono_summary", "profile_summary", "register"]


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
    _register_convert(profile_sub)
    return profile_sub


def _size(text: str) -> tuple[int, int]:
    """argparse type for ``WIDTHxHEIGHT``."""
    width, sep, height = text.lower().partition("x")
    if not sep or not width.isdigit() or not height.isdigit() or int(width) <= 0 or int(height) <= 0:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 848x480, got {text!r}")
    return int(width), int(height)


def _register_convert(profile_sub: Any) -> None:
    p_conv = profile_sub.add_parser(
        "convert", help="convert between s2r, ROS camera_info, OpenCV, Kalibr (and import RealSense text)",
        description="Convert a stereo calibration. The input format is detected from the content: s2r YAML, "
        "ROS camera_info (two files: left then right, or a folder with left.yaml/right.yaml; rostopic echo text "
        "works too), OpenCV FileStorage (one file, or intrinsics.yml + extrinsics.yml), Kalibr camchain, "
        "rs-enumerate-devices -c text.",
    )
    p_conv.add_argument("src", nargs="+", metavar="SRC", help="input file(s): one, or two for ROS / OpenCV pairs")
    p_conv.add_argument("--to", required=True, choices=("s2r", "ros", "opencv", "kalibr"), help="output format")
    p_conv.add_argument("-o", "--output", required=True, metavar="OUT",
                        help="output file (for --to ros: a folder receiving left.yaml and right.yaml; one "
                        "camera_info file for a mono profile)")
    p_conv.add_argument("--name", help="profile name of the result (default: from the input)")
    p_conv.add_argument("--origin", default="real", choices=("real", "sim", "nominal"),
                        help="provenance origin of an imported profile (default real)")
    p_conv.add_argument("--image-size", type=_size, metavar="WxH",
                        help="image size for OpenCV files that do not store it (the stereo sample's do not)")
    p_conv.add_argument("--units-m", type=float, default=1.0, metavar="M",
                        help="metres per unit of an OpenCV file's T: the square size when it was calibrated in "
                        "squares, 0.001 for millimetres (default 1: T already in metres)")
    p_conv.add_argument("--resolution", type=_size, metavar="WxH",
                        help="RealSense: which infrared resolution to import (default 848x480 or the only one); "
                        "ZED conf: which section (2208x1242, 1920x1080, 1280x720 or 672x376; default 1280x720)")
    p_conv.add_argument("--left", metavar="CAM", help="Kalibr camchain: the left camera (camN; default cam0)")
    p_conv.add_argument("--right", metavar="CAM", help="Kalibr camchain: the right camera (camM; default cam1)")
    p_conv.add_argument("--swap", action="store_true",
                        help="exchange the left and right cameras (a file whose right camera sits on the left)")
    p_conv.add_argument("--allow-bad-baseline", action="store_true",
                        help="write a pair whose right camera sits on the left or along the optical axis anyway "
                        "(refused by default, as from-urdf and s2r lint do)")
    p_conv.add_argument("--drop-k3", action="store_true",
                        help="Kalibr export: drop a non-zero k3 (radtan has none) instead of refusing")
    add_force(p_conv)
    add_json(p_conv)
    p_conv.set_defaults(func=_cmd_convert)


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
        "depth_range_m": [near, far],  # what the disparity range reaches
        "working_range_m": [max(near, profile.matcher.min_depth_m), min(far, profile.matcher.max_depth_m)],
        "depth_rms_mm": {f"{z:g}m": 1000 * float(profile.depth_rms_m(z)) for z in (0.5, 1.0, 2.0, 3.0, 5.0)},
        "depth_2pct_limit_m": profile.max_depth_within_m(0.02),
    }


def _cmd_list(args: argparse.Namespace) -> int:
    from s2r.registry import list_profiles

    profiles = list_profiles()
    if args.json:
        print_json({name: str(path) for name, path in profiles.items()})
        return 0
    for name, path in profiles.items():
        print(f"{name:<32} {path}")
    return 0


def mono_summary(profile: MonoProfile) -> dict[str, Any]:
    """The derived figures of a mono profile (intrinsics, FOV)."""
    cam = profile.camera
    cal = profile.provenance.calibration
    return {"name": profile.name, "origin": profile.provenance.origin, "convention": profile.provenance.convention,
            "image_size": [cam.width_px, cam.height_px], "fx_px": cam.fx_px, "fy_px": cam.fy_px, "cx_px": cam.cx_px,
            "cy_px": cam.cy_px, "distortion": cam.distortion.model, "coefficients": list(cam.distortion.coefficients),
            "hfov_deg": math.degrees(cam.hfov_rad), "vfov_deg": math.degrees(cam.vfov_rad),
            "rms_px": None if cal is None else cal.rms_left_px}


def _show_mono(path: Path, as_json: bool) -> int:
    from s2r.formats.s2r_yaml import load_mono_profile

    profile = load_mono_profile(path)
    summary = mono_summary(profile)
    if as_json:
        print_json({"summary": summary, "profile": profile})
        return 0
    w, h = summary["image_size"]
    print(f"{profile.name}  (mono, {summary['origin']}, {summary['convention']} pixels)  {w}x{h}")
    print(f"  fx {summary['fx_px']:.3f}  fy {summary['fy_px']:.3f}  cx {summary['cx_px']:.2f}  "
          f"cy {summary['cy_px']:.2f}  HFOV {summary['hfov_deg']:.1f}°  VFOV {summary['vfov_deg']:.1f}°")
    coeffs = " ".join(f"{c:.6g}" for c in summary["coefficients"])
    print(f"  distortion {summary['distortion']}: {coeffs}")
    if summary["rms_px"] is not None:
        print(f"  calibration RMS {summary['rms_px']:.3f} px")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from s2r.formats.mono import is_mono_profile_file
    from s2r.registry import resolve_profile

    path = resolve_profile(args.profile)
    if is_mono_profile_file(path):
        return _show_mono(path, args.json)
    profile = load_profile(path)
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
    x, y, _ = (float(v) for v in -profile.R.T @ profile.T)  # right camera in the left optical frame, metres
    if abs(y) > abs(x):  # the figures below assume a side-by-side pair
        print(f"  warning: vertical rig (right camera {abs(y) * 100:.1f} cm {'below' if y > 0 else 'above'}): "
              "s2r depth and validate need a side-by-side pair")
    print(_range_line(profile, summary))
    rms = "  ".join(f"{k} {v:.1f}" for k, v in summary["depth_rms_mm"].items())
    print(f"  theoretical depth RMS (mm, s=0.08 px): {rms}")
    print(f"  stays under 2 % depth error up to {summary['depth_2pct_limit_m']:.2f} m")
    if profile.sensor is not None:
        print(f"  sensor model: {profile.sensor.describe()}")
    return 0


def _range_line(profile: StereoProfile, summary: dict[str, Any]) -> str:
    """The depth the pipeline gives: the disparity range cut to matcher.min_depth_m..max_depth_m (s2r depth
    drops the rest), with what the disparities alone reach when the cut is narrower."""
    near, far = summary["depth_range_m"]
    lo, hi = summary["working_range_m"]
    line = f"  matcher {summary['matcher']}, {summary['num_disparities']} disparities: depth {lo:.2f}-{hi:.1f} m"
    if (lo, hi) == (near, far):
        return line
    return (line + f" (matcher.min_depth_m..max_depth_m {profile.matcher.min_depth_m:g}-"
            f"{profile.matcher.max_depth_m:g} m; the disparities alone reach {near:.2f}-{far:.1f} m)")


def _write(profile: StereoProfile, args: argparse.Namespace) -> list[Path]:
    out = Path(args.output)
    if args.to == "s2r":
        from s2r.formats.s2r_yaml import dump_profile

        return [dump_profile(profile, out, force=args.force)]
    if args.to == "kalibr":
        from s2r.formats.kalibr import dump_kalibr

        return [dump_kalibr(profile, out, force=args.force, drop_k3=args.drop_k3)]
    if args.to == "ros":
        from s2r.depth.ros_params import ros_disparity_file  # local: OpenCV (rectification) loads only when needed
        from s2r.formats.ros import dump_ros_pair

        return list(dump_ros_pair(profile, out, force=args.force, extra=ros_disparity_file(profile)))
    from s2r.formats.opencv import dump_opencv

    return [dump_opencv(profile, out, force=args.force)]


def _convert_mono(path: Path, args: argparse.Namespace) -> int:
    """A mono profile to s2r, ROS (one camera_info file), Kalibr (cam0) or OpenCV (camera_matrix ...)."""
    from s2r.formats.mono import dump_mono
    from s2r.formats.s2r_yaml import dump_profile, load_mono_profile

    profile = load_mono_profile(path)
    if args.name:
        profile = profile.model_copy(update={"name": args.name})
    out = Path(args.output)
    written = dump_profile(profile, out, force=args.force) if args.to == "s2r" else \
        dump_mono(profile, out, args.to, force=args.force, drop_k3=args.drop_k3)
    if args.json:
        print_json({"input_format": "s2r mono", "inputs": [str(path)], "output_format": args.to,
                    "outputs": [str(written)], "profile": mono_summary(profile)})
        return 0
    cam = profile.camera
    print(f"read s2r mono profile: {path} -> {profile.name} ({cam.width_px}x{cam.height_px}, fx {cam.fx_px:.3f})")
    print(f"wrote {written}")
    return 0


def _cmd_convert(args: argparse.Namespace) -> int:
    from s2r.formats.detect import FORMAT_NAMES, check_layout, detect_format, load_any, swap_cameras
    from s2r.formats.mono import is_mono_profile_file
    from s2r.registry import resolve_profile

    if len(args.src) > 2:
        raise FormatError(f"expected one or two inputs, got {len(args.src)}", field="SRC",
                          hint="two inputs are a ROS left/right pair or OpenCV intrinsics + extrinsics")
    sources = [str(resolve_profile(args.src[0]))] if len(args.src) == 1 else args.src  # a name works too
    if len(sources) == 1 and is_mono_profile_file(sources[0]):
        return _convert_mono(Path(sources[0]), args)
    fmt = detect_format(sources[0])
    profile = load_any(sources, name=args.name, origin=args.origin, image_size=args.image_size,
                       t_scale_m=args.units_m, resolution=args.resolution, cameras=(args.left, args.right),
                       layout_warning=False)
    if args.swap:
        profile = swap_cameras(profile)
    check_layout(profile, sources[-1], allow_bad_baseline=args.allow_bad_baseline)
    written = _write(profile, args)
    if args.json:
        print_json({"input_format": fmt, "inputs": sources, "output_format": args.to,
                    "outputs": [str(p) for p in written], "profile": profile_summary(profile)})
        return 0
    method = profile.provenance.method
    found = method.removeprefix("imported from ") if method.startswith("imported from ") and fmt != "s2r" else \
        FORMAT_NAMES[fmt]  # an s2r profile is read as s2r YAML, whatever format it was first imported from
    print(f"read {found}: {', '.join(sources)} -> profile {profile.name} "
          f"({profile.image_size[0]}x{profile.image_size[1]}, baseline {1000 * profile.baseline_m:.2f} mm)")
    for path in written:
        print(f"wrote {path}")
    return 0
