"""Theoretical depth resolution of a profile: Intel's RMS model by distance and the 2 % distance.

Intel's model: ``RMS(Z) = Z^2 s / (fx B)`` metres, with ``s`` the sub-pixel matching error (0.08 px
typical), ``fx`` the focal length in pixels and ``B`` the baseline in metres.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from s2r.profile import DEFAULT_SUBPIXEL_PX, MatcherSettings, StereoProfile

__all__ = ["DepthResolution", "depth_resolution", "theory_rel_rms"]


@dataclass(frozen=True)
class DepthResolution:
    """Theoretical depth error of one profile.

    ``distances_m`` and ``rms_m`` are parallel tuples (metres); ``rel_pct`` is ``100 rms / Z``;
    ``limit_2pct_m`` the depth up to which the RMS stays under 2 % of the depth; ``near_m``/``far_m`` the
    depth range the matcher's disparity range can see.
    """

    profile: str
    subpixel_px: float
    distances_m: tuple[float, ...]
    rms_m: tuple[float, ...]
    rel_pct: tuple[float, ...]
    limit_2pct_m: float
    near_m: float
    far_m: float

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping for JSON."""
        return asdict(self)


def theory_rel_rms(profile: StereoProfile, depth_m: float, *, subpixel_px: float = DEFAULT_SUBPIXEL_PX) -> float:
    """Theoretical RMS depth error at ``depth_m`` as a fraction of the depth (``Z s / (fx B)``)."""
    return float(profile.depth_rms_m(depth_m, subpixel_px)) / depth_m


def depth_resolution(profile: StereoProfile, distances_m: tuple[float, ...] | list[float], *,
                     matcher: MatcherSettings | None = None,
                     subpixel_px: float = DEFAULT_SUBPIXEL_PX) -> DepthResolution:
    """Intel's theoretical depth RMS at each distance (metres), the 2 % distance and the matcher's range."""
    z = np.asarray(distances_m, dtype=np.float64)
    rms = np.asarray(profile.depth_rms_m(z, subpixel_px), dtype=np.float64)
    near, far = profile.depth_range_m(matcher)
    return DepthResolution(
        profile=profile.name, subpixel_px=subpixel_px, distances_m=tuple(float(v) for v in z),
        rms_m=tuple(float(v) for v in rms), rel_pct=tuple(float(v) for v in 100.0 * rms / z),
        limit_2pct_m=profile.max_depth_within_m(0.02, subpixel_px), near_m=float(near), far_m=float(far),
    )
