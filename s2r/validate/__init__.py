"""Sim-versus-real validation: parameter and projection diffs, depth resolution, recovered calibration, depth
accuracy on rendered ground truth, the edits that make the sim match, a verdict and reports.

    >>> from s2r.validate import validate, QUICK
    >>> result = validate(load_profile("gazebo_dual_camera"), load_profile("realsense_d435_848x480"), settings=QUICK)
    >>> result.passed, [c.text for c in result.failures]

Layout (imports run one way, top imports bottom; tests/test_import_graph.py):

- ``run`` (the whole comparison), ``tasks`` (its expensive stages in parallel processes), ``settings`` (how much work),
  ``summary`` and ``report`` (terminal lines, HTML page).
- :mod:`s2r.validate.advice` -- what to change: edits for Gazebo and MuJoCo sims, root causes grouping the failures.
- :mod:`s2r.validate.recording` -- sim and real cameras measured on recordings, compared per distance bin.
- ``verdict`` (every figure against its tolerance) and ``tolerances``.
- :mod:`s2r.validate.measures` -- the figures: parameter and projection diffs, depth resolution, recovered
  calibration, depth accuracy on rendered ground truth.
"""

import importlib
from typing import TYPE_CHECKING, Any

from s2r.validate.advice.edits import Edit, gazebo_hfov_rad, right_joint_origin, suggest_edits
from s2r.validate.measures.depth_accuracy import DEFAULT_BINS_M, BinStats, DepthAccuracy, measure_depth_accuracy
from s2r.validate.measures.params import ParamRow, parameter_table
from s2r.validate.measures.projection import ProjectionDiff, projection_difference
from s2r.validate.measures.recovery import RecoveryResult, RecoveryRow, compare_recovered, recover_calibration
from s2r.validate.measures.resolution import DepthResolution, depth_resolution
from s2r.validate.run import FULL, QUICK, Settings, ValidationResult, check_distances, validate
from s2r.validate.summary import summary_lines
from s2r.validate.tolerances import Tolerances, load_tolerances
from s2r.validate.verdict import Check

if TYPE_CHECKING:
    from s2r.validate.report import write_validation_report

__all__ = [
    "DEFAULT_BINS_M",
    "FULL",
    "QUICK",
    "BinStats",
    "Check",
    "DepthAccuracy",
    "DepthResolution",
    "Edit",
    "ParamRow",
    "ProjectionDiff",
    "RecoveryResult",
    "RecoveryRow",
    "Settings",
    "Tolerances",
    "ValidationResult",
    "check_distances",
    "compare_recovered",
    "depth_resolution",
    "gazebo_hfov_rad",
    "load_tolerances",
    "measure_depth_accuracy",
    "parameter_table",
    "projection_difference",
    "recover_calibration",
    "right_joint_origin",
    "suggest_edits",
    "summary_lines",
    "validate",
    "write_validation_report",
]


def __getattr__(name: str) -> Any:
    """``write_validation_report`` on first use (PEP 562): it loads matplotlib (0.3-0.6 s of CPU), which a
    validation without ``--report`` never needs."""
    if name != "write_validation_report":
        raise AttributeError(f"module 's2r.validate' has no attribute {name!r}")
    value = importlib.import_module("s2r.validate.report").write_validation_report
    globals()[name] = value
    return value
