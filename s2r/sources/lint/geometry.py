"""Lint rules on the pair's geometry: a baseline along the optical axis, zero, reversed, or off the image x axis.

Each finding carries the corrected joint origin (or camera ``<pose>``) that would put the right camera at
the same distance straight along the left camera's image x axis, keeping the right camera's rotation.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from s2r.geometry import baseline_layout_problem, invert_transform, make_transform, rpy_from_rotation
from s2r.sources.description import Description, FloatArray
from s2r.sources.kinematics import KinematicTree
from s2r.sources.loader import StereoPair, optical_pose

__all__ = ["RawFinding", "baseline_findings", "corrected_placement", "rectified_area_kept"]

#: (severity, code, message, fix, line, search strings for xacro sources)
RawFinding = tuple[str, str, str, str, "int | None", tuple[str, ...]]
#: Fraction of rectified image area that may be lost to a baseline off the x axis before it is reported.
AREA_LOSS_WARN = 0.01


def _num(value: float) -> str:
    text = f"{round(value, 9):g}"
    return "0" if text in ("-0", "0") else text


def _xyz_rpy(T: FloatArray) -> str:
    xyz = " ".join(_num(v) for v in T[:3, 3])
    rpy = " ".join(_num(v) for v in rpy_from_rotation(T[:3, :3]))
    return f'xyz="{xyz}" rpy="{rpy}"'


def corrected_placement(description: Description, pair: StereoPair) -> tuple[str, int | None, tuple[str, ...]]:
    """Text of the corrected joint origin / camera pose, its line and xacro search strings."""
    T_now = pair.T_left_right
    baseline = float(np.linalg.norm(T_now[:3, 3])) or 0.1
    T_new = make_transform(T_now[:3, :3], [baseline, 0.0, 0.0])
    if description.kind == "mjcf":
        from s2r.sources.lint.mjcf import mjcf_placement

        text, line = mjcf_placement(description, pair, T_new)
        return text + " (in place of its orientation attribute)", line, ()
    left, right = pair.left, pair.right
    tree = KinematicTree(description)
    T_link_optR_new = optical_pose(left) @ T_new  # the corrected right optical frame in the left link
    T_camR_optR = invert_transform(right.T_link_camera) @ optical_pose(right)
    if left.link == right.link and right.T_link_sensor is not None and left.sensor_name == right.sensor_name:
        pose = invert_transform(right.T_link_sensor) @ T_link_optR_new @ invert_transform(T_camR_optR)
        xyz = " ".join(_num(v) for v in pose[:3, 3])
        rpy = " ".join(_num(v) for v in rpy_from_rotation(pose[:3, :3]))
        return (f"set camera {right.camera_name!r}'s <pose> to \"{xyz} {rpy}\"", right.lines.get("pose"),
                ("<pose>",))
    joint = tree.parent_joint.get(right.link)
    if joint is not None and joint not in tree.chain_to_root(left.link):
        T_root_left, _ = tree.pose_in_root(left.link)
        T_root_parent, _ = tree.pose_in_root(joint.parent)
        T_root_linkR_new = T_root_left @ T_link_optR_new @ invert_transform(optical_pose(right))
        origin = invert_transform(T_root_parent) @ T_root_linkR_new
        return f"set joint {joint.name!r} <origin {_xyz_rpy(origin)}/>", joint.line, (f'name="{joint.name}"',)
    return (f"place the right camera {_num(baseline)} m along the left camera's image x axis (to its right)",
            right.lines.get("sensor"), ("<sensor",))


def rectified_area_kept(description: Description, pair: StereoPair) -> tuple[float, float]:
    """Fraction of the image area left valid by rectification: (this pair, the same pair with an ideal
    x-axis baseline of the same length). Uses :func:`s2r.rectification.stereo_rectification` (alpha 1)."""
    from s2r.rectification import stereo_rectification
    from s2r.sources.pair_profile import profile_from_pair

    builder_log = logging.getLogger("s2r.sources.pair_profile")
    was_disabled, builder_log.disabled = builder_log.disabled, True  # its lens warnings are not about this area
    try:
        profile = profile_from_pair(description, pair, convention="exact")
    finally:
        builder_log.disabled = was_disabled
    baseline = profile.baseline_m
    ideal = profile.model_copy(update={"extrinsics": profile.extrinsics.model_copy(
        update={"translation_m": tuple((-profile.R @ np.array([baseline, 0.0, 0.0])).tolist())})})
    area = profile.left.width_px * profile.left.height_px

    def kept(p: object) -> float:
        rect = stereo_rectification(p, alpha=1.0)  # type: ignore[arg-type]
        return min(r[2] * r[3] for r in (rect.roi_left, rect.roi_right)) / area

    return kept(profile), kept(ideal)


def baseline_findings(description: Description, pair: StereoPair) -> list[RawFinding]:
    """``baseline-axis`` (error), ``baseline-side`` (error) and ``baseline-offset`` (warning) findings."""
    t = pair.T_left_right[:3, 3]
    fix, line, needles = corrected_placement(description, pair)
    problem = baseline_layout_problem(t)
    if problem is not None:
        code, message = problem
        if code == "baseline-side":
            return [("error", code, message, "swap --left and --right (or the camera names), or " + fix, line,
                     needles)]
        return [("error", code, f"{message}; corrected: {fix}", fix, line, needles)]
    tx, ty, tz = (float(v) for v in t)
    if abs(ty) < 1e-9 and abs(tz) < 1e-9:
        return []
    kept, ideal = rectified_area_kept(description, pair)
    lost = 1.0 - kept / ideal if ideal > 0 else 0.0
    if lost < AREA_LOSS_WARN:
        return []
    angle = math.degrees(math.atan2(math.hypot(ty, tz), tx))
    return [("warning", "baseline-offset", f"baseline has a vertical component of {ty * 1000:+.1f} mm and a forward "
             f"component of {tz * 1000:+.1f} mm ({angle:.1f} deg off the image x axis): rectification loses "
             f"{100 * lost:.1f} % of the valid image area", fix, line, needles)]
