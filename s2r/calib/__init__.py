"""Chessboard calibration: inputs (folders, globs, ROS bags), parallel cached detection, mono and stereo
solves with outlier rejection and uncertainties, coverage figures and an HTML report.

``calibrate_stereo(left_paths, right_paths, pattern=(9, 6), square_m=0.025)`` returns a
:class:`StereoCalibration` whose ``profile`` is a real :class:`~s2r.profile.StereoProfile`.
"""

from s2r.calib.coverage import Coverage, PoseSpread
from s2r.calib.detect import CornerCache, Detection, detect_board
from s2r.calib.inputs import PairSet, find_mono_images, find_stereo_pairs
from s2r.calib.stereo import StereoCalibration, ViewError, calibrate_stereo
from s2r.calib.views import MIN_VIEWS, match_corner_order

__all__ = [
    "MIN_VIEWS",
    "CornerCache",
    "Coverage",
    "Detection",
    "PairSet",
    "PoseSpread",
    "StereoCalibration",
    "ViewError",
    "calibrate_stereo",
    "detect_board",
    "find_mono_images",
    "find_stereo_pairs",
    "match_corner_order",
]
