"""The parts of a profile beside its cameras: extrinsics (OpenCV's ``X_right = R @ X_left + T``, metres),
matcher settings and working range, simulator settings, and the provenance with a calibration's figures."""

from __future__ import annotations

import datetime as _dt
import math

import numpy as np
from pydantic import Field, model_validator

from s2r._version import __version__
from s2r.geometry import ORTHONORMAL_TOL, check_rotation, rotation_angle_rad
from s2r.limits import MAX_IMAGE_PX
from s2r.profile.base import (
    MAX_BASELINE_M,
    MAX_STEREO_ROTATION_DEG,
    MIN_BASELINE_M,
    Algorithm,
    Convention,
    Origin,
    _Model,
)

__all__ = ["CalibrationQuality", "DroppedView", "Extrinsics", "MatcherSettings", "Provenance", "SimulationSettings",
           "SourceFile"]


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
