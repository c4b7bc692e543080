"""What to change: concrete edits that make the sim camera match the real one.

The edits are phrased for a Gazebo camera sensor in a robot description (``<image><width>``,
``<horizontal_fov>``, ``<lens><intrinsics>``, the right camera's joint ``<origin>``, ``<distortion>``), because
that is where a sim profile comes from; ``s2r profile export-gazebo REAL`` writes the sensor XML with all of them.
Every value is in the simulator's own convention and units, computed by the export's own functions, so a value
copied from the advice equals the one the export writes.

Frames: the joint origin is the pose of the right camera LINK in the left camera link (ROS link frames: x
forward, y left, z up), derived from the real profile's OpenCV extrinsics through the optical frame
(``T_link_optical``, rpy = (-pi/2, 0, -pi/2)).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from s2r.geometry import T_LINK_OPTICAL, invert_transform, pose_from_opencv_extrinsics, rpy_from_rotation
from s2r.profile import Camera, StereoProfile
from s2r.sources.export.gazebo import lens_intrinsics
from s2r.validate.measures.params import ParamRow

__all__ = ["Edit", "gazebo_hfov_rad", "right_joint_origin", "suggest_edits"]


@dataclass(frozen=True)
class Edit:
    """One change to the sim description: what, from which value, to which, and where to write it."""

    parameter: str
    current: str
    target: str
    where: str

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


def gazebo_hfov_rad(profile: StereoProfile) -> float:
    """The ``<horizontal_fov>`` (radians) that makes Gazebo publish the profile's fx at its width.

    Gazebo sets ``fx = W / (2 tan(hfov / 2))``, so ``hfov = 2 atan(W / (2 fx))``.
    """
    return 2.0 * math.atan(profile.left.width_px / (2.0 * profile.left.fx_px))


def right_joint_origin(profile: StereoProfile) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """``(xyz metres, rpy radians)`` of the right camera link in the left camera link (URDF joint origin)."""
    T_lopt_ropt = pose_from_opencv_extrinsics(profile.R, profile.T)
    T_llink_rlink = T_LINK_OPTICAL @ T_lopt_ropt @ invert_transform(T_LINK_OPTICAL)
    xyz = tuple(float(v) + 0.0 for v in np.round(T_llink_rlink[:3, 3], 6))
    rpy = tuple(float(v) + 0.0 for v in np.round(rpy_from_rotation(T_llink_rlink[:3, :3]), 6))
    return xyz, rpy  # type: ignore[return-value]


def _fmt(values: tuple[float, ...]) -> str:
    return " ".join(f"{v:g}" for v in values)


def _failed(rows: list[ParamRow], *names: str) -> bool:
    return any(r.exceeds_tolerance for r in rows if r.name in names)


def _off_centre(cam: Camera) -> float:
    """Largest distance (pixels) of the principal point from the exact image centre ((W - 1) / 2, (H - 1) / 2)."""
    return max(abs(cam.cx_px - (cam.width_px - 1) / 2.0), abs(cam.cy_px - (cam.height_px - 1) / 2.0))


def _per_camera(profile: StereoProfile, *fields: int) -> str:
    """``left (a, b), right (c, d) px``: fields of :func:`lens_intrinsics` (0 fx, 1 fy, 2 cx, 3 cy) per camera.

    The values are what ``<lens><intrinsics>`` takes (the export's own numbers), so copying them is exact.
    """
    parts = []
    for side, cam in (("left", profile.left), ("right", profile.right)):
        lens = lens_intrinsics(profile, cam)
        values = ", ".join(f"{lens[i]:.2f}" for i in fields)
        parts.append(f"{side} ({values})" if len(fields) > 1 else f"{side} {values}")
    return ", ".join(parts) + " px"


def _intrinsic_edits(sim: StereoProfile, real: StereoProfile, rows: list[ParamRow], *,
                     principal_point_px: float) -> list[Edit]:
    edits = []
    if _failed(rows, "image size"):
        edits.append(Edit("resolution", f"{sim.image_size[0]}x{sim.image_size[1]}",
                          f"{real.image_size[0]}x{real.image_size[1]}",
                          f"<image><width>{real.image_size[0]}</width><height>{real.image_size[1]}</height> "
                          "in both camera sensors"))
    if _failed(rows, "HFOV", "left fx", "right fx", "image size"):
        hfov = gazebo_hfov_rad(real)
        edits.append(Edit("horizontal_fov", f"{gazebo_hfov_rad(sim):.4f} rad", f"{hfov:.4f} rad "
                          f"({math.degrees(hfov):.2f} deg)", "<horizontal_fov> in both camera sensors"))
    if _failed(rows, "left fy", "right fy", "VFOV") and any(
            abs(c.fy_px - c.fx_px) > 1e-6 * c.fx_px for c in (real.left, real.right)):
        edits.append(Edit("fy", _per_camera(sim, 1), _per_camera(real, 1),
                          "<lens><intrinsics><fy> of each camera sensor (Gazebo classic and gz-sim render with it; "
                          "gazebo_ros' camera_info still publishes fx for fy)"))
    off_centre = max(_off_centre(c) for c in (real.left, real.right, sim.left, sim.right))
    if _failed(rows, "left cx", "left cy", "right cx", "right cy") and off_centre > principal_point_px:
        edits.append(Edit("principal point", _per_camera(sim, 2, 3), _per_camera(real, 2, 3),
                          "<lens><intrinsics><cx>/<cy> of each camera sensor, in the simulator's continuous "
                          "pixels (OpenCV's 0-based value + 0.5), as s2r profile export-gazebo writes them"))
    if _failed(rows, "left distortion", "right distortion"):
        edits.append(Edit("distortion", sim.left.distortion.model + " " + _fmt(sim.left.distortion.coefficients),
                          real.left.distortion.model + " " + _fmt(real.left.distortion.coefficients),
                          "<distortion> k1 k2 p1 p2 k3 (Gazebo's k are image-size normalised: let "
                          "s2r profile export-gazebo convert them)"))
    return edits


def suggest_edits(sim: StereoProfile, real: StereoProfile, rows: list[ParamRow], *,
                  principal_point_px: float = 2.0) -> list[Edit]:
    """The edits to the sim description that remove each parameter difference beyond tolerance.

    A principal-point edit is suggested only when the real or the sim principal point lies more than
    ``principal_point_px`` from its image centre (two centred cameras need only the resolution edit).
    """
    edits = _intrinsic_edits(sim, real, rows, principal_point_px=principal_point_px)
    if _failed(rows, "baseline", "inter-camera rotation"):
        (xyz_s, rpy_s), (xyz_r, rpy_r) = right_joint_origin(sim), right_joint_origin(real)
        edits.append(Edit("right camera joint origin", f'xyz="{_fmt(xyz_s)}" rpy="{_fmt(rpy_s)}"',
                          f'xyz="{_fmt(xyz_r)}" rpy="{_fmt(rpy_r)}"',
                          "<origin> of the joint from the left to the right camera link (baseline "
                          f"{sim.baseline_m * 1000:.1f} -> {real.baseline_m * 1000:.1f} mm); multicamera "
                          f"plugin <hackBaseline>{real.baseline_m:g}</hackBaseline>"))
    if edits:
        edits.append(Edit("sensor XML", sim.name, real.name,
                          f"s2r profile export-gazebo {real.name} -o {real.name}.urdf.xml"))
    return edits
