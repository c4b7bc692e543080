"""Root-cause grouping: each single-parameter mismatch becomes ONE root cause carrying its consequences and edit.

Known answers: rigs that differ from a reference in exactly one parameter (built by tests.conftest.make_rig, not
by the code under test) must give exactly that root cause, whatever number of checks it fails.
"""

from __future__ import annotations

import math

import pytest

from s2r.profile import StereoProfile
from s2r.registry import load_profile
from s2r.validate.advice.causes import RootCause, group_failures
from s2r.validate.advice.edits import suggest_edits
from s2r.validate.measures.params import parameter_table
from s2r.validate.measures.projection import projection_difference
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import Check, parameter_checks, projection_checks
from tests.conftest import make_rig


def _static(sim: StereoProfile, real: StereoProfile) -> tuple[list[Check], list[RootCause]]:
    tol = Tolerances()
    rows = parameter_table(sim, real, tol)
    checks = parameter_checks(rows) + projection_checks(projection_difference(sim, real, distance_m=2.0), tol)
    edits = suggest_edits(sim, real, rows)
    return checks, group_failures(checks, rows, edits, sim=sim, real=real)


def _every_failure_once(checks: list[Check], causes: list[RootCause]) -> None:
    grouped = [c.name for cause in causes for c in cause.checks]
    assert sorted(grouped) == sorted(c.name for c in checks if not c.passed)


def test_one_wrong_fov_is_one_root_cause_with_its_consequences() -> None:
    real = make_rig(hfov_rad=math.radians(70.0))
    sim = make_rig(hfov_rad=math.radians(60.0))
    checks, causes = _static(sim, real)
    failures = [c for c in checks if not c.passed]
    assert len(failures) >= 8  # fx, fy of both cameras, HFOV, VFOV, 2 % distance, projection shifts
    assert [c.key for c in causes] == ["focal"]
    focal = causes[0]
    assert focal.what.startswith("HFOV: sim 60 vs real 70 deg")
    consequences = {c.name for c in focal.consequences}
    assert {"2% depth distance", "left projection p95", "right projection p95"} <= consequences
    assert [e.parameter for e in focal.edits] == ["horizontal_fov"]
    assert f"{math.radians(70.0):.4f} rad" in focal.fix
    _every_failure_once(checks, causes)


@pytest.mark.parametrize(("change", "key", "edit"), [
    ({"baseline_m": 0.12}, "baseline", "right camera joint origin"),
    ({"rotation_deg": (0.0, 1.0, 0.0)}, "rotation", "right camera joint origin"),
    ({"distortion": (-0.2, 0.05, 0.0, 0.0, 0.0)}, "lens", "distortion"),
    ({"cx": 300.0, "cy": 250.0}, "principal_point", "principal point"),
])
def test_single_parameter_mismatches(change: dict[str, object], key: str, edit: str) -> None:
    real = make_rig()
    sim = make_rig(**change)  # type: ignore[arg-type]
    checks, causes = _static(sim, real)
    assert [c.key for c in causes] == [key]
    assert [e.parameter for e in causes[0].edits] == [edit]
    _every_failure_once(checks, causes)


def test_resolution_alone_explains_its_focal_lengths() -> None:
    # same 60 deg field of view at two resolutions: fx and cx differ only because the size does
    real, sim = make_rig(width=848, height=480), make_rig(width=640, height=480)
    checks, causes = _static(sim, real)
    assert [c.key for c in causes] == ["resolution"]
    assert {"left fx", "left cx", "VFOV"} <= {c.name for c in causes[0].consequences}
    _every_failure_once(checks, causes)
    assert causes[0].edits[0].target == "848x480"


def test_seed_rig_against_the_realsense() -> None:
    real = load_profile("realsense_d435_848x480")
    sim = make_rig(cx=320.5, cy=240.5)
    checks, causes = _static(sim, real)
    keys = [c.key for c in causes]
    assert keys[:2] == ["resolution", "focal"] and "baseline" in keys
    # fx * B: the sim's 10 cm baseline (2x) changes it more than its focal length (554 vs 424 px, 1.3x)
    baseline = next(c for c in causes if c.key == "baseline")
    assert "2% depth distance" in {c.name for c in baseline.consequences}
    _every_failure_once(checks, causes)
    as_json = causes[0].as_dict()
    assert set(as_json) == {"cause", "title", "what", "fix", "edits", "checks", "consequences"}


def test_self_check_failures_go_to_depth_and_bench() -> None:
    checks = [Check("recovery", "profile fx", 2.0, 1.0, "px", False, "recovered fx off"),
              Check("depth", "profile median error 1-2 m", 3.0, 1.0, "%", False, "depth off"),
              Check("depth", "profile fill rate 1-2 m", 0.9, 0.8, "", True, "fill ok")]
    causes = group_failures(checks, [], [])
    assert [c.key for c in causes] == ["depth", "bench"]
    assert "--preset" in causes[0].fix and "renderer" in causes[1].fix
    assert group_failures([c for c in checks if c.passed], [], []) == []
