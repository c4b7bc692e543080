"""Lens models of the calibration: which distortion terms are solved, and the projection behind them.

A :class:`Projection` maps board points (board frame, metres) through a board pose (``rvec``, ``tvec``:
board frame in the camera's optical frame) and the intrinsics ``K`` (3x3 px) and ``D`` (coefficients)
to pixels, with the Jacobian in one fixed column order: ``rvec (3), tvec (3), fx, fy, cx, cy, D[0..n)``.
:data:`PINHOLE` is OpenCV's pinhole model (``cv2.projectPoints``: plumb_bob and rational distortion);
other models (e.g. an equidistant fisheye through ``cv2.fisheye.projectPoints``) implement the same
protocol and plug into :mod:`s2r.calib.solve.solvers.joint` unchanged.

:data:`LENS_MODELS` maps each ``--distortion`` choice to its projection, its coefficient count (all
stored, fixed ones at 0) and the indices of the coefficients the solve estimates:

- ``k1k2p1p2`` (default, as ROS camera_calibration): k1 k2 p1 p2, k3 fixed at 0;
- ``k1k2``: k1 k2 (tangential and k3 fixed at 0);
- ``plumb_bob``: k1 k2 p1 p2 k3;
- ``rational``: k1 k2 p1 p2 k3 k4 k5 k6.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import NDArray

from s2r.errors import CalibrationError

__all__ = ["DEFAULT_LENS", "FISHEYE", "LENS_MODELS", "PINHOLE", "EquidistantProjection", "LensModel",
           "PinholeProjection", "Projection", "lens_model"]

FloatArray = NDArray[np.float64]


class Projection(Protocol):
    """A camera projection with its Jacobian (columns: rvec, tvec, fx, fy, cx, cy, coefficients)."""

    @property
    def name(self) -> str:
        """Short model name (``pinhole``, ``equidistant``, ...)."""
        ...

    def project(self, obj: FloatArray, rvec: FloatArray, tvec: FloatArray, K: FloatArray,
                D: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Pixels (N, 2) of board points ``obj`` (N, 3) m and the Jacobian (2N, 10 + len(D)), rows
        interleaved (u0, v0, u1, v1, ...)."""
        ...


@dataclass(frozen=True)
class PinholeProjection:
    """OpenCV's pinhole camera with plumb_bob / rational distortion (``cv2.projectPoints``)."""

    name: str = "pinhole"

    def project(self, obj: FloatArray, rvec: FloatArray, tvec: FloatArray, K: FloatArray,
                D: FloatArray) -> tuple[FloatArray, FloatArray]:
        pts, jac = cv2.projectPoints(np.ascontiguousarray(obj, np.float64).reshape(-1, 1, 3),
                                     np.asarray(rvec, np.float64).reshape(3, 1),
                                     np.asarray(tvec, np.float64).reshape(3, 1), K, D)
        return np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(jac, np.float64)[:, :10 + len(D)]


PINHOLE = PinholeProjection()


@dataclass(frozen=True)
class LensModel:
    """A ``--distortion`` choice: projection, stored coefficient count, estimated coefficient indices,
    OpenCV calibration flags giving the same model (used to initialise), and the profile's model name."""

    name: str
    projection: Projection
    n_coef: int
    free: tuple[int, ...]
    cv_flags: int
    profile_model: str
    coef_names: tuple[str, ...]

    @property
    def jacobian_columns(self) -> slice | list[int]:
        """Columns of the projection's Jacobian for fx, fy, cx, cy and the free coefficients (a slice when they
        are consecutive: numpy copies a slice twice as fast as a list of columns)."""
        cols = [6, 7, 8, 9, *(10 + i for i in self.free)]
        return slice(6, cols[-1] + 1) if cols == list(range(6, cols[-1] + 1)) else cols


_PB = ("k1", "k2", "p1", "p2", "k3")
LENS_MODELS: dict[str, LensModel] = {
    "k1k2p1p2": LensModel("k1k2p1p2", PINHOLE, 5, (0, 1, 2, 3), cv2.CALIB_FIX_K3, "plumb_bob", _PB),
    "k1k2": LensModel("k1k2", PINHOLE, 5, (0, 1), cv2.CALIB_FIX_K3 | cv2.CALIB_ZERO_TANGENT_DIST, "plumb_bob", _PB),
    "plumb_bob": LensModel("plumb_bob", PINHOLE, 5, (0, 1, 2, 3, 4), 0, "plumb_bob", _PB),
    "rational": LensModel("rational", PINHOLE, 8, tuple(range(8)), cv2.CALIB_RATIONAL_MODEL,
                          "rational_polynomial", (*_PB, "k4", "k5", "k6")),
}
#: The default, as ROS camera_calibration: k1 k2 p1 p2 with k3 fixed at 0.
DEFAULT_LENS = "k1k2p1p2"


def lens_model(name: str) -> LensModel:
    """The lens model of a ``--distortion`` choice (CalibrationError naming the choices otherwise)."""
    if name not in LENS_MODELS:
        raise CalibrationError(f"unknown distortion model {name!r}", field="--distortion",
                               hint=f"choose one of {', '.join(LENS_MODELS)}")
    return LENS_MODELS[name]


@dataclass(frozen=True)
class EquidistantProjection:
    """OpenCV's fisheye (equidistant, k1..k4) camera through ``cv2.fisheye.projectPoints``, with the Jacobian
    in the joint solve's column order (rvec, tvec, fx, fy, cx, cy, k1..k4); as :class:`PinholeProjection`."""

    name: str = "equidistant"

    def project(self, obj: FloatArray, rvec: FloatArray, tvec: FloatArray, K: FloatArray,
                D: FloatArray) -> tuple[FloatArray, FloatArray]:
        pts, jac = cv2.fisheye.projectPoints(np.ascontiguousarray(obj, np.float64).reshape(-1, 1, 3),
                                             np.asarray(rvec, np.float64).reshape(3, 1),
                                             np.asarray(tvec, np.float64).reshape(3, 1), K,
                                             np.asarray(D, np.float64).reshape(4, 1))
        return np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(jac, np.float64)[:, list(_JOINT_COLUMNS)]


#: cv2.fisheye.projectPoints' Jacobian columns (f 2, c 2, k 4, rvec 3, tvec 3, alpha) in the joint order.
_JOINT_COLUMNS = (8, 9, 10, 11, 12, 13, 0, 1, 2, 3, 4, 5, 6, 7)
#: The fisheye lens model of ``--lens fisheye`` for :func:`s2r.calib.solve.solvers.joint.solve_joint` (all four k free).
FISHEYE = LensModel("equidistant", EquidistantProjection(), 4, (0, 1, 2, 3), 0, "equidistant",
                    ("k1", "k2", "k3", "k4"))
