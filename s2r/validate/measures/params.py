"""Parameter table: each camera parameter of the sim and real profiles side by side, with the difference.

Differences are ``sim - real`` in the parameter's own units (pixels, degrees, metres). The real profile's
one-sigma standard deviation is shown where its calibration recorded one; a difference beyond
``tolerances.sigma`` of them is flagged as significant, and beyond the tolerance as a failure.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from s2r.geometry import rotation_angle_rad
from s2r.profile import Camera, StereoProfile
from s2r.validate.tolerances import Tolerances

__all__ = ["ParamRow", "parameter_table"]


@dataclass(frozen=True)
class ParamRow:
    """One parameter of the table.

    ``sim``/``real`` are the values (numbers, or text such as ``640x480``); ``diff`` is ``sim - real``
    (or the size of the difference for non-scalar parameters); ``limit`` the allowed ``|diff|`` in the
    same unit; ``real_std`` the real profile's one-sigma uncertainty when known.
    """

    name: str
    unit: str
    sim: float | str
    real: float | str
    diff: float
    limit: float
    real_std: float | None = None
    exceeds_tolerance: bool = False
    exceeds_sigma: bool | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


def _row(name: str, unit: str, sim: float, real: float, limit: float, *, std: float | None = None,
         sigma: float = 3.0) -> ParamRow:
    diff = sim - real
    return ParamRow(name=name, unit=unit, sim=sim, real=real, diff=diff, limit=limit, real_std=std,
                    exceeds_tolerance=abs(diff) > limit + 1e-12,
                    exceeds_sigma=None if not std else abs(diff) > sigma * std)


def _padded(cam: Camera, n: int) -> np.ndarray:
    coeffs = np.zeros(n)
    coeffs[: len(cam.distortion.coefficients)] = cam.distortion.coefficients
    return coeffs


def _distortion_row(side: str, sim: Camera, real: Camera, tol: Tolerances) -> ParamRow:
    n = max(len(sim.distortion.coefficients), len(real.distortion.coefficients))
    diff = float(np.max(np.abs(_padded(sim, n) - _padded(real, n))))
    same_model = sim.distortion.model == real.distortion.model or (sim.distortion.is_zero and real.distortion.is_zero)

    def text(cam: Camera) -> str:
        return f"{cam.distortion.model} [{', '.join(f'{c:.4g}' for c in cam.distortion.coefficients)}]"

    limit = tol.distortion_abs
    return ParamRow(name=f"{side} distortion", unit="max |dk|", sim=text(sim), real=text(real), diff=diff,
                    limit=limit, exceeds_tolerance=diff > limit or not same_model)


def _camera_rows(side: str, sim: Camera, real: Camera, tol: Tolerances) -> list[ParamRow]:
    std = real.std
    rows = []
    for key, label in (("fx_px", "fx"), ("fy_px", "fy")):
        real_value = float(getattr(real, key))
        rows.append(_row(f"{side} {label}", "px", float(getattr(sim, key)), real_value, tol.focal_rel * real_value,
                         std=None if std is None else getattr(std, key), sigma=tol.sigma))
    for key, label in (("cx_px", "cx"), ("cy_px", "cy")):
        rows.append(_row(f"{side} {label}", "px", float(getattr(sim, key)), float(getattr(real, key)),
                         tol.principal_point_px, std=None if std is None else getattr(std, key), sigma=tol.sigma))
    rows.append(_distortion_row(side, sim, real, tol))
    return rows


def _size_row(sim: StereoProfile, real: StereoProfile, tol: Tolerances) -> ParamRow:
    (ws, hs), (wr, hr) = sim.image_size, real.image_size
    diff = float(max(abs(ws - wr), abs(hs - hr)))
    return ParamRow(name="image size", unit="px", sim=f"{ws}x{hs}", real=f"{wr}x{hr}", diff=diff,
                    limit=tol.size_px, exceeds_tolerance=diff > tol.size_px)


def parameter_table(sim: StereoProfile, real: StereoProfile, tol: Tolerances) -> list[ParamRow]:
    """Every compared parameter: size, intrinsics and distortion of both cameras, FOV, baseline, rotation.

    Intrinsics are compared at each profile's own resolution, in the pixel convention the profiles carry
    (``validate`` first converts both to OpenCV pixels with :meth:`StereoProfile.in_opencv_pixels`); the
    projection difference (:mod:`s2r.validate.measures.projection`) compares them after scaling to a common resolution.
    """
    rows = [_size_row(sim, real, tol)]
    rows += _camera_rows("left", sim.left, real.left, tol)
    rows += _camera_rows("right", sim.right, real.right, tol)
    rows.append(_row("HFOV", "deg", math.degrees(sim.left.hfov_rad), math.degrees(real.left.hfov_rad), tol.fov_deg))
    rows.append(_row("VFOV", "deg", math.degrees(sim.left.vfov_rad), math.degrees(real.left.vfov_rad), tol.fov_deg))
    rows.append(_row("baseline", "m", sim.baseline_m, real.baseline_m, tol.baseline_rel * real.baseline_m,
                     std=real.extrinsics.baseline_std_m, sigma=tol.sigma))
    relative = rotation_angle_rad(sim.R @ real.R.T)
    rotation = ParamRow(name="inter-camera rotation", unit="deg", sim=math.degrees(sim.rotation_angle_rad),
                        real=math.degrees(real.rotation_angle_rad), diff=math.degrees(relative),
                        limit=tol.rotation_deg, exceeds_tolerance=math.degrees(relative) > tol.rotation_deg)
    rows.append(rotation)
    limit_sim, limit_real = sim.max_depth_within_m(0.02), real.max_depth_within_m(0.02)
    rows.append(_row("2% depth distance", "m", limit_sim, limit_real, tol.depth_limit_rel * limit_real))
    return rows
