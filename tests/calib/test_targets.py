"""Target files (Kalibr aprilgrid / checkerboard, ChArUco): parsing, corner ids, object points, bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from s2r.errors import CalibrationError
from s2r.targets import AprilGridTarget, CharucoTarget, CheckerboardTarget, load_target

#: Kalibr's own example files (kalibr wiki "Calibration targets"), verbatim but for the values.
KALIBR_APRILGRID = """target_type: 'aprilgrid' #gridtype
tagCols: 6               #number of apriltags
tagRows: 6               #number of apriltags
tagSize: 0.088           #size of apriltag, edge to edge [m]
tagSpacing: 0.3          #ratio of space between tags to tagSize
"""
KALIBR_CHECKERBOARD = """target_type: 'checkerboard' #gridtype
targetCols: 6               #number of internal chessboard corners
targetRows: 7               #number of internal chessboard corners
rowSpacingMeters: 0.06      #size of one chessboard square [m]
colSpacingMeters: 0.05      #size of one chessboard square [m]
"""
CHARUCO = "target_type: charuco\nsquaresX: 5\nsquaresY: 7\nsquareLength: 0.04\nmarkerLength: 0.03\n" \
          "dictionary: DICT_4X4_50\n"


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "target.yaml"
    path.write_text(text)
    return path


def test_kalibr_aprilgrid_points_and_tag_corners(tmp_path: Path) -> None:
    t = load_target(_write(tmp_path, KALIBR_APRILGRID))
    assert isinstance(t, AprilGridTarget)
    pts = t.object_points()
    assert pts.shape == (144, 3)
    pitch = 0.088 * 1.3
    # Kalibr's grid: id r * 12 + c; tag 0's corners 0, 1, 13, 12 (BL, BR, TR, TL), y up
    np.testing.assert_allclose(pts[[0, 1, 13, 12]], [[0, 0, 0], [0.088, 0, 0], [0.088, 0.088, 0], [0, 0.088, 0]])
    np.testing.assert_allclose(pts[2], [pitch, 0, 0])
    np.testing.assert_allclose(pts[143], [5 * pitch + 0.088, 5 * pitch + 0.088, 0])
    assert t.tag_corner_ids(np.array([0, 7])).tolist() == [[0, 1, 13, 12], [26, 27, 39, 38]]


def test_kalibr_checkerboard_spacings(tmp_path: Path) -> None:
    t = load_target(_write(tmp_path, KALIBR_CHECKERBOARD))
    assert isinstance(t, CheckerboardTarget) and t.pattern == (6, 7)
    pts = t.object_points()
    np.testing.assert_allclose(pts[1], [0.05, 0, 0])
    np.testing.assert_allclose(pts[6], [0, 0.06, 0])


def test_charuco_points_match_opencv(tmp_path: Path) -> None:
    import cv2

    from s2r.calib.detect.markers import charuco_board

    t = load_target(_write(tmp_path, CHARUCO))
    assert isinstance(t, CharucoTarget)
    ours = t.object_points()
    theirs = np.asarray(charuco_board(t).getChessboardCorners(), np.float64)
    np.testing.assert_allclose(ours, theirs, atol=1e-9)
    assert getattr(cv2.aruco, t.dictionary) == cv2.aruco.DICT_4X4_50


@pytest.mark.parametrize(("text", "field"), [
    (KALIBR_APRILGRID.replace("tagSize: 0.088", "tagSize: -1"), "tagSize"),
    (KALIBR_APRILGRID.replace("tagCols: 6", "tagCol: 6"), "tagCol"),
    (KALIBR_APRILGRID.replace("'aprilgrid'", "'apriltag'"), "target_type"),
    (KALIBR_CHECKERBOARD.replace("rowSpacingMeters: 0.06", ""), "rowSpacingMeters"),
    (CHARUCO.replace("DICT_4X4_50", "DICT_9X9_1"), "dictionary"),
    (CHARUCO.replace("markerLength: 0.03", "markerLength: 0.05"), "markerLength"),
    (CHARUCO.replace("squaresX: 5", "squaresX: 50"), "dictionary"),
    ("- a list\n", "mapping"),
    ("tagCols: [\n", "malformed"),
    ("squaresX: 5\n", "target_type"),
])
def test_bad_target_files_name_the_field(tmp_path: Path, text: str, field: str) -> None:
    with pytest.raises(CalibrationError) as err:
        load_target(_write(tmp_path, text))
    msg = str(err.value)
    assert field in msg and "target.yaml" in msg and "\n" not in msg


def test_missing_target_file(tmp_path: Path) -> None:
    with pytest.raises(CalibrationError, match="file not found"):
        load_target(tmp_path / "nope.yaml")
