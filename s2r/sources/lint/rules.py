"""``s2r lint``: mistakes in a robot description's stereo pair, each with a severity, a place and a fix.

Rules (code: severity):

- ``baseline-axis`` (error): the baseline is zero or runs along the optical axis (the seed rig's joint
  puts the right camera 10 cm behind the left one); the message gives the corrected joint origin/pose.
- ``baseline-offset`` (warning): a vertical or forward baseline component that costs rectified image area.
- ``pair-resolution`` (error), ``pair-fov`` / ``pair-rate`` (warning): the two cameras differ.
- ``camera-info`` (error/warning): a published camera_info disagrees with the description.
- ``focal-length`` (error), ``lens-intrinsics`` (warning): ``<focalLength>`` or ``<lens><intrinsics>``
  disagree with ``horizontal_fov``.
- ``hack-baseline`` (error/warning/info): missing, on the wrong camera, wrong sign or wrong size.
- ``near-clip`` (warning): the near clip plane is farther than the matcher's closest working depth.
- ``movable-joint`` / ``optical-link`` (warning): geometry taken at joint zero; a sensor on an ``*_optical`` link
  that renders along another axis than the link's +z (decided from the poses, as Gazebo renders).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from s2r.errors import SourceError, terminal_safe
from s2r.sources.conventions import CENTRE_OFFSET_PX, focal_from_hfov, hfov_from_focal
from s2r.sources.description import CameraSpec, Description
from s2r.sources.lint.geometry import baseline_findings
from s2r.sources.loader import StereoPair, load_description, log_notes, optical_pose, stereo_pair
from s2r.sources.pair_profile import seed_matcher

__all__ = ["SEVERITIES", "Finding", "lint_description"]

SEVERITIES = ("error", "warning", "info")
#: Relative focal-length difference treated as a disagreement (0.5 %, about 3 px at 640 px).
FOCAL_REL_TOL = 0.005


@dataclass(frozen=True)
class Finding:
    """One lint finding: severity (error | warning | info), rule code, message, place and fix."""

    severity: str
    code: str
    message: str
    file: str
    line: int | None
    fix: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return asdict(self)

    def one_line(self) -> str:
        """``file:line: severity [code] message (fix: ...)``, control characters (of names) escaped."""
        where = f"{self.file}:{self.line}" if self.line else self.file
        fix = "" if self.fix in self.message else f" (fix: {self.fix})"
        return terminal_safe(f"{where}: {self.severity} [{self.code}] {self.message}{fix}")


class _Report:
    def __init__(self, description: Description) -> None:
        self.description = description
        self.findings: list[Finding] = []
        self.xacro = description.source_text != description.expanded_text

    def simulator(self, camera: CameraSpec) -> str | None:
        """The simulator the file is for (from the plugins it loads), else classic for a gazebo_ros camera."""
        guess = self.description.simulator
        if guess is not None and guess.simulator is not None:
            return guess.simulator
        return "gazebo-classic" if camera.plugin is not None else None

    def line(self, line: int | None, *needles: str) -> int | None:
        """Line in the file on disk: the parsed line, or for xacro the first source line holding a needle."""
        if not self.xacro:
            return line
        for needle in needles:
            for number, text in enumerate(self.description.source_text.splitlines(), start=1):
                if needle and needle in text:
                    return number
        return None

    def add(self, severity: str, code: str, message: str, fix: str, line: int | None, *needles: str) -> None:
        self.findings.append(Finding(severity, code, message, str(self.description.path),
                                     self.line(line, *needles), fix))


def _deg(rad: float) -> str:
    return f"{math.degrees(rad):.1f} deg"


def _pair_rules(report: _Report, pair: StereoPair) -> None:
    left, right = pair.left, pair.right
    where = right.lines.get("camera")
    if (left.width, left.height) != (right.width, right.height):
        report.add("error", "pair-resolution",
                   f"cameras differ in resolution: {left.width}x{left.height} vs {right.width}x{right.height}",
                   "give both cameras the same <image> width and height", where, "<image>")
    if abs(left.hfov_rad - right.hfov_rad) > 1e-6:
        report.add("warning", "pair-fov", f"cameras differ in horizontal_fov: {left.hfov_rad} rad "
                   f"({_deg(left.hfov_rad)}) vs {right.hfov_rad} rad ({_deg(right.hfov_rad)})",
                   "give both cameras the same <horizontal_fov>", right.lines.get("horizontal_fov"),
                   "<horizontal_fov>")
    if left.update_rate_hz != right.update_rate_hz:
        report.add("warning", "pair-rate", f"cameras differ in update rate: {left.update_rate_hz} Hz vs "
                   f"{right.update_rate_hz} Hz (frames will not pair up)", "give both sensors the same <update_rate>",
                   right.lines.get("update_rate"), "<update_rate>")


def _lens_consequence(simulator: str | None) -> str:
    """What a ``<lens><intrinsics>`` / ``horizontal_fov`` disagreement does in the simulator the file is for."""
    classic = "Gazebo classic renders the intrinsics but gazebo_ros publishes camera_info from horizontal_fov"
    gz = "gz-sim renders and publishes the intrinsics, so horizontal_fov says something else"
    return {"gazebo-classic": classic, "gz-sim": gz}.get(simulator or "", f"{gz}; {classic}")


def _focal_rules(report: _Report, camera: CameraSpec) -> None:
    f = focal_from_hfov(camera.width, camera.hfov_rad)
    plugin = camera.plugin
    if plugin is not None and plugin.focal_length and abs(plugin.focal_length - f) > FOCAL_REL_TOL * f:
        report.add("error", "focal-length", f"camera {camera.name!r}: <focalLength> {plugin.focal_length:g} px "
                   f"disagrees with horizontal_fov {camera.hfov_rad} rad at {camera.width} px (fx = {f:.3f} px, "
                   f"{_deg(hfov_from_focal(camera.width, plugin.focal_length))} vs {_deg(camera.hfov_rad)})",
                   f"set <focalLength> to {f:.3f} (or 0 to derive it), or horizontal_fov to "
                   f"{hfov_from_focal(camera.width, plugin.focal_length):.4f}", plugin.focal_length_line,
                   "<focalLength>", "focal_length")
    lens = camera.lens
    if lens is not None and (abs(lens.fx - f) > FOCAL_REL_TOL * f or abs(lens.fy - f) > FOCAL_REL_TOL * f):
        report.add("warning", "lens-intrinsics", f"camera {camera.name!r}: <lens><intrinsics> fx {lens.fx:g} "
                   f"fy {lens.fy:g} px disagree with horizontal_fov {camera.hfov_rad} rad (fx = {f:.3f} px): "
                   f"{_lens_consequence(report.simulator(camera))}", f"set horizontal_fov to "
                   f"{hfov_from_focal(camera.width, lens.fx):.6f} or fx = fy = {f:.3f}", lens.line, "<intrinsics>")


def _optical_link_rule(report: _Report, camera: CameraSpec) -> None:
    """A sensor on a ``*_optical`` link whose rendered viewing axis is not the link's +z (decided from the poses)."""
    if not camera.link_is_optical:
        return
    axis = optical_pose(camera)[:3, 2]  # the rendered viewing direction, in link coordinates
    angle = math.degrees(math.acos(max(-1.0, min(1.0, float(axis[2])))))
    if angle < 0.1:
        return
    shown = " ".join(f"{v:+.3f}" for v in axis)
    report.add("warning", "optical-link", f"sensor {camera.sensor_name!r} is on optical-frame link {camera.link!r} "
               f"but Gazebo renders along its camera frame's +x, the link's ({shown}) direction: {angle:.1f} deg "
               "off the link's +z (the axis its name promises)", "attach the sensor to the camera body link (x "
               "forward), or give the sensor <pose> the rotation 0 -1.5708 1.5708 that turns +x onto the link's +z",
               camera.lines.get("sensor"), f'reference="{camera.link}"')


def _hack_rules(report: _Report, pair: StereoPair) -> None:
    left, right = pair.left, pair.right
    tx = float(pair.T_left_right[0, 3])
    baseline = float(np.linalg.norm(pair.T_left_right[:3, 3]))
    multi = left.sensor_name == right.sensor_name and right.cameras_in_sensor > 1
    plugin = right.plugin
    if multi:
        if plugin is None:
            return
        if right.camera_name != "right":
            report.add("error", "hack-baseline", f"the pair's right camera is named {right.camera_name!r}: "
                       "gazebo_ros_multicamera applies hackBaseline to the camera named 'right' only",
                       "name the right-hand camera 'right' (and the other 'left')", right.lines.get("camera"),
                       f'name="{right.camera_name}"')
        _hack_value(report, right, plugin.hack_baseline, tx, baseline, plugin.hack_baseline_line or plugin.line)
        if plugin.hack_baseline and plugin.hack_baseline_tag == "hack_baseline":
            report.add("warning", "hack-baseline", "<hack_baseline> (ROS 2 spelling): ROS 2 gazebo_ros applies it to "
                       "EVERY camera of the sensor, so the left camera_info also gets P[3] = -fx * baseline",
                       "check the left camera_info's P[3] (it should be 0), or publish the pair from two camera "
                       "sensors", plugin.hack_baseline_line, "hack_baseline")
        return
    if left.plugin is not None and left.plugin.hack_baseline:
        report.add("error", "hack-baseline", f"hackBaseline {left.plugin.hack_baseline:g} is on the LEFT camera "
                   f"{left.name!r}: its camera_info gets P[3] = -fx * {left.plugin.hack_baseline:g}",
                   "remove it from the left camera and put it on the right one", left.plugin.hack_baseline_line,
                   "hackBaseline", "hack_baseline")
    if plugin is not None:
        _hack_value(report, right, plugin.hack_baseline, tx, baseline, plugin.hack_baseline_line or plugin.line,
                    missing="info")


def _hack_value(report: _Report, camera: CameraSpec, value: float | None, tx: float, baseline: float,
                line: int | None, *, missing: str = "warning") -> None:
    if not value:
        report.add(missing, "hack-baseline", f"camera {camera.name!r} publishes P[3] = 0 (no hackBaseline): "
                   "stereo_image_proc will see a zero baseline", f"add <hackBaseline>{baseline:.6g}</hackBaseline> to "
                   "its plugin", line, "<plugin", "filename=")
        return
    if value * tx < 0:
        report.add("error", "hack-baseline", f"hackBaseline {value:g} has the wrong sign: the right camera is "
                   f"{tx:+.4f} m along the left camera's image x axis", f"use <hackBaseline>{tx:.6g}</hackBaseline>",
                   line, "hackBaseline", "hack_baseline")
    elif abs(abs(value) - baseline) > 0.01 * baseline:
        report.add("warning", "hack-baseline", f"hackBaseline {value:g} m differs from the geometric baseline "
                   f"{baseline:.6g} m", f"use <hackBaseline>{baseline:.6g}</hackBaseline>", line, "hackBaseline",
                   "hack_baseline")


def _clip_rules(report: _Report, pair: StereoPair) -> None:
    baseline = float(np.linalg.norm(pair.T_left_right[:3, 3]))
    left = pair.left
    near = left.clip_near_m if left.clip_near_m is not None else 0.1
    far = left.clip_far_m if left.clip_far_m is not None else 100.0
    if baseline <= 0 or far <= near:
        return
    matcher = seed_matcher(focal_from_hfov(left.width, left.hfov_rad), baseline, left.width, far_limit_m=far)
    for camera in (pair.left, pair.right):
        cam_near = camera.clip_near_m if camera.clip_near_m is not None else 0.1
        if cam_near > matcher.min_depth_m:
            report.add("warning", "near-clip", f"camera {camera.name!r}: near clip {cam_near:g} m is farther than "
                       f"the closest depth the matcher is set to see ({matcher.min_depth_m:g} m: "
                       f"{matcher.num_disparities} disparities at fx*B)", f"set <clip><near> to at most "
                       f"{matcher.min_depth_m:g}", camera.lines.get("clip"), "<near>")


def _camera_info_tx(report: _Report, pair: StereoPair, camera: CameraSpec, info: Any, line: int | None) -> None:
    """P[0, 3] = -fx * B on the right camera only (ROS stereo convention)."""
    P = getattr(info, "P", None)
    if P is None:
        return
    P = np.asarray(P, dtype=np.float64).reshape(3, 4)
    if P[0, 0] <= 0 or P[0, 3] == 0:
        return
    implied = -float(P[0, 3]) / float(P[0, 0])
    baseline = float(np.linalg.norm(pair.T_left_right[:3, 3]))
    if camera is pair.left:
        report.add("warning", "camera-info", f"the left camera_info has P[3] = {P[0, 3]:g} (baseline {implied:g} m); "
                   "the left camera of a ROS stereo pair has P[3] = 0", "apply hackBaseline to the right camera only",
                   line, "<horizontal_fov>")
    elif abs(implied - baseline) > 0.01 * baseline:
        report.add("warning", "camera-info", f"camera_info P[3] = {P[0, 3]:g} means a {implied:g} m baseline; the "
                   f"description's is {baseline:.6g} m", f"publish P[3] = {-P[0, 0] * baseline:.6g}", line,
                   "<horizontal_fov>")


def _camera_info_rules(report: _Report, pair: StereoPair, info: Any) -> None:
    name = str(getattr(info, "camera_name", "") or "")
    camera = pair.right if (name and pair.right.matches(name)) or "right" in name.lower() else pair.left
    width, height = int(info.width), int(info.height)
    K = np.asarray(info.K, dtype=np.float64).reshape(3, 3)
    line = camera.lines.get("horizontal_fov")
    if (width, height) != (camera.width, camera.height):
        report.add("error", "camera-info", f"camera_info is {width}x{height} but camera {camera.name!r} renders "
                   f"{camera.width}x{camera.height}", "publish the description's resolution",
                   camera.lines.get("camera"), "<width>")
        return
    f = focal_from_hfov(camera.width, camera.hfov_rad)
    fx_info = float(K[0, 0])
    if abs(fx_info - f) > FOCAL_REL_TOL * f:
        report.add("error", "camera-info", f"camera_info fx {fx_info:g} px means horizontal_fov "
                   f"{hfov_from_focal(width, fx_info):.3f} rad ({_deg(hfov_from_focal(width, fx_info))}) but camera "
                   f"{camera.name!r} has horizontal_fov {camera.hfov_rad} rad ({_deg(camera.hfov_rad)}, fx "
                   f"{f:.2f} px)", f"use fx = fy = {f:.2f} in the camera_info, or set horizontal_fov to "
                   f"{hfov_from_focal(width, fx_info):.4f}", line, "<horizontal_fov>")
    _camera_info_tx(report, pair, camera, info, line)
    offsets = {name: (width - 1) / 2 + off for name, off in CENTRE_OFFSET_PX.items() if name != "opencv"}
    cx = float(K[0, 2])
    if min(abs(cx - v) for v in offsets.values()) > 0.01:
        known = ", ".join(f"{n} {v:g}" for n, v in offsets.items())
        report.add("warning", "camera-info", f"camera_info cx {cx:g} px matches no Gazebo convention ({known})",
                   "check which simulator published it", line, "<horizontal_fov>")


def _profile_rule(report: _Report, description: Description, pair: Any) -> None:
    """``invalid-profile`` (error): the pair breaks a physical bound of s2r.profile, so ``profile from-urdf``
    refuses it (lint and from-urdf agree)."""
    from s2r.sources.pair_profile import profile_from_pair

    if float(np.linalg.norm(pair.T_left_right[:3, 3])) < 1e-6:
        return  # a zero baseline is the baseline-axis error already
    try:
        profile_from_pair(description, pair, convention="exact")
    except SourceError as exc:
        report.add("error", "invalid-profile", f"profile from-urdf refuses this pair: {exc.message}",
                   "fix the value the message names", pair.right.lines.get("sensor"), "<sensor")


def lint_description(path: str | Path, *, camera_info: Any = None, xacro_args: Mapping[str, str] | None = None,
                     package_paths: Sequence[Path] = (), left: str | None = None,
                     right: str | None = None, env: Mapping[str, str] | None = None,
                     keyframe: str | None = None) -> list[Finding]:
    """Lint a URDF / xacro / SDF / MJCF stereo rig (and optionally a published camera_info against it).

    Args:
        path: the description file.
        camera_info: an object with ``width``, ``height``, ``K`` (3x3, pixels) and optionally ``P`` (3x4)
            and ``camera_name`` (as :func:`s2r.formats.ros_read.read_camera_info` returns).
        xacro_args, package_paths, env: as for :func:`s2r.sources.load_description_profile`.
        left, right: camera names when the pair is not unambiguous.
        keyframe: MJCF only: the ``<keyframe>`` (index or name) the bodies are read at.

    Returns:
        Findings, errors first. Unreadable input raises :class:`~s2r.errors.SourceError` instead.
    """
    description = load_description(path, xacro_args=xacro_args, package_paths=package_paths, env=env, keyframe=keyframe)
    pair = stereo_pair(description, left=left, right=right)
    report = _Report(description)
    for joint in pair.movable_joints:
        at = f"it is taken at {description.joint_state}" if description.joint_state else "its position 0 is assumed"
        report.add("warning", "movable-joint", f"joint {joint.name!r} ({joint.type}) lies between the camera "
                   f"links; {at}", "make it fixed if the cameras are rigidly mounted",
                   joint.line, f'name="{joint.name}"')
    mjcf = description.kind == "mjcf"
    for camera in (pair.left, pair.right) if not mjcf else ():
        _optical_link_rule(report, camera)
        _focal_rules(report, camera)
    for severity, code, message, fix, line, needles in baseline_findings(description, pair):
        report.add(severity, code, message, fix, line, *needles)
    if not any(f.severity == "error" and f.code.startswith("baseline-") for f in report.findings):
        _profile_rule(report, description, pair)  # a baseline error is the cause already named
    if mjcf:
        from s2r.sources.lint.mjcf import mjcf_pair_findings

        for severity, code, message, fix, line in mjcf_pair_findings(pair):
            report.add(severity, code, message, fix, line)
    else:
        _pair_rules(report, pair)
        _hack_rules(report, pair)
    if not mjcf or pair.left.clip_near_m is not None:  # MuJoCo's clip planes scale with the model's extent
        _clip_rules(report, pair)
    if camera_info is not None:
        _camera_info_rules(report, pair, camera_info)
    log_notes(description)
    order = {s: i for i, s in enumerate(SEVERITIES)}
    return sorted(report.findings, key=lambda f: order.get(f.severity, 9))
