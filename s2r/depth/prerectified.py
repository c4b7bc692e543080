"""Pairs that are already rectified (Middlebury's, a camera driver's rectified topics): the profile their
geometry implies, and its rectification taken as given (no resampling: the remap tables are the identity).

Geometry, pixels and metres: both images share ``f`` and the row ``cy``; the left principal point is at ``cx``
and the right one at ``cx + doffs`` (Middlebury's ``doffs``), the right camera ``baseline`` metres to the right.
Depth is then ``Z = f B / (d + doffs)`` with ``d = x_left - x_right``.
"""

from __future__ import annotations

import math

import numpy as np

from s2r.errors import DepthError
from s2r.profile import Camera, Extrinsics, MatcherSettings, Provenance, StereoProfile
from s2r.rectification import StereoRectification

__all__ = ["given_rectification", "rectified_profile"]


def rectified_profile(size: tuple[int, int], *, f_px: float, baseline_m: float, cx_px: float, cy_px: float,
                      doffs_px: float = 0.0, name: str = "rectified_pair") -> StereoProfile:
    """The profile of an already-rectified pair of ``size`` ``(width, height)`` px (no distortion, R = I,
    T = (-baseline, 0, 0)); DepthError naming the option that is out of range."""
    width, height = size
    for field, value, ok in (("--f", f_px, f_px > 0), ("--baseline", baseline_m, baseline_m > 0),
                             ("--cx", cx_px, -width <= cx_px <= 2 * width),
                             ("--cy", cy_px, -height <= cy_px <= 2 * height),
                             ("--doffs", doffs_px, abs(doffs_px) <= width)):
        if not (math.isfinite(value) and ok):
            raise DepthError(f"out of range for a {width}x{height} rectified pair: {value}", field=field,
                             hint="f and baseline > 0; cx, cy near the image centre; |doffs| under the width")
    left = Camera(width_px=width, height_px=height, fx_px=f_px, fy_px=f_px, cx_px=cx_px, cy_px=cy_px)
    right = left.model_copy(update={"cx_px": cx_px + doffs_px})
    return StereoProfile(
        name=name, left=left, right=right,
        extrinsics=Extrinsics(rotation=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
                              translation_m=(-baseline_m, 0.0, 0.0)),
        matcher=MatcherSettings(),
        provenance=Provenance(origin="real", method="s2r depth --rectified (given f, baseline, cx, cy, doffs)"))


def given_rectification(profile: StereoProfile) -> StereoRectification:
    """The rectification of a :func:`rectified_profile` as it is: R1 = R2 = I, P1 / P2 its cameras' K (so the
    remap tables are the identity), ``P2[0, 3] = -f B``, and OpenCV's Q with the principal-point offset."""
    K1, K2 = profile.left.K, profile.right.K
    f, B = float(K1[0, 0]), float(-profile.T.reshape(3)[0])
    P1 = np.hstack([K1, np.zeros((3, 1))])
    P2 = np.hstack([K2, np.array([[-f * B], [0.0], [0.0]])])
    cx, cy, cx_right = float(K1[0, 2]), float(K1[1, 2]), float(K2[0, 2])
    Q = np.array([[1.0, 0.0, 0.0, -cx], [0.0, 1.0, 0.0, -cy], [0.0, 0.0, 0.0, f],
                  [0.0, 0.0, 1.0 / B, (cx_right - cx) / B]])
    size = profile.image_size
    full = (0, 0, int(size[0]), int(size[1]))
    return StereoRectification(R1=np.eye(3), R2=np.eye(3), P1=P1, P2=P2, Q=Q, image_size=size, roi_left=full,
                               roi_right=full)
