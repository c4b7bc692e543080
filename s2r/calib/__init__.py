"""Chessboard calibration: inputs (folders, globs, ROS bags), parallel cached detection, mono and stereo
solves with outlier rejection and uncertainties, coverage figures and an HTML report
(:func:`s2r.calib.report.write_calibration_report`, kept out of this namespace because it loads matplotlib).

``calibrate_stereo(left_paths, right_paths, pattern=(9, 6), square_m=0.025)`` returns a
:class:`StereoCalibration` whose ``profile`` is a real :class:`~s2r.profile.StereoProfile`.

The names below load their module on first use (PEP 562): importing one stage (``s2r.calib.detect``) does not
load the solver, so ``s2r calibrate`` can start detecting while the solver's modules load.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from s2r.lazy import lazy_names

if TYPE_CHECKING:
    from s2r.calib.detect import CornerCache, Detection, detect_board
    from s2r.calib.detect.coverage import Coverage, PoseSpread
    from s2r.calib.detect.inputs import PairSet, find_mono_images, find_stereo_pairs
    from s2r.calib.solve.pipelines.mono import MonoCalibration, calibrate_mono
    from s2r.calib.solve.pipelines.stereo import StereoCalibration, ViewError, calibrate_stereo
    from s2r.calib.solve.pipelines.stereo_bag import calibrate_stereo_bag
    from s2r.calib.solve.views import MAX_SOLVE_VIEWS, MIN_VIEWS, match_corner_order

#: Public name -> the module that defines it.
_HOMES = {
    "CornerCache": "s2r.calib.detect", "Detection": "s2r.calib.detect", "detect_board": "s2r.calib.detect",
    "Coverage": "s2r.calib.detect.coverage", "PoseSpread": "s2r.calib.detect.coverage",
    "PairSet": "s2r.calib.detect.inputs", "find_mono_images": "s2r.calib.detect.inputs",
    "find_stereo_pairs": "s2r.calib.detect.inputs",
    "MonoCalibration": "s2r.calib.solve.pipelines.mono", "calibrate_mono": "s2r.calib.solve.pipelines.mono",
    "StereoCalibration": "s2r.calib.solve.pipelines.stereo", "ViewError": "s2r.calib.solve.pipelines.stereo",
    "calibrate_stereo": "s2r.calib.solve.pipelines.stereo",
    "calibrate_stereo_bag": "s2r.calib.solve.pipelines.stereo_bag",
    "MAX_SOLVE_VIEWS": "s2r.calib.solve.views", "MIN_VIEWS": "s2r.calib.solve.views",
    "match_corner_order": "s2r.calib.solve.views",
}

__all__ = ["MAX_SOLVE_VIEWS", "MIN_VIEWS", "CornerCache", "Coverage", "Detection", "MonoCalibration", "PairSet",
           "PoseSpread", "StereoCalibration", "ViewError", "calibrate_mono", "calibrate_stereo", "calibrate_stereo_bag",
           "detect_board", "find_mono_images", "find_stereo_pairs", "match_corner_order"]

__getattr__, __dir__ = lazy_names(__name__, _HOMES, globals())
