"""The validation report answers at a glance: a coloured verdict banner, root causes first, one number style,
captions, and the renderer/calibrator self-test as a closed "test bench" section after the answer.

Built from a real static comparison (parameters, projection, edits) of the seed rig and the RealSense, with
recovery and depth figures made up here (the expensive stages are covered by test_validate_chain.py).
"""

from __future__ import annotations

import re

import numpy as np

from s2r.htmlreport import ReportSection, render_report
from s2r.registry import load_profile
from s2r.validate.measures.depth_accuracy import DEFAULT_BINS_M, DepthAccuracy, bin_stats, within_stats
from s2r.validate.measures.recovery import RecoveryResult, RecoveryRow
from s2r.validate.report import EXTRA_SECTIONS, build_sections
from s2r.validate.run import QUICK, ValidationResult, _collect_checks, _static_stages
from s2r.validate.summary import summary_lines
from s2r.validate.tolerances import Tolerances
from s2r.validate.verdict import parameter_checks
from tests.conftest import make_rig


def _result(*, same: bool = False) -> ValidationResult:
    real = load_profile("realsense_d435_848x480")
    sim = real if same else make_rig(name="seed_rig", cx=320.5, cy=240.5)
    result = ValidationResult(roles={"sim": sim, "real": real}, settings=QUICK, tolerances=Tolerances())
    _static_stages(result, sim, real)
    rng = np.random.default_rng(0)
    truth = rng.uniform(0.5, 5.0, 5000)
    for role, profile in result.roles.items():
        result.recovery[role] = RecoveryResult(profile.name, [RecoveryRow("left fx", "px", 424.0, 424.1, 0.1, 0.05,
                                                                          2.0, 1.3, True)], 0.1, 16, 16)
        rel = rng.normal(0, 0.005, truth.size)
        result.depth[role] = DepthAccuracy(profile.name, "profile", ("planes",), (1.0, 2.0),
                                           bin_stats(truth, rel, DEFAULT_BINS_M, profile=profile),
                                           within_stats(truth, rel, profile=profile))
    result.checks = _collect_checks(result)
    result.seconds = {"total": 12.5}
    return result


def test_banner_and_root_causes_come_first() -> None:
    page = render_report("t", build_sections(_result()))
    first_h2 = page.index("<h2>")
    assert page.index("class='banner fail'") < page.index("Root causes") < page.index("What to change")
    assert page[first_h2:first_h2 + len("<h2>Verdict</h2>")] == "<h2>Verdict</h2>"
    banner = re.search(r"class='banner fail'>(.*?)</div>", page, re.S)
    assert banner is not None and "resolution, focal length / field of view" in banner.group(1)
    # the self-test and run settings are closed <details> blocks after the answer
    bench = page.index("<details><summary>The test bench itself")
    assert bench > page.index("Depth accuracy") and page.index("<details><summary>Run settings") > bench
    assert "{'" not in page and "&#x27;views&#x27;" not in page  # no raw Python dict anywhere


def test_one_number_style_with_captions() -> None:
    page = render_report("t", build_sections(_result()))
    assert "fill rate (%)" in page and "fill rate 9" not in page.replace("fill rate (%)", "")
    assert re.search(r"fill rate 100\.0 %|fill rate \d\d\.\d %", page)
    assert page.count("<caption>") >= 6  # causes, edits, parameters, projection, resolution, depth, bench
    assert "white-space: pre-wrap" in page  # long XML lines wrap instead of overflowing


def test_pass_banner_and_extra_sections_hook() -> None:
    result = _result(same=True)
    EXTRA_SECTIONS.append(lambda r: ReportSection("Recorded pairs", paragraphs=["hook"]))
    try:
        page = render_report("t", build_sections(result))
    finally:
        EXTRA_SECTIONS.pop()
    assert "class='banner pass'" in page and "PASS: the sim is a faithful twin" in page
    assert page.index("Recorded pairs") < page.index("The test bench itself")
    assert summary_lines(result)[-2].startswith("PASS")


def test_terminal_summary_groups_like_the_report() -> None:
    lines = summary_lines(_result())
    verdict = lines[next(i for i, line in enumerate(lines) if line.startswith("FAIL"))]
    assert "root cause(s)" in verdict
    text = "\n".join(lines)
    assert "1. Resolution" in text and "2. Focal length / field of view" in text
    assert "also fails: left fx, left fy, right fx, right fy" in text


def test_principal_point_cause_uses_the_pixels_images_obey() -> None:
    # gazebo_dual_camera declares Gazebo classic's cx = 320.5: its images are centred at 319.5 (OpenCV pixels)
    sim, real = load_profile("gazebo_dual_camera"), load_profile("realsense_d435_848x480")
    result = ValidationResult(roles={"sim": sim, "real": real}, settings=QUICK, tolerances=Tolerances())
    _static_stages(result, sim, real)
    result.checks = parameter_checks(result.params)
    (pp,) = [c for c in result.root_causes if c.key == "principal_point"]
    assert "sim (+0.00, +0.00) px" in pp.what
