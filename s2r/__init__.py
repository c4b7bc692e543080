"""s2r: move stereo-camera setups between simulation and real hardware.

One typed :class:`StereoProfile` (YAML on disk) drives one rectification + matching pipeline
(:class:`StereoPipeline`), whether it came from a robot description (sim) or a calibration (real).

    >>> import s2r
    >>> profile = s2r.load_profile("realsense_d435_848x480")
    >>> profile.baseline_m
    0.05
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from s2r._version import __version__
from s2r.errors import (
    CalibrationError,
    DepthError,
    FormatError,
    OutputExistsError,
    ProfileError,
    RenderError,
    S2RError,
    SourceError,
    ValidateError,
)

if TYPE_CHECKING:
    from s2r.depth.pipeline import StereoPipeline
    from s2r.formats.s2r_yaml import dump_profile
    from s2r.profile import Camera, Distortion, Extrinsics, MatcherSettings, MonoProfile, Provenance, StereoProfile
    from s2r.registry import list_profiles, load_profile

#: Public names loaded on first use (PEP 562), so `import s2r` and the CLI start without pydantic's model
#: building or OpenCV: name -> module.
_LAZY = {
    **dict.fromkeys(("Camera", "Distortion", "Extrinsics", "MatcherSettings", "MonoProfile", "Provenance",
                     "StereoProfile"), "s2r.profile"),
    "dump_profile": "s2r.formats.s2r_yaml", "list_profiles": "s2r.registry", "load_profile": "s2r.registry",
    "StereoPipeline": "s2r.depth.pipeline",
}

__all__ = [
    "CalibrationError",
    "Camera",
    "DepthError",
    "Distortion",
    "Extrinsics",
    "FormatError",
    "MatcherSettings",
    "MonoProfile",
    "OutputExistsError",
    "ProfileError",
    "Provenance",
    "RenderError",
    "S2RError",
    "SourceError",
    "StereoPipeline",
    "StereoProfile",
    "ValidateError",
    "__version__",
    "dump_profile",
    "list_profiles",
    "load_profile",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 's2r' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
