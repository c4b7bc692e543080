"""Parameter table and mrcal-style projection difference on rigs with known differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from s2r.lens.distortion import project_points, undistort_pixels
from s2r.profile import CameraUncertainty, Extrinsics, StereoProfile
from s2r.registry import load_profile
from s2r.validate.measures.params import ParamRow, parameter_table
from s2r.validate.measures.projection import projection_difference
from s2r.validate.tolerances import Tolerances
from tests.conftest import make_rig


def _rows(sim: StereoProfile, real: StereoProfile) -> dict[str, ParamRow]:
    return {r.name: r for r in parameter_table(sim, real, Tolerances())}


def test_profile_against_itself_has_no_difference() -> None:
    rig = make_rig(distortion=(-0.1, 0.02, 0.0, 0.0, 0.0), rotation_deg=(0.2, 0.1, 0.0))
    rows = _rows(rig, rig)
    assert all(not r.exceeds_tolerance for r in rows.values())
    assert all(abs(r.diff) < 1e-9 for r in rows.values())


def test_known_differences_are_reported_with_hand_values() -> None:
    real = load_profile("realsense_d435_848x480")
    sim = make_rig(cx=320.5, cy=240.5)  # the seed's gazebo rig: 640x480, hfov 1.047, B 0.1
    rows = _rows(sim, real)
    assert rows["image size"].sim == "640x480" and rows["image size"].real == "848x480"
    assert rows["image size"].diff == 208 and rows["image size"].exceeds_tolerance
    assert rows["left fx"].diff == pytest.approx(320 / math.tan(1.047 / 2) - 424.0)
    assert rows["baseline"].diff == pytest.approx(0.05) and rows["baseline"].exceeds_tolerance
    assert rows["HFOV"].real == pytest.approx(math.degrees(2 * math.atan(424 / 424)), abs=1e-3)
    assert rows["HFOV"].exceeds_tolerance
    assert rows["2% depth distance"].real == pytest.approx(0.02 * 424 * 0.05 / 0.08)
    assert not rows["inter-camera rotation"].exceeds_tolerance
    assert not rows["left distortion"].exceeds_tolerance


def test_sigma_flag_uses_the_real_std() -> None:
    real = make_rig()
    std = CameraUncertainty(fx_px=0.1, fy_px=0.1, cx_px=0.2, cy_px=0.2)
    real = real.model_copy(update={"left": real.left.model_copy(update={"std": std}),
                                   "extrinsics": Extrinsics(translation_m=(-0.1, 0, 0), baseline_std_m=1e-4)})
    sim = make_rig(baseline_m=0.1005)
    rows = _rows(sim, real)
    assert rows["left fx"].real_std == 0.1 and rows["left fx"].exceeds_sigma is False
    assert rows["baseline"].exceeds_sigma is True  # 0.5 mm > 3 x 0.1 mm ...
    assert not rows["baseline"].exceeds_tolerance  # ... but within 2 % of 0.1 m
    assert rows["right fx"].exceeds_sigma is None


def test_rotation_difference_is_the_relative_angle() -> None:
    rows = _rows(make_rig(rotation_deg=(0.0, 0.5, 0.0)), make_rig(rotation_deg=(0.0, 0.2, 0.0)))
    assert rows["inter-camera rotation"].diff == pytest.approx(0.3, abs=1e-6)
    assert rows["inter-camera rotation"].exceeds_tolerance


def test_unproject_project_round_trip_with_distortion() -> None:
    cam = make_rig(distortion=(-0.12, 0.05, 0.001, -0.001, 0.0)).left
    pixels = np.array([[0.0, 0.0], [319.5, 239.5], [600.0, 50.0], [100.0, 400.0]])
    rays = undistort_pixels(cam, pixels)
    back = project_points(cam, np.column_stack([rays * 2.0, np.full(4, 2.0)]))
    np.testing.assert_allclose(back, pixels, atol=1e-6)


def test_projection_difference_of_identical_profiles_is_zero() -> None:
    rig = make_rig(distortion=(-0.1, 0.02, 0.0, 0.0, 0.0))
    for diff in projection_difference(rig, rig):
        assert diff.max_px < 1e-6
        assert diff.shift_px.shape == (30, 40)


def test_principal_point_shift_moves_every_pixel_by_the_same_amount() -> None:
    left, right = projection_difference(make_rig(cx=322.5), make_rig())
    np.testing.assert_allclose(left.shift_px, 3.0, atol=1e-9)
    np.testing.assert_allclose(right.shift_px, 3.0, atol=1e-9)


def test_focal_difference_grows_towards_the_corners() -> None:
    real = make_rig()
    sim = real.model_copy(update={"left": real.left.model_copy(update={"fx_px": real.left.fx_px * 1.01,
                                                                        "fy_px": real.left.fy_px * 1.01})})
    left, _ = projection_difference(sim, real)
    corner = 0.01 * math.hypot(319.5, 239.5)  # pixel (0, 0) is 0.01 (u - cx, v - cy) away
    assert left.max_px == pytest.approx(corner, rel=1e-6)
    assert left.shift_px[0, 0] == pytest.approx(corner, rel=1e-6)


def test_same_camera_at_another_resolution_matches_after_scaling() -> None:
    real = make_rig()
    big = real.left.scaled(1280, 960)
    sim = real.model_copy(update={"left": big, "right": big})
    for diff in projection_difference(sim, real):
        assert diff.max_px < 1e-9


def test_baseline_difference_shows_in_the_right_camera_at_the_working_distance() -> None:
    sim, real = make_rig(baseline_m=0.11), make_rig(baseline_m=0.10)
    left, right = projection_difference(sim, real, distance_m=2.0)
    assert left.max_px < 1e-9
    np.testing.assert_allclose(right.shift_px, real.left.fx_px * 0.01 / 2.0, rtol=1e-9)


def test_the_pairs_own_non_overlap_is_not_a_sim_real_difference() -> None:
    """A profile against itself: nothing the real cameras see falls outside the sim images, left or right.

    (The right camera cannot see the real left image's left edge at 2 m; that share is the pair's non-overlap.)"""
    rig = make_rig(baseline_m=0.3)
    left, right = projection_difference(rig, rig)
    assert left.outside_fraction == 0.0 and right.outside_fraction == 0.0
    narrower = make_rig(baseline_m=0.3, hfov_rad=0.9)  # a narrower sim misses what the real one sees
    assert projection_difference(narrower, rig)[1].outside_fraction > 0.05
