"""Rigs and comparisons shared by the format tests."""

from __future__ import annotations

import numpy as np

from s2r.profile import StereoProfile
from tests.conftest import make_rig


def with_distortion(rig: StereoProfile, model: str, coeffs: tuple[float, ...]) -> StereoProfile:
    """``rig`` with both cameras given distortion ``model`` and ``coeffs``."""
    data = rig.model_dump()
    for side in ("left", "right"):
        data[side]["distortion"] = {"model": model, "coefficients": coeffs}
    return StereoProfile.model_validate(data)


def distorted_rotated_rig() -> StereoProfile:
    """A plumb_bob rig with all five coefficients, an off-centre principal point and a slight rotation."""
    return make_rig(name="distorted", distortion=(-0.12, 0.05, 0.001, -0.002, 0.01), rotation_deg=(0.3, -0.5, 0.2),
                    cx=322.0, cy=238.5)


def assert_same_rig(back: StereoProfile, truth: StereoProfile, tol: float = 1e-9) -> None:
    """K, D, model and size of both cameras, R and T agree to ``tol`` (absolute)."""
    for cam_b, cam_t in ((back.left, truth.left), (back.right, truth.right)):
        np.testing.assert_allclose(cam_b.K, cam_t.K, atol=tol, rtol=0)
        np.testing.assert_allclose(cam_b.D, cam_t.D, atol=tol, rtol=0)
        assert cam_b.distortion.model == cam_t.distortion.model
        assert cam_b.image_size == cam_t.image_size
    np.testing.assert_allclose(back.R, truth.R, atol=tol, rtol=0)
    np.testing.assert_allclose(back.T, truth.T, atol=tol, rtol=0)
