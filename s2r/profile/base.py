"""What every part of a profile shares: the schema version, the physical bounds (field of view, distortion,
baseline, stereo rotation), the literal choices (distortion model, pixel convention, origin, matcher) and the strict
frozen pydantic base model that refuses NaN/inf and strings or booleans where a number is expected."""

from __future__ import annotations

import types
from typing import Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

__all__ = ["CENTRE_OFFSET_PX", "DEFAULT_SUBPIXEL_PX", "DISTORTION_COEFFICIENTS", "MAX_BASELINE_M", "MIN_BASELINE_M",
           "SCHEMA_VERSION"]

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
