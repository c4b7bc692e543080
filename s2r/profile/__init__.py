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

Layout (imports run one way, top imports bottom; every public name is importable from ``s2r.profile`` itself):

- :mod:`s2r.profile.rig` -- :class:`StereoProfile` and :class:`MonoProfile`.
- :mod:`s2r.profile.settings` -- extrinsics, matcher and simulator settings, provenance and calibration figures.
- :mod:`s2r.profile.camera` -- :class:`Camera`, :class:`Distortion`, :class:`CameraUncertainty`.
- :mod:`s2r.profile.base` -- the bounds, units and the strict base model every part shares.

Low in the layers: imports :mod:`s2r.geometry`, :mod:`s2r.limits` and the sensor model's type
(:mod:`s2r.sensor.model`) only.
"""

from s2r.limits import MAX_IMAGE_PX, MIN_IMAGE_PX
from s2r.profile.base import (
    CENTRE_OFFSET_PX,
    DEFAULT_SUBPIXEL_PX,
    DISTORTION_COEFFICIENTS,
    MAX_BASELINE_M,
    MIN_BASELINE_M,
    SCHEMA_VERSION,
)
from s2r.profile.camera import Camera, CameraUncertainty, Distortion
from s2r.profile.rig import MonoProfile, StereoProfile
from s2r.profile.settings import (
    CalibrationQuality,
    DroppedView,
    Extrinsics,
    MatcherSettings,
    Provenance,
    SimulationSettings,
    SourceFile,
)

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
