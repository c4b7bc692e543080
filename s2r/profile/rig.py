"""The whole profiles: :class:`StereoProfile` (two cameras, extrinsics, matcher, provenance) and
:class:`MonoProfile` (one calibrated camera)."""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from s2r.geometry import rotation_angle_rad
from s2r.profile.base import CENTRE_OFFSET_PX, DEFAULT_SUBPIXEL_PX, SCHEMA_VERSION, _Model
from s2r.profile.camera import Camera
from s2r.profile.settings import Extrinsics, MatcherSettings, Provenance, SimulationSettings
from s2r.sensor.model import SensorModel

__all__ = ["MonoProfile", "StereoProfile"]


class StereoProfile(_Model):
    """A stereo camera: two cameras, their extrinsics, matcher settings and provenance."""

    schema_version: Literal[1] = SCHEMA_VERSION
    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.\-]+$")
    description: str = ""
    left: Camera
    right: Camera
    extrinsics: Extrinsics
    matcher: MatcherSettings = MatcherSettings()
    simulation: SimulationSettings | None = None
    provenance: Provenance
    #: The fitted sensor model (:mod:`s2r.sensor.model`, ``s2r sensor fit``): noise, blur, depth fill; optional.
    sensor: SensorModel | None = None

    @model_validator(mode="after")
    def _cameras_fit_matcher(self) -> StereoProfile:
        if self.left.image_size != self.right.image_size:
            raise ValueError(
                f"left and right image sizes differ ({self.left.width_px}x{self.left.height_px} vs "
                f"{self.right.width_px}x{self.right.height_px}); rectification needs one size"
            )
        nd = self.matcher.num_disparities
        if nd is not None and self.matcher.min_disparity + nd >= self.left.width_px:
            raise ValueError(
                f"matcher disparity range {self.matcher.min_disparity}+{nd} px does not fit the "
                f"{self.left.width_px} px wide image"
            )
        return self

    @property
    def published_offset_px(self) -> float:
        """How far (pixels, in x and y) the principal point this profile declares lies from the one its images
        obey in OpenCV's convention: 1 for gazebo-classic, 0.5 for gz-sim, 0 otherwise."""
        return CENTRE_OFFSET_PX.get(self.provenance.convention, 0.0)

    def in_opencv_pixels(self) -> StereoProfile:
        """The camera geometry its images actually have, in OpenCV's 0-based pixel-centre convention.

        A sim profile keeps what its simulator publishes (a gazebo-classic camera_info says cx = (W + 1) / 2
        for an image centred at (W - 1) / 2); this subtracts :attr:`published_offset_px` from both principal
        points and labels the result ``opencv``. Profiles already in OpenCV pixels come back unchanged.
        """
        offset = self.published_offset_px
        if offset == 0.0:
            return self
        provenance = self.provenance.model_copy(update={"convention": "opencv"})
        return self.model_copy(update={"left": self.left.shifted(-offset, -offset),
                                       "right": self.right.shifted(-offset, -offset), "provenance": provenance})

    @property
    def R(self) -> NDArray[np.float64]:
        """3x3 rotation, OpenCV convention (``X_right = R X_left + T``)."""
        return np.array(self.extrinsics.rotation, dtype=np.float64)

    @property
    def T(self) -> NDArray[np.float64]:
        """Translation in metres, OpenCV convention, shape (3,)."""
        return np.array(self.extrinsics.translation_m, dtype=np.float64)

    @property
    def baseline_m(self) -> float:
        """Distance between the optical centres in metres."""
        return float(np.linalg.norm(self.T))

    @property
    def image_size(self) -> tuple[int, int]:
        """``(width, height)`` in pixels (both cameras share it)."""
        return self.left.image_size

    @property
    def rotation_angle_rad(self) -> float:
        """Angle of the rotation between the two cameras, radians."""
        return rotation_angle_rad(self.R)

    def disparity_px(self, depth_m: float) -> float:
        """Ideal disparity (pixels) of a point at ``depth_m`` on the left axis: ``fx * B / Z``."""
        return self.left.fx_px * self.baseline_m / depth_m

    def num_disparities_for(self, min_depth_m: float | None = None) -> int:
        """Disparity count that sees down to ``min_depth_m`` (default the matcher's): fx B / z + 1, up to 16.

        The largest disparity of a range is ``min_disparity + num_disparities - 1`` (as :meth:`depth_range_m`).
        """
        z_min = self.matcher.min_depth_m if min_depth_m is None else min_depth_m
        needed = self.disparity_px(z_min) - self.matcher.min_disparity + 1
        return int(max(16, math.ceil(needed / 16.0) * 16))

    def depth_range_m(self, matcher: MatcherSettings | None = None) -> tuple[float, float]:
        """Nearest and farthest depth (metres) a matcher's disparity range can see: ``fx B / d``.

        Nearest uses the largest disparity (min_disparity + num_disparities - 1), farthest the smallest
        positive one (min_disparity, or 1 px when that is 0); the far end is where depth resolution ends.
        """
        m = self.matcher if matcher is None else matcher
        nd = m.num_disparities if m.num_disparities is not None else self.num_disparities_for(m.min_depth_m)
        fb = self.left.fx_px * self.baseline_m
        d_max = m.min_disparity + nd - 1
        d_min = max(m.min_disparity, 1)
        return (fb / d_max if d_max > 0 else math.inf, fb / d_min)

    def depth_rms_m(self, depth_m: float | NDArray[np.float64], subpixel_px: float = DEFAULT_SUBPIXEL_PX) -> Any:
        """Intel's theoretical depth RMS error (metres) at ``depth_m``: ``Z^2 s / (fx B)``."""
        return np.asarray(depth_m, dtype=np.float64) ** 2 * subpixel_px / (self.left.fx_px * self.baseline_m)

    def max_depth_within_m(self, relative_error: float = 0.02, subpixel_px: float = DEFAULT_SUBPIXEL_PX) -> float:
        """Largest depth (metres) whose theoretical RMS stays under ``relative_error`` of the depth."""
        return relative_error * self.left.fx_px * self.baseline_m / subpixel_px


class MonoProfile(_Model):
    """A single calibrated camera (``s2r calibrate --mono``)."""

    schema_version: Literal[1] = SCHEMA_VERSION
    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.\-]+$")
    description: str = ""
    camera: Camera
    provenance: Provenance
