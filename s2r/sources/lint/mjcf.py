"""``s2r lint`` rules for an MJCF stereo pair, and the corrected camera pose its baseline findings propose.

Rules (code: severity), besides the shared geometry rules (``baseline-axis``, ``baseline-side``,
``baseline-offset``, ``invalid-profile``, ``movable-joint``):

- ``pair-resolution`` (error): the two cameras render different image sizes.
- ``pair-fov`` (warning): the two cameras differ in focal lengths or principal point (their fields differ).
- ``mjcf-camera`` (warning): a camera whose pose moves with the simulation state (mode track, trackcom,
  targetbody) or whose size is the offscreen buffer's (no ``resolution``).
- ``pixel-aspect`` (warning): fx and fy differ by more than 1 %: real pixels are square, and a ``sensorsize``
  whose aspect is not the ``resolution``'s stretches the image (the usual cause).
"""

from __future__ import annotations

import math

import numpy as np

from s2r.geometry import invert_transform
from s2r.sources.description import CameraSpec, Description, FloatArray
from s2r.sources.kinematics import KinematicTree
from s2r.sources.loader import StereoPair, optical_pose
from s2r.sources.mjcf.pose import quat_from_rotation
from s2r.sources.mjcf.reader import T_MJCAM_OPTICAL

__all__ = ["MjcfFinding", "mjcf_pair_findings", "mjcf_placement"]

#: (severity, code, message, fix, line)
MjcfFinding = tuple[str, str, str, str, "int | None"]
_REL_TOL = 1e-6
_ASPECT_TOL = 0.01


def _num(value: float) -> str:
    text = f"{round(value, 9):g}"
    return "0" if text in ("-0", "0") else text


def _intrinsics(camera: CameraSpec) -> tuple[float, float, float, float]:
    lens = camera.lens
    assert lens is not None  # every MJCF camera carries its intrinsics as a lens
    return lens.fx, lens.fy, lens.cx - 0.5, lens.cy - 0.5


def _field(camera: CameraSpec) -> str:
    fx, fy, cx, cy = _intrinsics(camera)
    vfov = math.degrees(2.0 * math.atan(camera.height / (2.0 * fy)))
    return f"fx {fx:.3f} fy {fy:.3f} cx {cx:.3f} cy {cy:.3f} px (vertical fov {vfov:.3f} deg, {camera.intrinsics_form})"


def mjcf_pair_findings(pair: StereoPair) -> list[MjcfFinding]:
    """The pair rules: same image size, same intrinsics, and each camera's remarks."""
    left, right = pair.left, pair.right
    line = right.lines.get("camera")
    found: list[MjcfFinding] = []
    if (left.width, left.height) != (right.width, right.height):
        found.append(("error", "pair-resolution", f"cameras differ in image size: {left.width}x{left.height} vs "
                      f"{right.width}x{right.height}", "give both cameras the same resolution (one <default> class "
                      "for both keeps them equal)", line))
    else:
        a, b = _intrinsics(left), _intrinsics(right)
        if any(abs(x - y) > _REL_TOL * max(1.0, abs(x)) for x, y in zip(a, b, strict=True)):
            found.append(("warning", "pair-fov", f"cameras differ in field: left {_field(left)} vs right "
                          f"{_field(right)}", "give both cameras the same fovy (or sensorsize, focal and principal), "
                          "e.g. through one <default> class", line))
    for camera in (left, right):
        fx, fy, _, _ = _intrinsics(camera)
        if abs(fx / fy - 1.0) > _ASPECT_TOL:
            found.append(("warning", "pixel-aspect", f"camera {camera.name!r}: fx {fx:.3f} and fy {fy:.3f} px differ "
                          f"by {100 * abs(fx / fy - 1):.1f} %: its pixels are not square ({camera.intrinsics_form})",
                          "make sensorsize's aspect the resolution's (and focal equal in x and y), unless the real "
                          "camera's calibration says otherwise", camera.lines.get("camera")))
        for remark in camera.remarks:
            found.append(("warning", "mjcf-camera", f"camera {camera.name!r}: {remark}",
                          "use mode='fixed' and a resolution for a stereo camera", camera.lines.get("camera")))
    return found


def mjcf_placement(description: Description, pair: StereoPair, T_new: FloatArray) -> tuple[str, int | None]:
    """The right camera's ``pos`` and ``quat`` (in its body, or the ``<frame>`` it is written in) that put it at
    ``T_new`` (the corrected right optical frame in the left optical frame), and the camera's line."""
    left, right = pair.left, pair.right
    tree = KinematicTree(description)
    T_links, _ = tree.transform(right.link, left.link)
    T_bodyR_optR = T_links @ optical_pose(left) @ T_new
    T_frame = right.T_link_sensor if right.T_link_sensor is not None else np.eye(4)
    T_local = invert_transform(T_frame) @ T_bodyR_optR @ invert_transform(T_MJCAM_OPTICAL)
    pos = " ".join(_num(v) for v in T_local[:3, 3])
    quat = " ".join(_num(v) for v in quat_from_rotation(T_local[:3, :3]))
    return f'set camera {right.name!r} pos="{pos}" quat="{quat}"', right.lines.get("camera")
