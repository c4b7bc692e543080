"""Detection stage: input folders and bags, chessboard and target corner detectors, the parallel cached
detection stream and the image coverage of the corners found. Imports nothing of :mod:`s2r.calib.solve` or
:mod:`s2r.calib.report`.
"""

from s2r.calib.detect.chessboard import detect_board
from s2r.calib.detect.stream import CornerCache, Detection, DetectItem, detect_stream

__all__ = ["CornerCache", "DetectItem", "Detection", "detect_board", "detect_stream"]
