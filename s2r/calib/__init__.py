"""Chessboard calibration: inputs (folders, globs, ROS bags), parallel cached detection, mono and stereo
solves with outlier rejection and uncertainties, coverage figures and an HTML report
(:func:`s2r.calib.report.write_calibration_report`, kept out of this namespace because it loads matplotlib).

``calibrate_stereo(left_paths, right_paths, pattern=(9, 6), square_m=0.025)`` returns a
:class:`StereoCalibration` whose ``profile`` is a real :class:`~s2r.profile.StereoProfile`.
"""

from s2r.calib.detect import CornerCache, Detection, detect_board
from s2r.calib.detect.coverage import Coverage, PoseSpread
from s2r.calib.detect.inputs import PairSet, find_mono_images, find_stereo_pairs
from s2r.calib.solve.mono import MonoCalibration, calibrate_mono
from s2r.calib.solve.stereo import StereoCalibration, ViewError, calibrate_stereo
from s2r.calib.solve.stereo_bag import calibrate_stereo_bag
from s2r.calib.solve.views import MAX_SOLVE_VIEWS, MIN_VIEWS, match_corner_order

__all__ = [
    "MAX_SOLVE_VIEWS",
    "MIN_VIEWS",
    "CornerCache",
    "Coverage",
    "Detection",
    "MonoCalibration",
    "PairSet",
    "PoseSpread",
    "StereoCalibration",
    "ViewError",
    "calibrate_mono",
    "calibrate_stereo",
    "calibrate_stereo_bag",
    "detect_board",
    "find_mono_images",
    "find_stereo_pairs",
    "match_corner_order",
]
