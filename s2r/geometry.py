"""Frames, rotations and rigid transforms (numpy; scipy imported where a conversion needs it).

Naming: ``T_a_b`` is the 4x4 pose of frame ``b`` expressed in frame ``a`` (it maps points from ``b``
coordinates to ``a`` coordinates: ``x_a = T_a_b @ x_b``). Translations are in metres.

Frames used across s2r:
- *link* frame (ROS / Gazebo): x forward (the viewing axis of a Gazebo camera), y left, z up.
- *optical* frame (ROS / OpenCV): z forward, x right, y down.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ORTHONORMAL_TOL",
    "R_LINK_OPTICAL",
    "T_LINK_OPTICAL",
    "baseline_layout_problem",
    "check_matrix",
    "check_rotation",
    "check_vector",
    "invert_transform",
    "make_transform",
    "opencv_extrinsics_from_pose",
    "pose_from_opencv_extrinsics",
    "rotation_angle_rad",
    "rotation_from_rpy",
    "rpy_from_rotation",
]

#: Tolerance on ``|R^T R - I|`` (max abs element) and ``|det R - 1|`` for a matrix to count as a rotation.
ORTHONORMAL_TOL = 1e-6

FloatArray = NDArray[np.float64]


def check_matrix(value: ArrayLike, shape: tuple[int, ...], *, name: str = "matrix") -> FloatArray:
    """Return ``value`` as a finite float64 array of ``shape``; raise ValueError naming the expected shape."""
    array = np.asarray(value, dtype=np.float64)
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must hold finite numbers only")
    return array


def check_vector(value: ArrayLike, length: int, *, name: str = "vector") -> FloatArray:
    """Return ``value`` flattened to a finite float64 vector of ``length``."""
    array = np.asarray(value, dtype=np.float64).reshape(-1)
    return check_matrix(array, (length,), name=name)


def check_rotation(value: ArrayLike, *, name: str = "R", tol: float = ORTHONORMAL_TOL) -> FloatArray:
    """Return a 3x3 rotation matrix, raising ValueError unless orthonormal with det +1 within ``tol``."""
    rot = check_matrix(value, (3, 3), name=name)
    err = float(np.max(np.abs(rot.T @ rot - np.eye(3))))
    if err > tol:
        raise ValueError(f"{name} is not orthonormal: max |R^T R - I| = {err:.2e} > {tol:.0e}")
    det = float(np.linalg.det(rot))
    if abs(det - 1.0) > tol:
        raise ValueError(f"{name} must have determinant +1 (a rotation, not a reflection), got {det:.6f}")
    return rot


def rotation_from_rpy(rpy: ArrayLike) -> FloatArray:
    """URDF/SDF roll-pitch-yaw (radians, about FIXED axes x, y, z) to a 3x3 rotation matrix."""
    from scipy.spatial.transform import Rotation  # scipy loads on first use: the CLI starts without it

    angles = check_vector(rpy, 3, name="rpy")
    return np.asarray(Rotation.from_euler("xyz", angles).as_matrix(), dtype=np.float64)


def rpy_from_rotation(rot: ArrayLike) -> FloatArray:
    """Inverse of :func:`rotation_from_rpy`: fixed-axis roll, pitch, yaw in radians."""
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_matrix(check_rotation(rot)).as_euler("xyz"), dtype=np.float64)


def rotation_angle_rad(rot: ArrayLike) -> float:
    """Angle of a rotation matrix about its axis, in radians (0 for the identity).

    ``atan2(|v|, trace(R) - 1)`` with ``v = (R32 - R23, R13 - R31, R21 - R12) = 2 sin(angle) axis`` and
    ``trace(R) - 1 = 2 cos(angle)``: accurate at small and large angles, without importing scipy.
    """
    R = check_rotation(rot)
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return float(np.arctan2(np.linalg.norm(v), np.trace(R) - 1.0))


def make_transform(rot: ArrayLike, translation_m: ArrayLike) -> FloatArray:
    """4x4 homogeneous transform from a 3x3 rotation and a translation in metres."""
    out = np.eye(4)
    out[:3, :3] = check_rotation(rot)
    out[:3, 3] = check_vector(translation_m, 3, name="translation")
    return out


def invert_transform(T_a_b: ArrayLike) -> FloatArray:
    """``T_b_a`` from ``T_a_b`` (exact rigid inverse, no general matrix inversion)."""
    T = check_matrix(T_a_b, (4, 4), name="transform")
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


#: Rotation of the optical frame in the link frame: rpy = (-pi/2, 0, -pi/2).
#: Columns are the optical axes (x right, y down, z forward) in link coordinates.
R_LINK_OPTICAL: FloatArray = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
#: 4x4 pose of the optical frame in its link frame (same origin).
T_LINK_OPTICAL: FloatArray = make_transform(R_LINK_OPTICAL, np.zeros(3))


def opencv_extrinsics_from_pose(T_left_right: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """OpenCV stereo extrinsics ``(R, T)`` from the pose of the right OPTICAL frame in the left one.

    OpenCV's convention is ``X_right = R @ X_left + T``, i.e. ``[R | T] = T_right_left``.
    A right camera 0.1 m to the right of the left one gives ``T = (-0.1, 0, 0)``.
    """
    T_right_left = invert_transform(T_left_right)
    return T_right_left[:3, :3].copy(), T_right_left[:3, 3].copy()


def pose_from_opencv_extrinsics(R: ArrayLike, T: ArrayLike) -> FloatArray:
    """Pose of the right optical frame in the left optical frame (``T_left_right``) from OpenCV ``R, T``."""
    return invert_transform(make_transform(R, T))


def as_plain(value: Any) -> Any:
    """Numpy arrays and scalars to nested Python lists/floats (for YAML and JSON output)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def baseline_layout_problem(position_m: ArrayLike) -> tuple[str, str] | None:
    """Why a right camera at ``position_m`` (metres, in the LEFT optical frame: x right, y down, z forward)
    makes no usable stereo pair, as ``(code, message)``; None when it is usable.

    One rule for lint, ``from-urdf`` and every export: ``baseline-axis`` when the baseline is zero or its
    forward component is at least as large as its length / sqrt(2) (no disparity), ``baseline-side`` when
    the "right" camera sits to the LEFT by at least that much (negative disparities).
    """
    t = check_vector(position_m, 3, name="right camera position")
    b = float(np.linalg.norm(t))
    if b < 1e-6:
        return "baseline-axis", "zero baseline: both cameras sit at the same place"
    tx, _, tz = (float(v) for v in t)
    if abs(tz) >= b * np.sqrt(0.5):
        where = "behind" if tz < 0 else "in front of"
        return "baseline-axis", (f"baseline along the optical axis: the right camera is {abs(tz) * 100:.1f} cm {where} "
                                 f"the left one along its viewing axis ({abs(tx) * 100:.1f} cm sideways): no stereo "
                                 "disparity")
    if tx < 0 and abs(tx) >= b * np.sqrt(0.5):
        return "baseline-side", (f"the 'right' camera is {abs(tx) * 100:.1f} cm to the LEFT of the left camera "
                                 "(disparities would be negative)")
    return None
