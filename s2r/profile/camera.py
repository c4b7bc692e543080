"""One camera of a profile: intrinsics (pixels), lens distortion in OpenCV's order, and their calibrated standard
deviations; bounds as :mod:`s2r.profile` lists them."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator, model_validator

from s2r.limits import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.profile.base import (
    DISTORTION_COEFFICIENTS,
    MAX_DISTORTION_COEFF,
    MAX_FISHEYE_FOV_DEG,
    MAX_PINHOLE_FOV_DEG,
    MAX_TANGENTIAL_COEFF,
    MIN_FOV_DEG,
    DistortionModel,
    _Model,
)

__all__ = ["Camera", "CameraUncertainty", "Distortion"]


class Distortion(_Model):
    """Lens distortion: ``plumb_bob`` (k1 k2 p1 p2 k3), ``rational_polynomial`` (k1 k2 p1 p2 k3 k4 k5 k6)
    or ``equidistant`` (fisheye k1 k2 k3 k4), coefficients in OpenCV's order and focal-normalised units."""

    model: DistortionModel = "plumb_bob"
    coefficients: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _count_matches_model(self) -> Distortion:
        expected = DISTORTION_COEFFICIENTS[self.model]
        if len(self.coefficients) != expected:
            raise ValueError(
                f"distortion model {self.model} needs {expected} coefficients, got {len(self.coefficients)}"
            )
        tangential = (2, 3) if self.model != "equidistant" else ()
        for i, c in enumerate(self.coefficients):
            bound = MAX_TANGENTIAL_COEFF if i in tangential else MAX_DISTORTION_COEFF
            if abs(c) > bound:
                kind = "tangential coefficient" if i in tangential else "coefficient"
                raise ValueError(f"distortion {kind} {i} = {c:g} exceeds {bound:g} in magnitude: no lens model "
                                 "fit is that large (wrong units or a corrupted file?)")
        return self

    @property
    def is_zero(self) -> bool:
        """True when every coefficient is exactly zero (an ideal pinhole)."""
        return all(c == 0.0 for c in self.coefficients)


class CameraUncertainty(_Model):
    """One-sigma standard deviations of a camera's calibrated parameters (same units as the values)."""

    fx_px: float | None = Field(default=None, ge=0)
    fy_px: float | None = Field(default=None, ge=0)
    cx_px: float | None = Field(default=None, ge=0)
    cy_px: float | None = Field(default=None, ge=0)
    distortion: tuple[float, ...] | None = None


class Camera(_Model):
    """One pinhole camera: image size, intrinsics (pixels), distortion, frame name."""

    width_px: int = Field(ge=MIN_IMAGE_PX, le=MAX_IMAGE_PX)
    height_px: int = Field(ge=MIN_IMAGE_PX, le=MAX_IMAGE_PX)
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    skew: float = 0.0
    distortion: Distortion = Distortion()
    frame_id: str = ""
    std: CameraUncertainty | None = None

    @field_validator("fx_px", "fy_px")
    @classmethod
    def _positive_focal(cls, value: float) -> float:
        if value <= 0:
            raise ValueError(f"focal length must be positive, got {value}")
        return value

    @model_validator(mode="after")
    def _physical(self) -> Camera:
        fisheye = self.distortion.model == "equidistant"
        for axis, focal, size in (("x", self.fx_px, self.width_px), ("y", self.fy_px, self.height_px)):
            half = size / 2.0
            fov = 2.0 * math.degrees(half / focal if fisheye else math.atan(half / focal))
            widest = MAX_FISHEYE_FOV_DEG if fisheye else MAX_PINHOLE_FOV_DEG
            if fov > widest:
                model = "an equidistant (fisheye)" if fisheye else "a pinhole"
                raise ValueError(f"f{axis} = {focal:g} px gives a {fov:.1f} deg field of view over {size} px, wider "
                                 f"than {model} camera can image ({widest:g} deg); is f{axis} in pixels?")
            if fov < MIN_FOV_DEG:
                raise ValueError(f"f{axis} = {focal:g} px gives a {fov:.3g} deg field of view over {size} px, "
                                 f"narrower than any real lens ({MIN_FOV_DEG:g} deg); is f{axis} in pixels?")
        if abs(self.skew) > self.fx_px:
            raise ValueError(f"skew {self.skew:g} exceeds fx ({self.fx_px:g}): pixel axes tilted over 45 deg exist "
                             "in no camera (OpenCV and ROS calibrations give 0)")
        return self

    @model_validator(mode="after")
    def _principal_point_inside(self) -> Camera:
        if not (0.0 <= self.cx_px <= self.width_px) or not (0.0 <= self.cy_px <= self.height_px):
            raise ValueError(
                f"principal point ({self.cx_px}, {self.cy_px}) lies outside the "
                f"{self.width_px}x{self.height_px} image"
            )
        return self

    @property
    def K(self) -> NDArray[np.float64]:
        """3x3 camera matrix in pixels."""
        return np.array(
            [[self.fx_px, self.skew, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]]
        )

    @property
    def D(self) -> NDArray[np.float64]:
        """Distortion coefficients as a float64 vector in OpenCV's order."""
        return np.array(self.distortion.coefficients, dtype=np.float64)

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels, as OpenCV wants it."""
        return (self.width_px, self.height_px)

    @property
    def hfov_rad(self) -> float:
        """Horizontal field of view (radians) between the image's outer pixel EDGES, at -0.5 and W - 0.5 in
        OpenCV's 0-based pixel-centre convention (so cx = (W - 1) / 2 is the exact centre)."""
        left_edge, right_edge = self.cx_px + 0.5, self.width_px - 0.5 - self.cx_px
        return math.atan(left_edge / self.fx_px) + math.atan(right_edge / self.fx_px)

    @property
    def vfov_rad(self) -> float:
        """Vertical field of view (radians) between the outer pixel edges, as :attr:`hfov_rad`."""
        top_edge, bottom_edge = self.cy_px + 0.5, self.height_px - 0.5 - self.cy_px
        return math.atan(top_edge / self.fy_px) + math.atan(bottom_edge / self.fy_px)

    def shifted(self, dx_px: float, dy_px: float) -> Camera:
        """This camera with its principal point moved by ``(dx_px, dy_px)`` pixels."""
        return self.model_copy(update={"cx_px": self.cx_px + dx_px, "cy_px": self.cy_px + dy_px})

    def scaled(self, width_px: int, height_px: int) -> Camera:
        """This camera at another resolution, scaling K about pixel edges (``c' = s (c + 0.5) - 0.5``)."""
        sx, sy = width_px / self.width_px, height_px / self.height_px
        return self.model_copy(
            update={
                "width_px": width_px,
                "height_px": height_px,
                "fx_px": self.fx_px * sx,
                "fy_px": self.fy_px * sy,
                "cx_px": sx * (self.cx_px + 0.5) - 0.5,
                "cy_px": sy * (self.cy_px + 0.5) - 0.5,
                "skew": self.skew * sx,
                "std": None,
            }
        )
