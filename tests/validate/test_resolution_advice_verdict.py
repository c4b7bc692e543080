"""Theoretical depth resolution, the suggested edits and the verdict checks, against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from s2r.registry import load_profile
from s2r.validate.advice.edits import gazebo_hfov_rad, right_joint_origin, suggest_edits
from s2r.validate.measures.depth_accuracy import DEFAULT_BINS_M, bin_stats, pixel_errors, within_stats
from s2r.validate.measures.params import parameter_table
from s2r.validate.measures.resolution import depth_resolution
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import parameter_checks
from tests.conftest import make_rig


def test_intel_model_figures_for_the_realsense() -> None:
    real = load_profile("realsense_d435_848x480")
    res = depth_resolution(real, (1.0, 2.0))
    # RMS = Z^2 s / (fx B) = 0.08 / (424 * 0.05) at 1 m (REFERENCE.md: about 3.8 mm at 1 m, 15 mm at 2 m)
    assert res.rms_m[0] == pytest.approx(0.08 / 21.2)
    assert res.rms_m[1] == pytest.approx(4 * 0.08 / 21.2)
    assert res.rel_pct[1] == pytest.approx(100 * 2 * 0.08 / 21.2)
    assert res.limit_2pct_m == pytest.approx(5.3)
    near, far = real.depth_range_m()
    assert (res.near_m, res.far_m) == (near, far)


def test_gazebo_hfov_inverts_the_gazebo_focal_formula() -> None:
    real = load_profile("realsense_d435_848x480")
    assert gazebo_hfov_rad(real) == pytest.approx(2 * math.atan(848 / (2 * 424)))
    assert gazebo_hfov_rad(make_rig(hfov_rad=1.047)) == pytest.approx(1.047)


def test_right_joint_origin_is_beside_the_left_link() -> None:
    xyz, rpy = right_joint_origin(make_rig(baseline_m=0.1))
    assert xyz == pytest.approx((0.0, -0.1, 0.0)) and rpy == pytest.approx((0.0, 0.0, 0.0))
    # a right camera toed in (yaw about the optical y axis) shows up as a link yaw about z
    _, rpy = right_joint_origin(make_rig(rotation_deg=(0.0, 2.0, 0.0)))
    assert abs(rpy[2]) == pytest.approx(math.radians(2.0), abs=1e-6)


def test_edits_for_the_seed_rig_against_the_realsense() -> None:
    real = load_profile("realsense_d435_848x480")
    sim = make_rig(cx=320.5, cy=240.5)
    edits = {e.parameter: e for e in suggest_edits(sim, real, parameter_table(sim, real, Tolerances()))}
    assert edits["resolution"].target == "848x480"
    assert edits["horizontal_fov"].target.startswith("1.5708 rad")
    assert 'xyz="0 -0.05 0"' in edits["right camera joint origin"].target
    # the real cy (235.0) lies 4.5 px above the centre of a 480-row image; <lens><intrinsics> takes it + 0.5
    assert edits["principal point"].target.startswith("left (423.00, 235.50), right (")
    centred = make_rig(width=848, height=480, hfov_rad=math.pi / 2, baseline_m=0.05)
    assert "principal point" not in {e.parameter for e in suggest_edits(
        sim, centred, parameter_table(sim, centred, Tolerances()))}
    assert "export-gazebo realsense_d435_848x480" in edits["sensor XML"].where


def test_off_centre_sim_principal_point_gets_an_edit() -> None:
    sim, real = make_rig(cx=322.5), make_rig()
    edits = {e.parameter: e for e in suggest_edits(sim, real, parameter_table(sim, real, Tolerances()))}
    assert edits["principal point"].target == "left (320.00, 240.00), right (320.00, 240.00) px"
    assert edits["principal point"].current.startswith("left (323.00, 240.00)")
    assert set(edits) == {"principal point", "sensor XML"}


def test_advice_values_are_what_export_gazebo_writes() -> None:
    """Every cx/cy/fy the report tells the user to type equals the export's <lens><intrinsics> (both cameras)."""
    import re
    import xml.etree.ElementTree as ET

    from s2r.sources.export.gazebo import export_gazebo

    real = make_rig(cx=331.25, cy=228.75, origin="real")
    left = real.left.model_copy(update={"fy_px": real.left.fx_px * 1.03})
    right = real.right.model_copy(update={"fy_px": real.right.fx_px * 1.035, "cx_px": 327.0, "cy_px": 231.0})
    real = real.model_copy(update={"left": left, "right": right})
    sim = make_rig()
    edits = {e.parameter: e for e in suggest_edits(sim, real, parameter_table(sim, real, Tolerances()))}
    centres = [(float(a), float(b)) for a, b in re.findall(r"\(([-\d.]+), ([-\d.]+)\)",
                                                           edits["principal point"].target)]
    fys = [float(v) for v in re.findall(r"(?:left|right) ([-\d.]+)", edits["fy"].target)]
    for fmt in ("urdf", "sdf", "gz-sim"):
        xml, _ = export_gazebo(real, fmt=fmt)
        lens = [{c.tag: float(c.text or "nan") for c in node} for node in ET.fromstring(xml).iter("intrinsics")]
        assert len(lens) == 2, fmt
        assert centres == [(pytest.approx(k["cx"], abs=0.005), pytest.approx(k["cy"], abs=0.005)) for k in lens]
        assert fys == [pytest.approx(k["fy"], abs=0.005) for k in lens]
    assert centres[0] == (331.75, 229.25)  # OpenCV's 0-based principal point + 0.5


def test_no_edits_when_profiles_match() -> None:
    rig = make_rig()
    assert suggest_edits(rig, rig, parameter_table(rig, rig, Tolerances())) == []


def test_parameter_checks_fail_exactly_on_the_differences() -> None:
    sim, real = make_rig(baseline_m=0.12), make_rig()
    checks = parameter_checks(parameter_table(sim, real, Tolerances()))
    failed = {c.name for c in checks if not c.passed}
    assert failed == {"baseline", "2% depth distance"}
    assert any("baseline: sim 0.12 vs real 0.1 m" in c.text for c in checks)


def test_pixel_errors_and_bins_on_known_values() -> None:
    truth = np.array([[0.6, 0.8, 1.5, np.nan], [2.5, 2.5, 4.0, 5.0]], dtype=np.float32)
    est = np.array([[0.606, np.nan, 1.47, 3.0], [2.5, 2.55, np.nan, 4.9]], dtype=np.float32)
    t, rel = pixel_errors(est, truth)
    assert t.size == 7  # the NaN truth is not scored
    bins = bin_stats(t, rel, DEFAULT_BINS_M)
    first, second, third, last = bins
    assert first.pixels == 2 and first.valid == 1 and first.fill_rate == 0.5
    assert first.median_pct == pytest.approx(1.0, abs=1e-4) and first.bias_pct == pytest.approx(1.0, abs=1e-4)
    assert second.median_pct == pytest.approx(2.0, abs=1e-4) and second.bias_pct == pytest.approx(-2.0, abs=1e-4)
    assert third.pixels == 2 and third.median_pct == pytest.approx(1.0, abs=1e-4)
    assert last.pixels == 2 and last.valid == 1 and last.median_pct == pytest.approx(2.0, abs=1e-4)  # 5.0 included
    within = within_stats(t, rel, 3.0)
    assert within.pixels == 5 and within.valid == 4


def test_pixels_not_visible_in_the_right_image_are_not_scored() -> None:
    truth = np.full((2, 4), 1.0, dtype=np.float32)
    disparity = np.full((2, 4), 2.0, dtype=np.float32)  # columns 0 and 1 map outside the right image
    t, _ = pixel_errors(np.full((2, 4), np.nan, np.float32), truth, disparity)
    assert t.size == 4


def test_theory_bounds_of_a_bin() -> None:
    rig = make_rig()
    (b,) = bin_stats(np.array([1.5]), np.array([0.001]), [(1.0, 2.0)], profile=rig)
    assert b.theory_hi_pct == pytest.approx(100 * 2.0 * 0.08 / (rig.left.fx_px * 0.1))
    assert b.theory_lo_pct == pytest.approx(100 * 1.0 * 0.08 / (rig.left.fx_px * 0.1))
