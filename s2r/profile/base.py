"""The typed stereo camera profile: intrinsics, distortion, extrinsics, matcher settings, provenance.

All models are frozen pydantic models with ``extra="forbid"`` and reject NaN/inf. Units are in the
field names: ``_px`` pixels, ``_m`` metres, ``_rad`` radians, ``_hz`` hertz. Pixel coordinates follow
OpenCV's convention (0-based, pixel centres at integers) unless ``provenance.convention`` says otherwise.

Physical bounds (each refusal says why): image sides 16..16384 px (:data:`MAX_IMAGE_PX`); a field of view
between 0.5 deg and 170 deg for a pinhole, up to 280 deg for the equidistant (fisheye) model; ``|skew| <= fx``;
distortion coefficients ``|k| <= 1e5`` and tangential ``|p| <= 1``; baseline 1 mm..10 m; the right camera
turned at most 90 deg from the left; ``provenance.convention`` one of :data:`CENTRE_OFFSET_PX`. Numbers must
be numbers: ``"500"`` (a string) or ``true`` is refused where a number is expected.

Extrinsics use OpenCV's stereo convention: ``X_right = R @ X_left + T`` with points in the LEFT optical
frame, ``T`` in metres. A right camera 0.1 m to the right of the left one has ``T = (-0.1, 0, 0)``.
"""

from __future__ import annotations

import datetime as _dt
import math
import types
from typing import Any, Literal, Union, get_args, get_origin

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from s2r._version import __version__
from s2r.geometry import ORTHONORMAL_TOL, check_rotation, rotation_angle_rad
from s2r.limits import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.sensor.model import SensorModel

__all__ = [
    "CENTRE_OFFSET_PX",
    "DEFAULT_SUBPIXEL_PX",
    "DISTORTION_COEFFICIENTS",
    "MAX_BASELINE_M",
    "MAX_IMAGE_PX",
    "MIN_BASELINE_M",
    "MIN_IMAGE_PX",
    "SCHEMA_VERSION",
    "CalibrationQuality",
    "Camera",
    "CameraUncertainty",
    "Distortion",
    "DroppedView",
    "Extrinsics",
    "MatcherSettings",
    "MonoProfile",
    "Provenance",
    "SimulationSettings",
    "SourceFile",
    "StereoProfile",
]

SCHEMA_VERSION: Literal[1] = 1
#: Intel's typical subpixel matching error ``s`` in the depth RMS model, pixels.
DEFAULT_SUBPIXEL_PX = 0.08
#: Number of coefficients per distortion model, in OpenCV's order.
DISTORTION_COEFFICIENTS: dict[str, int] = {"plumb_bob": 5, "rational_polynomial": 8, "equidistant": 4}

#: Principal point a convention PUBLISHES for a centred render, minus the exact centre ((W - 1) / 2 in
#: OpenCV's 0-based pixel-centre convention), pixels, in x and in y (REFERENCE.md): Gazebo classic
#: publishes (W + 1) / 2, gz-sim W / 2.
CENTRE_OFFSET_PX: dict[str, float] = {"gazebo-classic": 1.0, "gz-sim": 0.5, "exact": 0.0, "opencv": 0.0}

#: Field-of-view bounds, degrees: a pinhole cannot image 180 deg (170 is about its useful limit; wider lenses
#: use the equidistant model, up to 280 deg); 0.5 deg is narrower than a 1000 mm telephoto.
MIN_FOV_DEG, MAX_PINHOLE_FOV_DEG, MAX_FISHEYE_FOV_DEG = 0.5, 170.0, 280.0
#: Distortion coefficient bounds: rational-polynomial fits of narrow lenses reach thousands (numerator and
#: denominator nearly cancel: k1 1831 with k4 1830 was measured on a 20-view 640x480 rig); beyond 1e5 the model
#: is numerically meaningless. Tangential terms are fractions of a focal length.
MAX_DISTORTION_COEFF, MAX_TANGENTIAL_COEFF = 1e5, 1.0
#: Baseline bounds, metres: 1 mm is below the smallest stereo endoscopes; above 10 m a "baseline" is almost
#: always a T written in millimetres or in chessboard squares (pass ``--units-m``).
MIN_BASELINE_M, MAX_BASELINE_M = 1e-3, 10.0
#: Largest angle between the two cameras' orientations, degrees: beyond 90 deg the views barely overlap and
#: rectification has no common image plane (a camera turned 180 deg looks the other way).
MAX_STEREO_ROTATION_DEG = 90.0

DistortionModel = Literal["plumb_bob", "rational_polynomial", "equidistant"]
Convention = Literal["gazebo-classic", "gz-sim", "exact", "opencv"]
Origin = Literal["sim", "real", "nominal"]
Algorithm = Literal["sgbm", "sgbm_3way", "hh", "hh4", "bm"]


def _numeric(annotation: Any) -> bool:
    """True when a field's type is a number, an optional number, or a tuple of numbers."""
    if annotation in (int, float):
        return True
    args = [a for a in get_args(annotation) if a is not type(None) and a is not Ellipsis]
    origin = get_origin(annotation)
    if origin in (Union, types.UnionType):
        return bool(args) and all(_numeric(a) for a in args)
    return origin is tuple and bool(args) and all(_numeric(a) for a in args)


def _non_number(value: Any) -> Any:
    """The first string or bool inside ``value`` (a scalar or nested lists), or None."""
    if isinstance(value, (str, bytes, bool)):
        return value
    if isinstance(value, (list, tuple)):
        return next((found for v in value if (found := _non_number(v)) is not None), None)
    return None


class _Model(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False, validate_default=True)

    @field_validator("*", mode="before")
    @classmethod
    def _numbers_are_numbers(cls, value: Any, info: ValidationInfo) -> Any:
        field = cls.model_fields.get(info.field_name or "")
        if field is not None and _numeric(field.annotation):
            found = _non_number(value)
            if found is not None:
                raise ValueError(f"expected a number, got {found!r}: write numbers without quotes")
        return value


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


class Extrinsics(_Model):
    """Right camera relative to the left, OpenCV convention: ``X_right = R @ X_left + T`` (metres)."""

    rotation: tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]] = (
        (1.0, 0.0, 0.0),
        (0.0, 1.0, 0.0),
        (0.0, 0.0, 1.0),
    )
    translation_m: tuple[float, float, float]
    baseline_std_m: float | None = Field(default=None, ge=0)

    @model_validator(mode="after")
    def _valid_rigid_motion(self) -> Extrinsics:
        check_rotation(self.rotation, name="rotation", tol=ORTHONORMAL_TOL)
        if max(abs(t) for t in self.translation_m) > MAX_BASELINE_M:
            raise ValueError(f"translation_m {self.translation_m} exceeds {MAX_BASELINE_M:g} m: stereo baselines "
                             "are millimetres to metres (is T in millimetres or in chessboard squares?)")
        baseline = math.hypot(*self.translation_m)
        if baseline < 1e-6:
            raise ValueError("baseline is zero: translation_m must separate the two cameras")
        if not MIN_BASELINE_M <= baseline <= MAX_BASELINE_M:
            raise ValueError(f"baseline {baseline:g} m is outside {MIN_BASELINE_M:g}..{MAX_BASELINE_M:g} m: stereo "
                             "baselines are millimetres to metres (is T in other units?)")
        angle = math.degrees(rotation_angle_rad(np.asarray(self.rotation, dtype=np.float64)))
        if angle > MAX_STEREO_ROTATION_DEG:
            raise ValueError(f"the right camera is turned {angle:.1f} deg from the left (more than "
                             f"{MAX_STEREO_ROTATION_DEG:g}): the two views do not overlap enough for stereo "
                             "(is R inverted, or the pair's frames mixed up?)")
        return self


class MatcherSettings(_Model):
    """Stereo matcher settings (OpenCV StereoSGBM / StereoBM names) and the working depth range in metres.

    ``num_disparities`` None means: derive it from ``min_depth_m`` (fx' * B / z_min, rounded up to 16).
    """

    algorithm: Algorithm = "sgbm"
    min_disparity: int = 0
    num_disparities: int | None = Field(default=None, gt=0, le=MAX_IMAGE_PX)
    block_size: int = Field(default=5, ge=1, le=255)
    p1: int | None = Field(default=None, ge=0)
    p2: int | None = Field(default=None, ge=0)
    disp12_max_diff: int = 1
    uniqueness_ratio: int = Field(default=10, ge=0)
    speckle_window_size: int = Field(default=100, ge=0)
    speckle_range: int = Field(default=32, ge=0)
    pre_filter_cap: int = Field(default=63, ge=1)
    texture_threshold: int = Field(default=10, ge=0)
    min_depth_m: float = Field(default=0.3, gt=0)
    max_depth_m: float = Field(default=5.0, gt=0)

    @model_validator(mode="after")
    def _consistent(self) -> MatcherSettings:
        if self.num_disparities is not None and self.num_disparities % 16:
            raise ValueError(f"num_disparities must be a multiple of 16, got {self.num_disparities}")
        if self.block_size % 2 == 0:
            raise ValueError(f"block_size must be odd, got {self.block_size}")
        if self.algorithm == "bm" and self.block_size < 5:
            raise ValueError(f"StereoBM needs block_size >= 5, got {self.block_size}")
        if self.p1 is not None and self.p2 is not None and self.p2 <= self.p1:
            raise ValueError(f"p2 must exceed p1, got p1={self.p1} p2={self.p2}")
        if self.max_depth_m <= self.min_depth_m:
            raise ValueError(f"max_depth_m ({self.max_depth_m}) must exceed min_depth_m ({self.min_depth_m})")
        return self


class SourceFile(_Model):
    """A file a profile was made from, with its content hash."""

    path: str
    sha256: str = Field(pattern=r"^[0-9a-f]{64}$")


class DroppedView(_Model):
    """A calibration view rejected as an outlier (or undetected), with why."""

    name: str
    rms_px: float | None = None
    reason: str = ""


class CalibrationQuality(_Model):
    """Figures of a chessboard calibration, kept with the profile it produced."""

    pattern: tuple[int, int]
    square_m: float = Field(gt=0)
    views_used: int = Field(ge=0)
    views_dropped: tuple[DroppedView, ...] = ()
    #: views whose board was found (more than ``views_used`` when outliers were dropped or, for very large
    #: sets, only the most diverse views were solved); None when not recorded.
    views_detected: int | None = Field(default=None, ge=0)
    rms_left_px: float | None = None
    rms_right_px: float | None = None
    rms_stereo_px: float | None = None
    epipolar_rms_px: float | None = None
    coverage_left: float | None = Field(default=None, ge=0, le=1)
    coverage_right: float | None = Field(default=None, ge=0, le=1)
    tilt_range_deg: tuple[float, float] | None = None
    distance_range_m: tuple[float, float] | None = None
    distortion_terms: str = "k1k2"
    #: the calibration target when not a ``--pattern`` chessboard (e.g. ``aprilgrid 6x6 tags of 88 mm``).
    target: str | None = None


class SimulationSettings(_Model):
    """Simulator-side facts of a camera (clip planes, rate, noise); used by the renderer."""

    clip_near_m: float = Field(default=0.05, gt=0)
    clip_far_m: float = Field(default=100.0, gt=0)
    update_rate_hz: float | None = Field(default=None, gt=0)
    noise_stddev: float | None = Field(default=None, ge=0)

    @model_validator(mode="after")
    def _clip_order(self) -> SimulationSettings:
        if self.clip_far_m <= self.clip_near_m:
            raise ValueError(f"clip_far_m ({self.clip_far_m}) must exceed clip_near_m ({self.clip_near_m})")
        return self


class Provenance(_Model):
    """Where a profile came from: origin, method, source files, tool version, date, pixel convention."""

    origin: Origin
    method: str
    convention: Convention = "opencv"
    sources: tuple[SourceFile, ...] = ()
    tool_version: str = __version__
    created: str = Field(default_factory=lambda: _dt.date.today().isoformat())
    notes: str = ""
    calibration: CalibrationQuality | None = None


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
